"""Frame lockstep (mav_sim's ``lockstep``): the simulator stops sim time before each new
frame until every node named in ``lockstep_nodes`` has reported the previous frame on
``frame_integrated``, and before frame 0 until every subscriber of its frame topics is
connected (see the start-up and lockstep paragraphs of node.py's docstring).

This module holds only that bookkeeping: the reports received, the master queries for
nodes and connections, and the waits (all in wall time, with the timeouts of SimConfig).
"""
import threading
import time
from typing import Callable, Dict, List

import rosgraph
import rospy

from semantic_exploration.msg import FrameIntegrated

NS = 1_000_000_000


def short_name(n: str) -> str:
    """A node's name without its namespace ("/ns/object_map/" -> "object_map")."""
    return n.rstrip("/").rsplit("/", 1)[-1]


class FrameLockstep:
    """Waits for lockstep nodes' frame reports and for frame subscribers to connect.

    depth_pub: the depth image publisher (a lockstep node must be connected to it to be waited for);
    frame_publishers: returns every publisher whose subscribers frame 0 waits for;
    strict: wait at start-up for every lockstep node, also one the master does not know yet
    (lockstep_planner: deterministic runs).
    """

    def __init__(self, nodes: List[str], timeout_s: float, startup_timeout_s: float, depth_pub,
                 frame_publishers: Callable[[], list], strict: bool):
        self.nodes = [short_name(n) for n in nodes]
        self.timeout_s, self.startup_timeout_s = timeout_s, startup_timeout_s
        self._depth_pub, self._frame_publishers, self._strict = depth_pub, frame_publishers, strict
        self._cv = threading.Condition()
        self._reported: Dict[str, int] = {}  # short node name -> newest frame stamp reported, ns
        self.timeouts = 0
        # lockstep nodes that exist but had no depth connection when the last frame went out: they
        # cannot report that frame (e.g. still connecting at start-up), so it does not wait for them
        self._absent = (None, set())  # (frame stamp ns, names)
        self._node_names = (0.0, set())  # (wall time of the query, short names of the master's nodes)

    def on_integrated(self, msg: FrameIntegrated) -> None:
        name = short_name(msg.node)
        with self._cv:
            self._reported[name] = max(self._reported.get(name, 0), msg.header.stamp.to_nsec())
            self._cv.notify_all()

    def wait_frame(self, frame_ns: int) -> None:
        """Blocks (wall time) until every lockstep node has reported frame_ns."""
        deadline = time.monotonic() + self.timeout_s
        with self._cv:
            while not rospy.is_shutdown():
                missing = [n for n in self.nodes if self._reported.get(n, -1) < frame_ns
                           and not (frame_ns == self._absent[0] and n in self._absent[1])]
                if not missing:
                    return
                left = deadline - time.monotonic()
                if left <= 0:
                    self.timeouts += 1
                    if self.timeouts <= 3 or self.timeouts % 20 == 0:  # keep the log readable
                        rospy.logwarn("mav_sim: lockstep: no frame_integrated from %s for frame %.3f s after %.1f s; "
                                      "continuing (%d timeouts so far)", ", ".join(missing), frame_ns / NS,
                                      self.timeout_s, self.timeouts)
                    return
                self._cv.wait(min(left, 0.1))

    def _unconnected_subscribers(self):
        """(topic, subscriber node) pairs the master lists for the frame topics that
        have no connection to this node yet (a subscriber still connecting)."""
        try:
            _, subs, _ = rosgraph.Master(rospy.get_name()).getSystemState()
        except Exception:  # master busy: judge by the connections alone
            return []
        subs = dict(subs)
        me = rospy.get_name()
        out = []
        for pub in self._frame_publishers():
            for node in subs.get(pub.resolved_name, []):
                if node != me and not pub.impl.has_connection(node):
                    out.append((pub.resolved_name, node))
        return out

    def wait_for_subscribers(self) -> None:
        """Before the first frame: waits (wall time) until the depth topic has a
        subscriber, every lockstep node that exists subscribes to it, and every
        subscriber of the frame topics is connected; at most startup_timeout_s."""
        deadline = time.monotonic() + self.startup_timeout_s
        stable_since = None
        while not rospy.is_shutdown():
            waiting = []
            if self._depth_pub.get_num_connections() == 0:
                waiting.append("a subscriber of %s" % self._depth_pub.resolved_name)
            waiting += ["%s on %s" % (n, t) for t, n in self._unconnected_subscribers()]
            waiting += ["lockstep node %s" % n for n in self.nodes if (self._strict or self._node_exists(n))
                        and not self._depth_connected(n)]
            now = time.monotonic()
            if not waiting:
                stable_since = stable_since or now
                if now - stable_since >= 0.3:  # nodes that start together register within a moment
                    return
            else:
                stable_since = None
            if now > deadline:
                rospy.logwarn("mav_sim: lockstep: still waiting for %s after %.0f s; starting anyway",
                              ", ".join(waiting), self.startup_timeout_s)
                return
            time.sleep(0.05)

    def _node_exists(self, short: str, max_age_s: float = 0.0) -> bool:
        """Whether the master knows a node of this short name (asks it again after max_age_s wall s)."""
        when, names = self._node_names
        if time.monotonic() - when > max_age_s:
            try:
                pubs, subs, srvs = rosgraph.Master(rospy.get_name()).getSystemState()
                names = {short_name(n) for g in (pubs, subs, srvs) for _, nodes in g for n in nodes}
                self._node_names = (time.monotonic(), names)
            except Exception:
                pass
        return short in names

    def note_absent(self, t_ns: int) -> None:
        """Records the lockstep nodes that exist but cannot receive the frame at t_ns."""
        absent = {n for n in self.nodes if not self._depth_connected(n) and self._node_exists(n, 1.0)}
        if absent != self._absent[1]:
            if absent:
                rospy.logwarn("mav_sim: lockstep: %s not connected to %s at frame %.3f s; not waiting for it "
                              "until it is", ", ".join(sorted(absent)), self._depth_pub.resolved_name, t_ns / NS)
            else:
                rospy.loginfo("mav_sim: lockstep: every lockstep node is connected (frame %.3f s)", t_ns / NS)
        self._absent = (t_ns, absent)

    def _depth_connected(self, short: str) -> bool:
        return any(short_name(c.endpoint_id) == short for c in list(self._depth_pub.impl.connections))

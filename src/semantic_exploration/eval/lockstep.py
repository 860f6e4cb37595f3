"""Deterministic time series (run_mission.py --deterministic).

mav_sim runs in lockstep with the planner (lockstep_planner) and with the
mission itself as one of its lockstep nodes: it renders frame k+1 only once
background_map, object_map, depth_history and the mission have reported
frame k. The mission reports a frame after it has written the rows that fall
at or before it and taken the snapshots due there, so every figure it
records is the state after a known frame, not after however many frames the
machine managed meanwhile.

- FrameBarrier: the mission's side of the lockstep (frame_integrated).
- StampedLog: the RunLog's messages held back and fed in stamp order up to a
  sim time once every message up to it has arrived (a frame all nodes have
  reported), so a row at sim time T holds exactly the messages stamped <= T.

Messages without a stamp (mav/collisions) are stamped with the mission's sim
clock when they arrive: the one figure that may still differ between runs by
a row (a collision at most 0.1 s of sim time before a row).
"""
import os
import threading
from typing import Dict, List, Optional

from .runlog import TOPICS, RunLog

NS = 1_000_000_000

#: what FrameBarrier waits for before a frame counts as done (the sim's other lockstep nodes)
MAP_NODES = ["background_map", "object_map", "depth_history"]
#: topics with a message stamped with every frame (the body pose at the frame's stamp; map statistics; the
#: objects, with object_map/publish_period_s 0), waited for before the frame's rows are written
PER_FRAME_TOPICS = ["/mav/pose", "/background_map/stats", "/object_map/objects"]


def _stamp_ns(msg) -> Optional[int]:
    h = getattr(msg, "header", None)
    if h is None or (h.stamp.secs == 0 and h.stamp.nsecs == 0):
        return None
    return h.stamp.secs * NS + h.stamp.nsecs


class StampedLog:
    """Feeds a RunLog in stamp order up to a given sim time (advance); put() is thread-safe."""

    def __init__(self, log: RunLog, clock_ns=None):
        self.log = log
        self._clock_ns = clock_ns  # sim time now, ns, for messages without a stamp
        self._pending: List = []
        self._seq = 0
        self._latest: Dict[str, int] = {}  # topic -> newest stamp received, ns
        self._lock = threading.Condition()

    def put(self, topic: str, msg) -> None:
        t = _stamp_ns(msg)
        if t is None:
            t = self._clock_ns() if self._clock_ns else 0
        with self._lock:
            self._seq += 1
            self._pending.append((t, self._seq, topic, msg))
            self._latest[topic] = max(self._latest.get(topic, t), t)
            self._lock.notify_all()

    def wait_for(self, topics: List[str], t_ns: int, timeout_s: float) -> List[str]:
        """Waits (wall time, at most timeout_s) until each topic has a message stamped >= t_ns;
        returns the topics still without one. A node's messages of a frame go out before its
        frame_integrated, but on other connections, each read by its own thread here: they
        may come in after it."""
        with self._lock:
            self._lock.wait_for(lambda: all(self._latest.get(k, -1) >= t_ns for k in topics), timeout_s)
            return [k for k in topics if self._latest.get(k, -1) < t_ns]

    def advance(self, t_ns: int) -> None:
        """Feeds every message stamped <= t_ns, in stamp order (arrival order within a stamp)."""
        with self._lock:
            due = sorted(m for m in self._pending if m[0] <= t_ns)
            self._pending = [m for m in self._pending if m[0] > t_ns]
        for _, _, topic, msg in due:
            self.log.handle(topic, msg)

    def subscribe(self) -> "StampedLog":
        """Live: the topics of RunLog.TOPICS into put() (needs rospy.init_node). No queue
        limit on mav/pose: a dropped pose would change the path length."""
        import rospy
        from geometry_msgs.msg import PoseStamped
        from std_msgs.msg import UInt32
        from semantic_exploration.msg import DropCounts, ExplorationStatus, FrameIntegrated, MapStats, ObjectArray
        types = {"/planner/status": ExplorationStatus, "/background_map/stats": MapStats,
                 "/object_map/objects": ObjectArray, "/mav/collisions": UInt32, "/mav/pose": PoseStamped,
                 "/dropped_input": DropCounts, "/mav_sim/faults": DropCounts, "/frame_integrated": FrameIntegrated}
        if self._clock_ns is None:
            self._clock_ns = lambda: rospy.get_rostime().to_nsec()
        for topic in TOPICS:
            rospy.Subscriber(topic, types[topic], lambda msg, t=topic: self.put(t, msg), queue_size=None)
        return self


class FrameBarrier:
    """The mission as mav_sim's lockstep node "mission": next_frame() gives the newest
    frame every map node has reported; ack() reports it, letting the simulator go on."""

    def __init__(self, nodes: List[str] = MAP_NODES, name: str = "mission"):
        import rospy
        from semantic_exploration.msg import FrameIntegrated
        self.nodes, self.name = list(nodes), name
        self._reported: Dict[str, int] = {}
        self._acked = -1
        self._cv = threading.Condition()
        self._msg = FrameIntegrated
        self._pub = rospy.Publisher("/frame_integrated", FrameIntegrated, queue_size=10)
        rospy.Subscriber("/frame_integrated", FrameIntegrated, self._on_integrated, queue_size=100)
        # mav_sim counts a lockstep node as present once it receives the depth images.
        rospy.Subscriber("/camera/depth/image_raw", rospy.AnyMsg, lambda _: None, queue_size=1)

    def _on_integrated(self, msg) -> None:
        name = msg.node.rstrip("/").rsplit("/", 1)[-1]
        with self._cv:
            self._reported[name] = max(self._reported.get(name, -1), msg.header.stamp.to_nsec())
            self._cv.notify_all()

    def _done(self) -> int:
        return min(self._reported.get(n, -1) for n in self.nodes)

    def next_frame(self, timeout_s: float) -> Optional[int]:
        """Stamp (ns) of the newest frame all map nodes have reported and this one has not
        acknowledged; None after timeout_s of wall time without one."""
        with self._cv:
            self._cv.wait_for(lambda: self._done() > self._acked, timeout_s)
            t = self._done()
            return t if t > self._acked else None

    def ack(self, t_ns: int) -> None:
        import rospy
        m = self._msg()
        m.header.stamp = rospy.Time(t_ns // NS, t_ns % NS)
        m.node = self.name
        m.integrated = True
        self._acked = t_ns
        self._pub.publish(m)


class RowClock:
    """Which rows (sim s, on the period's grid) fall at or before a frame; each once."""

    def __init__(self, period_s: float):
        self.period_s = period_s
        self.k = 0

    def rows_until(self, t_ns: int) -> List[float]:
        out = []
        while int(round(self.k * self.period_s * NS)) <= t_ns:
            out.append(round(self.k * self.period_s, 6))
            self.k += 1
        return out


def deterministic_setup(args, out: str, overrides: str, config_dir: str) -> None:
    """--deterministic: config/deterministic.yaml after the C++ nodes' overrides, and the
    simulator's overrides (args.sim_overrides, if any) with config/deterministic_sim.yaml
    on top in out/sim_overrides.yaml, which args.sim_overrides then names."""
    from .overrides import load, merge, write, write_merged
    write_merged(overrides, [load(os.path.join(config_dir, "deterministic.yaml"))],
                 "written by run_mission.py: the scene's bounds and classes, its planner settings, "
                 "--extra-overrides, config/deterministic.yaml")
    merged = {}
    for path in ([args.sim_overrides] if args.sim_overrides else []) + [os.path.join(config_dir,
                                                                                         "deterministic_sim.yaml")]:
        merge(merged, load(path))
    args.user_sim_overrides = args.sim_overrides
    args.sim_overrides = os.path.join(out, "sim_overrides.yaml")
    write(args.sim_overrides, merged)


def timing_of(deterministic, get_param):
    """How the run's planner was timed, for the report (get_param(name, default) reads a ROS parameter)."""
    if get_param("/planner/planner/ompl_termination", "time") == "iterations":
        how = "OMPL stops after %s iterations per candidate" % get_param("/planner/planner/ompl_iterations", "?")
    else:
        how = "OMPL wall-time budget of %s s per candidate" % get_param("/planner/planner/time_budget_s", "?")
    return how + ("; deterministic (lockstep planner and mission)" if deterministic else
                  "; paths depend on the machine's speed, two runs differ")


def run_lockstep(barrier: FrameBarrier, stamped: StampedLog, rows: RowClock, write_row, snapshots, limits,
                 progress=None, frame_timeout_s: float = 5.0, per_frame_timeout_s: float = 1.0):
    """The mission's loop in deterministic mode, one pass per frame every map node has
    reported: rows up to the frame (each fed only the messages stamped <= its time), the
    snapshots due at the frame (`snapshots(t_s)`), then the stop checks (`limits(t_s)`:
    a reason to stop, or ''), then the acknowledgement that lets mav_sim go on.
    The frame the run stops at is not acknowledged: mav_sim waits (up to its
    lockstep_timeout_s) while the maps are saved, so they hold the state after it.
    `write_row(t_s)` writes one row; `limits(None)` is asked while no frame comes.
    Returns (reason, sim time of the last frame, s)."""
    t_s = 0.0
    while True:
        t_ns = barrier.next_frame(frame_timeout_s)
        if t_ns is None:
            why = limits(None)
            if why:
                return why, t_s
            continue
        t_s = t_ns / NS
        # A frame a node dropped may lack its message: wait a moment, then go on.
        stamped.wait_for(PER_FRAME_TOPICS, t_ns, per_frame_timeout_s)
        for row_s in rows.rows_until(t_ns):
            stamped.advance(int(round(row_s * NS)))
            write_row(row_s)
        stamped.advance(t_ns)
        snapshots(t_s)
        if progress is not None:
            progress(t_s)
        why = limits(t_s)
        if why:
            return why, t_s
        barrier.ack(t_ns)

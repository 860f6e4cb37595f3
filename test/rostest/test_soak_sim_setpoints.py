#!/usr/bin/env python3
"""rostest (soak_sim_setpoints.test): the randomised-input soak of mav_sim's
setpoint input, setpoint_position/local (follow:=setpoints), which
soak_sim_detector.test (mav_sim following paths) leaves out.

~messages setpoints from seed ~seed, in one stream: valid ones (some in
"/world" or "", with non-unit quaternions down to 1e-5 and up to 1e200, or
with stamps at 0 or going back up to 100 s), and ones in another frame, with
NaN/inf, with a zero quaternion, out of the accepted region (just outside,
or 1e30), raw bytes too short to be a PoseStamped or claiming a 2^31-byte
frame_id, and PoseStamped filled field by field at random
(soak_messages.fill); some with two defects. The test names the reason of
each refused one itself, by the rules of setpoints.py (the first of frame,
values, quaternion, bounds that applies), waits for each to be counted, and
checks at the end that mav_sim's counts on /dropped_input equal its own per
reason (so refused + accepted = sent, and no accepted one is counted).

Afterwards mav_sim is the process it was, still publishes camera frames,
counts a ping (a setpoint in another frame), flies to a valid setpoint
streamed at 20 Hz, and its peak RSS (VmHWM) is under ~sim_max_rss_mb.
One line per category to the log; docs/BENCHMARKS.md quotes them."""
import math
import os
import random
import struct
import sys
import threading
import time
import unittest

import genpy
import rospy
from geometry_msgs.msg import PoseStamped

from semantic_exploration.msg import DropCounts

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import soak_messages as sm  # noqa: E402
from test_soak import node_pid, raw_message_type, rss_mb, serialised, wait_for  # noqa: E402

FRAMES_OTHER = ("map", "camera", "body", "odom", "world2", "World", " world", "world/")


RawPoseStamped = raw_message_type(PoseStamped)  # mav_sim reads this topic raw


def expected_reason(m, lo, hi):
    """Why mav_sim must refuse PoseStamped m (None: it takes it), by the order of setpoints.py."""
    frame = m.header.frame_id.lstrip("/")
    if frame not in ("", "world"):
        return "setpoint_wrong_frame"
    p, q = m.pose.position, m.pose.orientation
    pos, quat = (p.x, p.y, p.z), (q.x, q.y, q.z, q.w)
    if not all(math.isfinite(v) for v in pos + quat):
        return "setpoint_not_finite"
    if math.hypot(*quat) < 1e-6:
        return "setpoint_zero_quaternion"
    if any(v < a or v > b for v, a, b in zip(pos, lo, hi)):
        return "setpoint_out_of_bounds"
    return None


class SoakSimSetpoints(unittest.TestCase):
    def setUp(self):
        self.rng = random.Random(rospy.get_param("~seed", 15))
        self.n_msgs = rospy.get_param("~messages", 300)
        self.lo = rospy.get_param("/mav_sim/bounds_min_m")
        self.hi = rospy.get_param("/mav_sim/bounds_max_m")
        self.lock = threading.Lock()
        self.drops, self.depth_frames, self.pose = {}, 0, None
        rospy.Subscriber("/dropped_input", DropCounts, self._on_drops, queue_size=1000)
        rospy.Subscriber("/camera/depth/image_raw", rospy.AnyMsg, self._on_depth, queue_size=10)
        rospy.Subscriber("/mav/pose", PoseStamped, self._on_pose, queue_size=10)
        self._wait_for(lambda: node_pid("mav_sim") is not None, 60.0, "/mav_sim to start")
        self.pid = node_pid("mav_sim")
        self.rss0 = rss_mb(self.pid)[0]
        self.t_s = 0.0

    # ------------------------------------------------------------ bookkeeping
    def _on_drops(self, m):
        if m.node.lstrip("/") == "mav_sim":
            with self.lock:
                self.drops = dict(zip(m.reasons, m.counts))

    def _on_depth(self, _):
        with self.lock:
            self.depth_frames += 1

    def _on_pose(self, m):
        with self.lock:
            self.pose = (m.pose.position.x, m.pose.position.y, m.pose.position.z)

    def _get(self, attr):
        with self.lock:
            return getattr(self, attr)

    def _count(self, reason=None):
        with self.lock:
            return self.drops.get(reason, 0) if reason else sum(self.drops.values())

    _wait_for = wait_for

    def _log(self, line):
        rospy.loginfo("soak: " + line)
        print("soak: " + line)

    # ------------------------------------------------------------ the messages
    def _valid(self):
        m = PoseStamped()
        self.t_s += 0.05
        m.header.stamp = genpy.Time.from_sec(self.t_s)
        m.header.frame_id = self.rng.choice(["world", "world", "/world", ""])
        p = m.pose.position
        p.x, p.y, p.z = (self.rng.uniform(a, b) for a, b in zip(self.lo, self.hi))
        yaw = self.rng.uniform(-math.pi, math.pi)
        m.pose.orientation.z, m.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        return m

    def _defect(self, m, kind):
        """Applies one defect of `kind` to PoseStamped m."""
        p, q = m.pose.position, m.pose.orientation
        if kind == "frame":
            m.header.frame_id = self.rng.choice(FRAMES_OTHER)
        elif kind == "non_finite":
            obj, field = self.rng.choice([(p, "x"), (p, "y"), (p, "z"), (q, "x"), (q, "y"), (q, "z"), (q, "w")])
            setattr(obj, field, self.rng.choice([float("nan"), float("inf"), -float("inf")]))
        elif kind == "zero_quaternion":
            s = self.rng.choice([0.0, 0.0, 5e-324, 1e-7])
            q.x, q.y, q.z, q.w = (s * self.rng.choice([0, 1, -1]) for _ in range(4))
        elif kind == "out_of_bounds":
            axis = self.rng.choice("xyz")
            k = "xyz".index(axis)
            setattr(p, axis, self.rng.choice([self.lo[k] - 0.01, self.hi[k] + 0.5, 1e30, -1e30, 1e300]))
        elif kind == "non_unit":  # taken: normalised
            s = self.rng.choice([1e-5, 0.5, 3.0, 1e200])
            q.x, q.y, q.z, q.w = q.x * s, q.y * s, q.z * s, q.w * s
        elif kind == "stamp_back":  # taken: flown without feed-forward velocity
            m.header.stamp = self.rng.choice([genpy.Time(0, 0),
                                              genpy.Time.from_sec(max(0.0, self.t_s - self.rng.uniform(0, 100)))])
        return m

    def _message(self):
        """(raw bytes, reason mav_sim must count or None, category for the log)."""
        r = self.rng.random()
        if r < 0.08:
            if self.rng.random() < 0.6:  # shorter than any PoseStamped (72 bytes with an empty frame_id)
                return bytes(self.rng.getrandbits(8) for _ in range(self.rng.randint(0, 71))), \
                    "setpoint_unreadable", "raw bytes"
            return struct.pack("<IIII", 0, 0, 0, 2 ** 31) + bytes(64), "setpoint_unreadable", "raw bytes"
        if r < 0.16:
            m = sm.fill(self.rng, PoseStamped())
            return serialised(m), expected_reason(m, self.lo, self.hi), "random fields"
        kinds = ["valid"] * 6 + ["non_unit", "stamp_back", "frame", "non_finite", "zero_quaternion",
                                 "out_of_bounds", "out_of_bounds"]
        kind = self.rng.choice(kinds)
        m = self._defect(self._valid(), kind)
        if kind != "valid" and self.rng.random() < 0.3:  # a second defect
            m = self._defect(m, self.rng.choice(kinds[6:]))
        return serialised(m), expected_reason(m, self.lo, self.hi), kind

    # ------------------------------------------------------------ the soak
    def test_soak(self):
        t0 = time.time()
        pub = rospy.Publisher("/setpoint_position/local", RawPoseStamped, queue_size=1000)
        self._wait_for(lambda: pub.get_num_connections() > 0, 20.0, "mav_sim to subscribe to setpoints")
        self._wait_for(lambda: self._get("depth_frames") >= 3, 30.0, "frames from mav_sim")
        self._wait_for(lambda: self._get("pose") is not None, 10.0, "mav/pose")
        time.sleep(0.2)
        self.t_s = rospy.Time.now().to_sec()
        expected, per_kind = {}, {}
        frames0, counted0 = self._get("depth_frames"), self._count()
        for i in range(self.n_msgs):
            buff, reason, kind = self._message()
            sent, refused = per_kind.get(kind, (0, 0))
            per_kind[kind] = (sent + 1, refused + (reason is not None))
            before = self._count(reason)
            pub.publish(RawPoseStamped(buff))
            if reason is None:
                time.sleep(0.01)  # no answer to wait for; a counted one later shows this one was handled
                continue
            expected[reason] = expected.get(reason, 0) + 1
            self._wait_for(lambda: self._count(reason) > before, 5.0,
                           "mav_sim to count setpoint %d (%s) as %s" % (i, kind, reason))
        refused = sum(expected.values())
        self._wait_for(lambda: self._count() - counted0 >= refused, 5.0)
        time.sleep(0.5)  # anything counted late would show now
        with self.lock:
            counts = dict(self.drops)
        for kind, (sent, n_refused) in sorted(per_kind.items()):
            self._log("setpoint_position/local -> mav_sim, %s: %d sent, %d refused" % (kind, sent, n_refused))
        self._log("setpoint_position/local -> mav_sim: %d sent, %d accepted, %d refused; expected %s, counted %s"
                  % (self.n_msgs, self.n_msgs - refused, refused, sorted(expected.items()), sorted(counts.items())))
        self.assertEqual(counts, expected, "mav_sim's drop counts per reason")
        for reason in ("setpoint_unreadable", "setpoint_wrong_frame", "setpoint_not_finite",
                       "setpoint_zero_quaternion", "setpoint_out_of_bounds"):
            self.assertGreater(counts.get(reason, 0), 0, "the soak sent no setpoint refused as " + reason)
        self.assertGreater(self.n_msgs - refused, 0)
        # Alive and answering: the same process, frames still coming, a ping counted.
        self.assertEqual(node_pid("mav_sim"), self.pid, "/mav_sim was restarted or died")
        self._wait_for(lambda: self._get("depth_frames") >= frames0 + 10, 20.0, "frames from mav_sim after the soak")
        before = self._count("setpoint_wrong_frame")
        ping = self._valid()
        ping.header.frame_id = "map"
        pub.publish(RawPoseStamped(serialised(ping)))
        self._wait_for(lambda: self._count("setpoint_wrong_frame") > before, 5.0, "mav_sim to count the ping")
        # It still flies: a valid setpoint streamed at 20 Hz is reached.
        target = (4.0, 3.0, 1.2)
        start = self._get("pose")
        dist = lambda: math.dist(self._get("pose"), target)  # noqa: E731
        t_fly = time.time()
        while dist() > 0.05 and time.time() < t_fly + 40.0:
            m = PoseStamped()
            m.header.stamp, m.header.frame_id = rospy.Time.now(), "world"
            m.pose.position.x, m.pose.position.y, m.pose.position.z = target
            m.pose.orientation.w = 1.0
            pub.publish(RawPoseStamped(serialised(m)))
            time.sleep(0.05)
        fly_s, frames = time.time() - t_fly, self._get("depth_frames") - frames0
        self._log("mav_sim flew from (%.2f, %.2f, %.2f) to within %.3f m of the setpoint (%.1f, %.1f, %.1f) "
                  "in %.1f s; %d depth frames since the soak began" % (start + (dist(),) + target + (fly_s, frames)))
        self.assertLess(dist(), 0.05, "mav_sim did not reach a valid setpoint after the soak")
        rss, peak = rss_mb(self.pid)
        bound = rospy.get_param("~sim_max_rss_mb", 500.0)
        self._log("mav_sim: RSS %.0f MB at the start, %.0f MB at the end, peak %.0f MB (bound %.0f MB)"
                  % (self.rss0, rss, peak, bound))
        self.assertLess(peak, bound, "/mav_sim peak RSS")
        self._log("total %.0f s wall" % (time.time() - t0))


if __name__ == "__main__":
    import rostest
    rospy.init_node("soak_sim_setpoints")
    rostest.rosrun("semantic_exploration", "soak_sim_setpoints", SoakSimSetpoints)
#!/usr/bin/env python3
"""rostest for mav_sim (see sim.test). Acts as the only lockstep node ("sim_test")."""
import math
import threading
import time
import unittest

import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import String, UInt32

from semantic_exploration.msg import Detections, FrameIntegrated

PKG = "semantic_exploration"
WALL_TIMEOUT = 30.0


def wait_for(cond, timeout=WALL_TIMEOUT):
    end = time.monotonic() + timeout
    while time.monotonic() < end and not rospy.is_shutdown():
        if cond():
            return True
        time.sleep(0.02)
    return cond()


class SimTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("sim_test")
        cls.lock = threading.Lock()
        cls.auto_report = True
        cls.msgs = {k: [] for k in ("depth", "rgb", "info", "inst", "cls", "det", "pose", "goal", "coll", "rej")}
        cls.clock = []
        cls.buffer = tf2_ros.Buffer(rospy.Duration(60.0))
        cls.listener = tf2_ros.TransformListener(cls.buffer)
        cls.report_pub = rospy.Publisher("/frame_integrated", FrameIntegrated, queue_size=10)
        cls.path_pub = rospy.Publisher("/planner/path", Path, queue_size=10)
        cls.scene_pub = rospy.Publisher("/mav_sim/load_scene", String, queue_size=1)

        # Like a real lockstep node, the test reports a frame once all of its
        # streams have arrived, so the simulator never runs ahead of a stream
        # still in transit (its image publishers keep only a few frames). A
        # frame missing a stream (subscriptions still connecting at start-up)
        # is reported after 2 s, as the newest depth frame.
        frame_keys = {"depth", "rgb", "info", "inst", "cls", "det"}
        arrived = {}
        cls.newest_depth = None  # (stamp, wall time it arrived)

        def keep(key):
            def cb(m):
                with cls.lock:
                    cls.msgs[key].append(m)
                    if key not in frame_keys:
                        return
                    if key == "depth":
                        cls.newest_depth = (m.header.stamp, time.monotonic())
                    stamp = m.header.stamp.to_nsec()
                    got = arrived.setdefault(stamp, set())
                    got.add(key)
                    complete = got == frame_keys
                    if complete:
                        del arrived[stamp]
                if complete and cls.auto_report:
                    cls.report(m.header.stamp)
            return cb

        def report_stragglers():
            while not rospy.is_shutdown():
                time.sleep(0.5)
                with cls.lock:
                    newest = cls.newest_depth
                    late = newest is not None and newest[0].to_nsec() in arrived and time.monotonic() - newest[1] > 2.0
                    if late:
                        del arrived[newest[0].to_nsec()]
                if late and cls.auto_report:
                    cls.report(newest[0])
        threading.Thread(target=report_stragglers, daemon=True).start()

        rospy.Subscriber("/camera/depth/image_raw", Image, keep("depth"), queue_size=50)
        for key, topic, typ in (("rgb", "/camera/rgb/image_raw", Image), ("info", "/camera/camera_info", CameraInfo),
                                ("inst", "/camera/instance_gt", Image), ("cls", "/camera/class_gt", Image),
                                ("det", "/detections", Detections), ("pose", "/mav/pose", PoseStamped),
                                ("goal", "/mav/goal_reached", PoseStamped), ("coll", "/mav/collisions", UInt32),
                                ("rej", "/mav/path_rejected", String)):
            rospy.Subscriber(topic, typ, keep(key), queue_size=200)
        rospy.Subscriber("/clock", Clock, lambda m: cls.clock.append(m.clock.to_nsec()), queue_size=1000)
        assert wait_for(lambda: len(cls.msgs["depth"]) >= 5, 90.0), "no frames from mav_sim"
        # Every subscription is connected before the tests look at the streams.
        keys = ("rgb", "info", "inst", "cls", "det", "pose", "coll")
        assert wait_for(lambda: all(cls.msgs[k] for k in keys) and cls.clock, 30.0), \
            "missing topics: %s" % ([k for k in keys if not cls.msgs[k]] + ([] if cls.clock else ["clock"]))

    @classmethod
    def report(cls, stamp):
        m = FrameIntegrated(node="sim_test", integrated=True, time_ms=1.0)
        m.header.stamp = stamp
        cls.report_pub.publish(m)

    def frames(self, key="depth"):
        with self.lock:
            return list(self.msgs[key])

    def by_stamp(self, key, stamp):
        return [m for m in self.frames(key) if m.header.stamp == stamp]

    def send_path(self, pts, frame="world"):
        m = Path()
        m.header.frame_id = frame
        for x, y, z, yaw in pts:
            p = PoseStamped()
            p.pose.position.x, p.pose.position.y, p.pose.position.z = x, y, z
            p.pose.orientation.z, p.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
            m.poses.append(p)
        self.path_pub.publish(m)

    def current_pose(self):
        p = self.frames("pose")[-1].pose.position
        return p.x, p.y, p.z

    # ------------------------------------------------------------------ tests
    def test_1_encodings_and_camera_info(self):
        d = self.frames()[-2]
        stamp = d.header.stamp
        self.assertTrue(wait_for(lambda: all(self.by_stamp(k, stamp) for k in ("rgb", "info", "inst", "cls", "det"))))
        rgb, info = self.by_stamp("rgb", stamp)[0], self.by_stamp("info", stamp)[0]
        inst, cls, det = self.by_stamp("inst", stamp)[0], self.by_stamp("cls", stamp)[0], self.by_stamp("det", stamp)[0]
        self.assertEqual((d.encoding, rgb.encoding, inst.encoding, cls.encoding, det.instance_image.encoding),
                         ("32FC1", "rgb8", "16UC1", "16UC1", "16UC1"))
        for img, bpp in ((d, 4), (rgb, 3), (inst, 2), (cls, 2), (det.instance_image, 2)):
            self.assertEqual((img.width, img.height), (info.width, info.height))
            self.assertEqual(img.step, img.width * bpp)
            self.assertEqual(len(img.data), img.step * img.height)
            self.assertEqual(img.header.frame_id, "camera")
        self.assertEqual((info.width, info.height), (320, 240))
        self.assertEqual(list(info.K), [262.5, 0.0, 159.5, 0.0, 262.5, 119.5, 0.0, 0.0, 1.0])
        self.assertEqual(info.P[0], info.K[0])
        self.assertEqual(info.header.frame_id, "camera")
        depth = np.frombuffer(d.data, np.float32)
        self.assertTrue(np.all(np.isfinite(depth)) and depth.max() <= 10.0 and (depth > 0).mean() > 0.5)
        mask = np.frombuffer(det.instance_image.data, np.uint16)
        ids = sorted(set(np.unique(mask).tolist()) - {0})
        self.assertEqual(ids, sorted(x.instance_id for x in det.detections))
        for x in det.detections:
            self.assertIn(x.class_name, ("chair", "table"))

    def test_2_rates_in_sim_time(self):
        n0 = len(self.frames())
        self.assertTrue(wait_for(lambda: len(self.frames()) >= n0 + 10))
        stamps = [m.header.stamp.to_nsec() for m in self.frames()]
        gaps = np.diff(stamps)
        self.assertTrue(np.all(gaps == 100_000_000), "frame stamps must be 0.1 s apart: %s" % gaps[:20])
        poses = [m.header.stamp.to_nsec() for m in self.frames("pose")]
        self.assertGreater(len(poses), 20)
        pg = np.diff(poses)
        self.assertTrue(np.all(pg > 0) and np.max(pg) <= 20_000_000,
                        "pose (tf) must come every <= 0.02 s of sim time: %s" % pg[:20])
        clock = list(self.clock)
        self.assertTrue(np.all(np.diff(clock) >= 0), "/clock must not go back")

    def test_3_tf_at_image_stamps(self):
        for d in self.frames()[-5:]:
            stamp = d.header.stamp
            ok = wait_for(lambda: self.buffer.can_transform("world", "camera", stamp), 10.0)
            self.assertTrue(ok, "no world->camera transform at image stamp %s" % stamp.to_sec())
            t = self.buffer.lookup_transform("world", "camera", stamp)
            # Camera optical z looks along body x: the rotation maps (0,0,1) to a horizontal vector.
            q = t.transform.rotation
            zx = 2 * (q.x * q.z + q.y * q.w)
            zy = 2 * (q.y * q.z - q.x * q.w)
            zz = 1 - 2 * (q.x * q.x + q.y * q.y)
            self.assertAlmostEqual(zz, 0.0, places=6)
            self.assertAlmostEqual(zx * zx + zy * zy, 1.0, places=6)

    def test_4_lockstep_waits(self):
        cls = type(self)
        cls.auto_report = False
        try:
            # At most one more frame can come (the one released by the last report): wait until
            # the stream has been quiet for 1 s; the sim is then waiting for the newest frame.
            n = -1
            while n != len(self.frames()):
                n = len(self.frames())
                time.sleep(1.0)
            last = self.frames()[-1].header.stamp
            time.sleep(3.0)
            self.assertEqual(self.frames()[-1].header.stamp, last, "a new frame came without a report")
            self.assertLessEqual(max(self.clock[-50:]), last.to_nsec() + 100_000_000, "sim time ran on")
            n = len(self.frames())
            self.report(last)
            self.assertTrue(wait_for(lambda: len(self.frames()) > n, 10.0), "report did not release the next frame")
            self.assertEqual(self.frames()[n].header.stamp.to_nsec(), last.to_nsec() + 100_000_000)
        finally:
            cls.auto_report = True
            self.report(self.frames()[-1].header.stamp)

    def test_5_bad_paths_are_rejected_and_sim_keeps_running(self):
        p0 = self.current_pose()
        self.send_path([(p0[0], p0[1], p0[2], 0.0), (float("nan"), 1.0, 1.0, 0.0)])
        time.sleep(0.3)
        self.send_path([(p0[0], p0[1], p0[2], 0.0), (50.0, 1.0, 1.0, 0.0)])
        time.sleep(0.3)
        self.send_path([(p0[0] + 1.0, p0[1], p0[2], 0.0)], frame="map")
        self.scene_pub.publish(String("/nonexistent/scene_semantic.ply"))
        n = len(self.frames())
        self.assertTrue(wait_for(lambda: len(self.frames()) >= n + 10), "sim stopped after bad input")
        p1 = self.current_pose()
        self.assertLess(np.linalg.norm(np.subtract(p1, p0)), 1e-6, "a rejected path moved the MAV")
        self.assertTrue(wait_for(lambda: len(self.frames("rej")) >= 3, 10.0))
        reasons = [m.data for m in self.frames("rej")]
        self.assertEqual(len(reasons), 3, reasons)
        self.assertIn("NaN", reasons[0])
        self.assertIn("outside the bounds", reasons[1])
        self.assertIn("frame 'map'", reasons[2])

    def test_6_path_following_and_goal_reached(self):
        x, y, z = self.current_pose()
        goal = (x + 1.5, y, z, 0.5)
        n = len(self.frames("goal"))
        self.send_path([(x, y, z, 0.0), goal])
        self.assertTrue(wait_for(lambda: len(self.frames("goal")) > n, 60.0), "goal not reached")
        g = self.frames("goal")[-1].pose
        self.assertLess(np.linalg.norm([g.position.x - goal[0], g.position.y - goal[1], g.position.z - goal[2]]), 0.05)
        self.assertAlmostEqual(2 * math.atan2(g.orientation.z, g.orientation.w), 0.5, delta=0.05)
        colls = self.frames("coll")
        self.assertEqual(colls[-1].data if colls else 0, 0)

    def test_7_path_through_a_wall_is_a_collision(self):
        x, y, z = self.current_pose()
        # The 8 x 6 house has a corridor along x; straight south crosses its wall and then the outer wall.
        self.send_path([(x, y, z, 0.0), (x, -0.05, z, 0.0)])
        self.assertTrue(wait_for(lambda: self.frames("coll") and self.frames("coll")[-1].data >= 1, 60.0),
                        "no collision reported")


if __name__ == "__main__":
    import rostest
    rostest.rosrun(PKG, "sim", SimTest)

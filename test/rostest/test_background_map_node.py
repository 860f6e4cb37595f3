#!/usr/bin/env python3
"""rostest: the background_map node on a wall 3.013 m in front of the camera.

The camera sits at the world origin looking along +x (optical z = world x),
so every pixel's depth is 3.013 m. Bad input must be dropped and counted in
MapStats while the node keeps integrating good frames.
"""
import math
import os
import shutil
import struct
import sys
import tempfile
import time
import unittest

import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import Point, TransformStamped
from sensor_msgs.msg import CameraInfo, Image, PointCloud2

from semantic_exploration.msg import FrameIntegrated, MapBlocks, MapStats
from semantic_exploration.srv import ComputeGains, GetMap, SaveMap

PKG = "semantic_exploration"
W, H, F = 320, 240, 262.5
WALL = 3.013


def camera_info(stamp):
    m = CameraInfo()
    m.header.stamp = stamp
    m.header.frame_id = "camera"
    m.width, m.height = W, H
    m.K = [F, 0, 159.5, 0, F, 119.5, 0, 0, 1]
    m.P = [F, 0, 159.5, 0, 0, F, 119.5, 0, 0, 0, 1, 0]
    m.distortion_model = "plumb_bob"
    m.D = [0.0] * 5
    return m


def depth_image(stamp, values, encoding="32FC1", frame="camera"):
    m = Image()
    m.header.stamp = stamp
    m.header.frame_id = frame
    m.height, m.width = values.shape[:2]
    m.encoding = encoding
    m.is_bigendian = 0
    m.step = values.strides[0]
    m.data = values.tobytes()
    return m


def static_tf(child, x):
    t = TransformStamped()
    t.header.stamp = rospy.Time(0)
    t.header.frame_id = "world"
    t.child_frame_id = child
    t.transform.translation.x = x
    # optical frame looking along world +x: x_C = -y_W, y_C = -z_W, z_C = x_W  -> q = (-0.5, 0.5, -0.5, 0.5)
    t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z, t.transform.rotation.w = -0.5, 0.5, -0.5, 0.5
    return t


class TestBackgroundMapNode(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_background_map_node")
        cls.stats, cls.updates, cls.done, cls.frontiers = [], [], [], []
        rospy.Subscriber("/background_map/stats", MapStats, lambda m: cls.stats.append(m), queue_size=100)
        rospy.Subscriber("/background_map/map_update", MapBlocks, lambda m: cls.updates.append(m), queue_size=100)
        rospy.Subscriber("/frame_integrated", FrameIntegrated, lambda m: cls.done.append(m), queue_size=100)
        rospy.Subscriber("/background_map/frontiers", PointCloud2, lambda m: cls.frontiers.append(m), queue_size=10)
        cls.occupied = []
        cls.occupied_sub = rospy.Subscriber("/background_map/occupied", PointCloud2, lambda m: cls.occupied.append(m),
                                            queue_size=10)
        cls.depth_pub = rospy.Publisher("/camera/depth/image_raw", Image, queue_size=10)
        cls.rgb_pub = rospy.Publisher("/camera/rgb/image_raw", Image, queue_size=10)
        cls.info_pub = rospy.Publisher("/camera/camera_info", CameraInfo, queue_size=10, latch=True)
        cls.tfb = tf2_ros.StaticTransformBroadcaster()
        cls.tfb.sendTransform([static_tf("camera", 0.0), static_tf("far_camera", 100.0)])
        for srv in ("/background_map/get_map", "/background_map/compute_gains", "/background_map/save"):
            rospy.wait_for_service(srv, timeout=30.0)
        deadline = time.time() + 10.0
        while (cls.depth_pub.get_num_connections() == 0 or cls.rgb_pub.get_num_connections() == 0) and time.time() < deadline:
            time.sleep(0.05)
        time.sleep(0.5)

    def send(self, msg, timeout=10.0):
        """Publishes a depth image and waits for its frame_integrated report."""
        n = len(self.done)
        self.depth_pub.publish(msg)
        deadline = time.time() + timeout
        while time.time() < deadline:
            for d in self.done[n:]:
                if d.header.stamp == msg.header.stamp:
                    time.sleep(0.1)  # let stats arrive
                    return d
            time.sleep(0.01)
        self.fail("no frame_integrated for stamp %s" % msg.header.stamp)

    def wall(self):
        return np.full((H, W), WALL, dtype=np.float32)

    def test_all(self):
        # 1. Depth before any camera_info is dropped.
        d = self.send(depth_image(rospy.Time.now(), self.wall()))
        self.assertFalse(d.integrated)
        self.assertEqual(self.stats[-1].dropped_no_camera_info, 1)
        self.info_pub.publish(camera_info(rospy.Time.now()))
        time.sleep(0.5)

        # 2. A good frame (with its colour image) integrates; an update with sequence 1 follows.
        stamp = rospy.Time.now()
        rgb = np.zeros((H, W, 3), dtype=np.uint8)
        rgb[..., 0] = 200
        self.rgb_pub.publish(depth_image(stamp, rgb, "rgb8"))
        d = self.send(depth_image(stamp, self.wall()))
        self.assertTrue(d.integrated)
        deadline = time.time() + 5.0
        while not self.occupied and time.time() < deadline:
            time.sleep(0.05)
        self.assertTrue(self.occupied)
        c = self.occupied[-1]
        self.assertGreater(c.width * c.height, 1000)
        off = {f.name: f.offset for f in c.fields}
        reds = [c.data[i * c.point_step + off["rgb"] + 2] for i in range(0, c.width, 50)]  # bgra byte order: r at +2
        self.assertGreater(sum(1 for r in reds if r == 200), 0.9 * len(reds))
        s = self.stats[-1]
        self.assertEqual(s.frames_integrated, 1)
        self.assertGreater(s.free_volume_m3, 5.0)     # the frustum up to the wall (~9.6 m^3)
        self.assertGreater(s.occupied_volume_m3, 0.0)
        self.assertGreater(s.frontier_count, 0)
        self.assertEqual(s.invalid_depth_pixels, 0)
        # frontier_period_s 0: the frame's frontier cloud goes out before its stats, which name it, so a
        # planner waiting for the frontiers the stats name plans on this frame's, not the one before.
        self.assertEqual(s.header.stamp, stamp)
        self.assertEqual(s.frontiers_stamp, stamp)
        self.assertIn(stamp, [f.header.stamp for f in self.frontiers])
        deadline = time.time() + 5.0
        while not self.updates and time.time() < deadline:
            time.sleep(0.05)
        self.assertTrue(self.updates)
        self.assertEqual(self.updates[0].sequence, 1)
        self.assertFalse(self.updates[0].full)
        self.assertEqual(len(self.updates[0].payload), len(self.updates[0].coords) // 3 * 512)

        # 3. Services: full map, gains looking at the wall, save.
        m = rospy.ServiceProxy("/background_map/get_map", GetMap)().map
        self.assertTrue(m.full)
        self.assertGreater(len(m.coords), 0)
        self.assertEqual(len(m.uniform_coords), 0)  # not asked for compact: every block in full
        # Compact: the same blocks, those of one value as that value (3 coordinates and 1 byte each).
        c = rospy.ServiceProxy("/background_map/get_map", GetMap)(compact=True).map
        self.assertGreater(len(c.uniform_values), 0)
        self.assertEqual(len(c.uniform_coords), 3 * len(c.uniform_values))
        self.assertEqual(len(c.coords) + len(c.uniform_coords), len(m.coords))
        self.assertEqual(len(c.payload) + 512 * len(c.uniform_values), len(m.payload))
        g = rospy.ServiceProxy("/background_map/compute_gains", ComputeGains)(
            positions=[Point(0.0, 0.0, 0.0)], width=36, height=10, max_depth_m=[])
        self.assertEqual(len(g.hit_depth), 1)
        hit = np.frombuffer(g.hit_depth[0].data, dtype=np.float32).reshape(10, 36)
        ent = np.frombuffer(g.entropy_gain[0].data, dtype=np.float32).reshape(10, 36)
        # column 18 = azimuth +5 deg, row 4 = elevation +2.1 deg: the wall at ~3.0 m
        self.assertAlmostEqual(float(hit[4, 18]), WALL / math.cos(math.radians(5)), delta=0.1)
        self.assertAlmostEqual(float(hit[4, 0]), 10.0, delta=1e-3)  # looking backwards: nothing hit
        self.assertGreater(float(ent[4, 0]), float(ent[4, 18]))      # unknown behind vs. known in front
        out = tempfile.mkdtemp(prefix="semexp_background_map_test_")
        self.addCleanup(shutil.rmtree, out, True)  # also when an assertion below fails
        r = rospy.ServiceProxy("/background_map/save", SaveMap)(directory=out)
        self.assertTrue(r.success, r.message)
        for f in r.files:
            self.assertTrue(os.path.getsize(f) > 0, f)
        self.assertEqual(sorted(os.path.basename(f) for f in r.files),
                         ["background_map.bt", "background_map.semexpmap", "occupied.ply"])

        # 4. Bad input: each dropped and counted, the node keeps running.
        before = self.stats[-1]
        self.assertFalse(self.send(depth_image(rospy.Time.now(), np.zeros((H, W), np.uint8), "8UC1")).integrated)
        self.assertFalse(self.send(depth_image(rospy.Time.now(), np.full((120, 160), WALL, np.float32))).integrated)
        self.assertFalse(self.send(depth_image(rospy.Time.now(), self.wall(), frame="nowhere")).integrated)
        self.assertFalse(self.send(depth_image(rospy.Time.now(), self.wall(), frame="far_camera")).integrated)
        s = self.stats[-1]
        self.assertEqual(s.dropped_bad_depth, before.dropped_bad_depth + 1)
        self.assertEqual(s.dropped_size_mismatch, before.dropped_size_mismatch + 1)
        self.assertEqual(s.dropped_no_tf, before.dropped_no_tf + 1)
        self.assertEqual(s.dropped_out_of_bounds, before.dropped_out_of_bounds + 1)
        self.assertEqual(s.frames_integrated, before.frames_integrated)

        # 5. NaN, inf, negative and zero pixels are counted and carve nothing; 16UC1 millimetres work.
        bad = self.wall()
        bad[0, :4] = [np.nan, np.inf, -1.0, 0.0]
        self.assertTrue(self.send(depth_image(rospy.Time.now(), bad)).integrated)
        self.assertEqual(self.stats[-1].invalid_depth_pixels, before.invalid_depth_pixels + 4)
        mm = np.full((H, W), int(WALL * 1000), dtype=np.uint16)
        self.assertTrue(self.send(depth_image(rospy.Time.now(), mm, "16UC1")).integrated)
        self.assertEqual(self.stats[-1].frames_integrated, before.frames_integrated + 2)
        seqs = [u.sequence for u in self.updates]
        self.assertEqual(seqs, list(range(1, len(seqs) + 1)))  # in order, no gaps

        # 6. A cloud that fell due while nobody listened reaches the next listener (rviz started late), with
        # nothing integrated after it: a nearer wall at 2.0 m is in the cloud the new subscriber gets.
        self.occupied_sub.unregister()
        time.sleep(3.5)  # past publish_period_s (3 s here): the next frame's cloud is due, with no listener
        near = np.full((H, W), 2.0, dtype=np.float32)
        self.assertTrue(self.send(depth_image(rospy.Time.now(), near)).integrated)
        late = []
        sub = rospy.Subscriber("/background_map/occupied", PointCloud2, late.append, queue_size=10)
        self.addCleanup(sub.unregister)
        deadline = time.time() + 5.0
        while not any(_has_point_near_x(c, 2.0) for c in late) and time.time() < deadline:
            time.sleep(0.05)
        self.assertTrue(any(_has_point_near_x(c, 2.0) for c in late),
                        "a late subscriber got %d clouds, none with the wall at 2.0 m" % len(late))

        # 7. The last change before frames stop reaches a listener once publish_period_s is over, though the
        # frontier cloud (period 0 here) went out with that frame while the occupied one was not due yet
        # (the step-6 frame's cloud went out under 3 s ago).
        # (A farther wall: voxels at 4.0 m are still unknown, so one frame makes them occupied.)
        farther = np.full((H, W), 4.0, dtype=np.float32)
        self.assertTrue(self.send(depth_image(rospy.Time.now(), farther)).integrated)
        deadline = time.time() + 5.0
        while not any(_has_point_near_x(c, 4.0) for c in late) and time.time() < deadline:
            time.sleep(0.05)
        self.assertTrue(any(_has_point_near_x(c, 4.0) for c in late),
                        "no cloud with the wall at 4.0 m in %d clouds after the frames stopped" % len(late))


def _has_point_near_x(cloud, x, tol=0.05):
    off = {f.name: f.offset for f in cloud.fields}["x"]
    rows = np.frombuffer(cloud.data, dtype=np.uint8).reshape(-1, cloud.point_step)
    xs = rows[:, off:off + 4].copy().view("<f4").ravel()
    return bool(np.any(np.abs(xs - x) < tol))


if __name__ == "__main__":
    import rostest
    rostest.rosrun(PKG, "test_background_map_node", TestBackgroundMapNode, sys.argv)

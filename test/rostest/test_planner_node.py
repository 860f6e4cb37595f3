#!/usr/bin/env python3
"""rostest: the planner node against a scripted background map.

The map is a 4 x 4 x 2 m room at 0.1 m (8^3 blocks from the origin) with a
wall at x in [2.0, 2.2] for y < 3 m; beyond x = 4 m it is unknown. The MAV
sits at (1, 1, 1). compute_gains answers entropy 0.5 in the six columns
centred on yaw +pi/2 and 0 elsewhere, so the chosen yaw must be pi/2.
"""
import math
import struct
import sys
import threading
import time
import unittest

import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import Point, TransformStamped
from nav_msgs.msg import Path
from sensor_msgs.msg import CameraInfo, Image, PointCloud2, PointField

from semantic_exploration import map_blocks
from semantic_exploration.msg import CandidateViewArray, ExplorationStatus, MapBlocks, MapStats
from semantic_exploration.srv import (ComputeGains, ComputeGainsResponse, GetHistoryMasks, GetMap, GetMapResponse,
                                      PlanOnce)

PKG = "semantic_exploration"
RES = 0.1
BS = 8
R = 0.125
START = (1.0, 1.0, 1.0)
# Frontier voxels just inside the unknown half beyond x = 4 m, at the MAV's height.
FRONTIER_POINTS = [(3.95, y, 1.0) for y in (0.55, 1.05, 1.55, 2.05)]


def room():
    """Voxel grid over blocks 0..4 x 0..4 x 0..2: log-odds int8 (-4 free, 20 occupied, -128 unknown)."""
    n = (5 * BS, 5 * BS, 3 * BS)
    g = np.full(n, -4, dtype=np.int8)
    c = (np.indices(n).transpose(1, 2, 3, 0) + 0.5) * RES
    x, y, z = c[..., 0], c[..., 1], c[..., 2]
    g[(x > 4.0)] = -128
    g[(y > 4.0)] = -128
    g[(z < 0.1) | (z > 2.0)] = 20
    g[(x > 2.0) & (x < 2.2) & (y < 3.0)] = 20
    return g


def occupied(g, p):
    i = [int(math.floor(p[k] / RES)) for k in range(3)]
    if any(i[k] < 0 or i[k] >= g.shape[k] for k in range(3)):
        return False  # unknown outside: not occupied
    return g[i[0], i[1], i[2]] >= 0


def assert_path_safe(test, g, path, start=START, escaped=False):
    """The path starts at `start`, and spheres of R (R/2 on an escape's first
    segment) every 1 cm along it hold no occupied voxel of grid g: voxel
    centres within R + half a voxel diagonal are tested conservatively by
    sampling the sphere surface and centre."""
    p0 = path.poses[0].pose.position
    test.assertAlmostEqual(p0.x, start[0], places=3)
    test.assertAlmostEqual(p0.y, start[1], places=3)
    test.assertAlmostEqual(p0.z, start[2], places=3)
    pts = [(q.pose.position.x, q.pose.position.y, q.pose.position.z) for q in path.poses]
    dirs = [(math.cos(a) * math.cos(e), math.sin(a) * math.cos(e), math.sin(e))
            for a in np.linspace(0, 2 * math.pi, 24, endpoint=False) for e in (-1.2, -0.6, 0.0, 0.6, 1.2)]
    dirs += [(0, 0, 1), (0, 0, -1), (0, 0, 0)]
    for s, (a, b) in enumerate(zip(pts[:-1], pts[1:])):
        radius = R / 2 if escaped and s == 0 else R
        n = max(1, int(math.ceil(math.dist(a, b) / 0.01)))
        for k in range(n + 1):
            c = [a[i] + (b[i] - a[i]) * k / n for i in range(3)]
            for d in dirs:
                q = [c[i] + radius * 0.999 * d[i] for i in range(3)]
                test.assertFalse(occupied(g, q), "path point %s within %.3f m of an occupied voxel" % (c, radius))


def blocks_msg(g, seq, full):
    m = MapBlocks()
    m.header.frame_id = "world"
    m.header.stamp = rospy.Time.now()
    return map_blocks.encode(m, g, (0.0, 0.0, 0.0), RES, BS, seq, full)  # the codec's layout and encoding


def cloud(points):
    c = PointCloud2()
    c.header.frame_id = "world"
    c.header.stamp = rospy.Time.now()
    c.height = 1
    c.width = len(points)
    c.fields = [PointField("x", 0, PointField.FLOAT32, 1), PointField("y", 4, PointField.FLOAT32, 1),
                PointField("z", 8, PointField.FLOAT32, 1)]
    c.point_step = 12
    c.row_step = 12 * len(points)
    c.is_dense = True
    c.data = b"".join(struct.pack("<fff", *p) for p in points)
    return c


def gain_image(values):
    img = Image()
    img.height, img.width = values.shape
    img.encoding = "32FC1"
    img.step = 4 * img.width
    img.data = values.astype("<f4").tobytes()
    return img


class PlannerNodeTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.grid = room()
        cls.gains_calls = 0
        cls.get_map_calls = 0
        cls.lock = threading.Lock()
        cls.paths, cls.status, cls.candidates = [], [], []
        rospy.Subscriber("/planner/path", Path, lambda m: cls.paths.append(m))
        rospy.Subscriber("/planner/status", ExplorationStatus, lambda m: cls.status.append(m))
        rospy.Subscriber("/planner/candidates", CandidateViewArray, lambda m: cls.candidates.append(m))
        rospy.Service("/background_map/compute_gains", ComputeGains, cls.compute_gains)
        rospy.Service("/background_map/get_map", GetMap, cls.get_map)
        cls.map_pub = rospy.Publisher("/background_map/map_update", MapBlocks, queue_size=5, latch=True)
        cls.frontier_pub = rospy.Publisher("/background_map/frontiers", PointCloud2, queue_size=1, latch=True)
        cls.tf = tf2_ros.StaticTransformBroadcaster()
        t = TransformStamped()
        t.header.frame_id = "world"
        t.child_frame_id = "body"
        t.header.stamp = rospy.Time.now()
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = START
        t.transform.rotation.w = 1.0
        # Optical camera at the body origin looking along body x (z forward, x right, y down).
        c = TransformStamped()
        c.header.frame_id = "body"
        c.child_frame_id = "camera"
        c.header.stamp = t.header.stamp
        c.transform.rotation.x, c.transform.rotation.y, c.transform.rotation.z, c.transform.rotation.w = (
            -0.5, 0.5, -0.5, 0.5)
        cls.tf.sendTransform([t, c])
        cls.map_pub.publish(blocks_msg(cls.grid, 1, True))
        # Frontiers along the unknown face x = 4 m, behind the wall.
        cls.frontier_pub.publish(cloud(FRONTIER_POINTS))
        rospy.wait_for_service("/planner/plan_once", timeout=30.0)
        time.sleep(1.0)  # let the latched messages arrive

    @classmethod
    def compute_gains(cls, req):
        with cls.lock:
            cls.gains_calls += 1
        w, h = req.width, req.height
        img = np.zeros((h, w), dtype=np.float32)
        centre = int(round((math.pi / 2 + math.pi) / (2 * math.pi) * w))  # yaw +pi/2
        img[:, centre - 3:centre + 3] = 0.5
        res = ComputeGainsResponse()
        for _ in req.positions:
            res.entropy_gain.append(gain_image(img))
            res.distance_gain.append(gain_image(np.zeros((h, w), dtype=np.float32)))
            res.hit_depth.append(gain_image(np.full((h, w), 10.0, dtype=np.float32)))
        return res

    @classmethod
    def get_map(cls, _req):
        with cls.lock:
            cls.get_map_calls += 1
        # Stamped as background_map stamps it: its last integrated frame, here an old one.
        m = blocks_msg(cls.grid, 7, True)
        m.header.stamp = rospy.Time(2.0)
        return GetMapResponse(map=m)

    def plan_once(self):
        return rospy.ServiceProxy("/planner/plan_once", PlanOnce)()

    def wait_for(self, cond, timeout=20.0):
        deadline = time.time() + timeout
        while time.time() < deadline and not cond():
            time.sleep(0.05)
        return cond()

    def test_1_path_is_safe_and_yawed(self):
        n_paths = len(self.paths)
        res = self.plan_once()
        self.assertTrue(res.success, res.message)
        self.assertTrue(self.wait_for(lambda: len(self.paths) > n_paths), "no path published")
        path = self.paths[-1]
        self.assertEqual(path.header.frame_id, "world")
        self.assertGreaterEqual(len(path.poses), 2)
        assert_path_safe(self, self.grid, path)
        pts = [(q.pose.position.x, q.pose.position.y, q.pose.position.z) for q in path.poses]
        # The end yaw is the best window's: +pi/2.
        o = path.poses[-1].pose.orientation
        self.assertAlmostEqual(2 * math.atan2(o.z, o.w), math.pi / 2, places=3)
        # Every frontier lies behind the wall (x in [2, 2.2] for y < 3): the
        # path ends past it and goes round it at y > 3.
        self.assertGreater(pts[-1][0], 2.2, "path ends at %s" % (pts[-1],))
        self.assertTrue(any(p[1] > 3.0 for p in pts), "path %s did not go round the wall" % (pts,))
        self.assertTrue(self.wait_for(lambda: any(s.iteration >= 1 and s.planning_time_s > 0 for s in self.status)))
        st = [s for s in self.status if s.iteration >= 1][-1]
        self.assertGreater(st.candidates_sampled, 0)
        self.assertGreater(st.candidates_reachable, 0)
        self.assertGreaterEqual(st.planning_time_s, st.path_planning_time_s)
        self.assertTrue(self.wait_for(lambda: len(self.candidates) > 0))
        self.assertGreaterEqual(self.candidates[-1].winner, 0)
        self.assertGreater(self.gains_calls, 0)

    def test_2_sequence_gap_resyncs(self):
        before = self.get_map_calls
        self.map_pub.publish(blocks_msg(self.grid, 5, False))  # 2..4 lost
        self.assertTrue(self.wait_for(lambda: self.get_map_calls > before), "no get_map call after a gap")

    def test_2b_frame_stamp_waits_for_the_frames_inputs(self):
        # A frame the planner has nothing of yet: it answers pending, naming the
        # first input missing, until stats, the map update and the frontier
        # cloud those stats name have all arrived; then it plans.
        frame = rospy.Time.now() + rospy.Duration(1000.0)
        n_paths = len(self.paths)

        def ask():
            return rospy.ServiceProxy("/planner/plan_once", PlanOnce)(rospy.Time(), frame, rospy.Time())
        res = ask()
        self.assertTrue(res.pending and not res.success, res)
        self.assertIn("background_map/stats", res.message)
        self.assertTrue(self.wait_for(lambda: self.get_map_calls > 0))  # test_2's resync: the replica is at 7
        time.sleep(0.5)
        stats_pub = rospy.Publisher("/background_map/stats", MapStats, queue_size=1, latch=True)
        self.assertTrue(self.wait_for(lambda: stats_pub.get_num_connections() > 0))
        stats = MapStats(explored_volume_m3=10.0, surface_observed_share=-1.0, map_update_sequence=8)
        stats.header.stamp = stats.frontiers_stamp = frame
        stats_pub.publish(stats)
        self.assertTrue(self.wait_for(lambda: "map_update 8" in ask().message), ask())
        self.map_pub.publish(blocks_msg(self.grid, 8, False))
        self.assertTrue(self.wait_for(lambda: "background_map/frontiers" in ask().message), ask())
        frontiers = cloud(FRONTIER_POINTS)
        frontiers.header.stamp = frame
        time.sleep(0.5)
        self.assertEqual(len(self.paths), n_paths, "a pending answer planned")
        self.frontier_pub.publish(frontiers)
        answers = []
        self.assertTrue(self.wait_for(lambda: not answers.append(ask()) and not answers[-1].pending))
        self.assertTrue(answers[-1].success, answers[-1].message)
        self.assertTrue(self.wait_for(lambda: len(self.paths) > n_paths), "no path after the inputs arrived")

    def test_2c_a_restarted_map_is_seen_without_its_sequence_1(self):
        # The replica holds sequence 8 (test_2b). An update older in sequence and
        # in stamp (queued before a resync) is only stale. One older in sequence
        # but newer in stamp comes from a background_map that restarted and whose
        # update 1 never arrived (or whose resync failed): resync. Both go over
        # one connection, in order. Had the first led to a resync, its full map
        # (stamped 2 s) would leave the second stale and newer again: a second call.
        before = self.get_map_calls
        queued = blocks_msg(self.grid, 3, False)
        queued.header.stamp = rospy.Time(1.0)
        self.map_pub.publish(queued)
        self.map_pub.publish(blocks_msg(self.grid, 3, False))
        self.assertTrue(self.wait_for(lambda: self.get_map_calls > before), "no resync after the map restarted")
        time.sleep(1.0)
        self.assertEqual(self.get_map_calls, before + 1, "the stale update led to a resync too")
        self.map_pub.publish(blocks_msg(self.grid, 8, False))  # back at 8 (the resync answers 7), as test_2b left it

    def test_3_no_frontiers_terminates(self):
        # Semantic mode: "explored" also needs the background seen from <= d_bg
        # (termination/background_observed_share 0.9) and no object left; the
        # background map reports the share in its stats.
        stats_pub = rospy.Publisher("/background_map/stats", MapStats, queue_size=1, latch=True)
        self.assertTrue(self.wait_for(lambda: stats_pub.get_num_connections() > 0))
        stats_pub.publish(MapStats(explored_volume_m3=10.0, surface_voxels=1000, surface_observed_share=0.95))
        self.frontier_pub.publish(cloud([]))
        time.sleep(0.5)
        res = self.plan_once()
        self.assertFalse(res.success)
        self.assertTrue(self.wait_for(lambda: any(s.state == ExplorationStatus.STATE_FINISHED for s in self.status)))
        fin = [s for s in self.status if s.state == ExplorationStatus.STATE_FINISHED][-1]
        self.assertEqual(fin.termination_reason, "explored")
        self.assertTrue(fin.frontiers_done and fin.background_done and fin.objects_done)
        self.assertAlmostEqual(fin.background_observed_share, 0.95, places=5)
        self.assertEqual(fin.active_frontiers, 0)
        # Finished stays finished: frontiers that come back (noise, a lockstep
        # simulator asking again while the MAV hovers) are not planned for.
        iterations = max(s.iteration for s in self.status)
        n_paths = len(self.paths)
        self.frontier_pub.publish(cloud(FRONTIER_POINTS))
        time.sleep(0.5)
        res = self.plan_once()
        self.assertFalse(res.success or res.pending)
        self.assertIn("finished: explored", res.message)
        time.sleep(0.5)
        self.assertEqual(len(self.paths), n_paths, "planned after the exploration finished")
        self.assertEqual(max(s.iteration for s in self.status), iterations)

    def test_4_depth_history_marks_invalid_pixel(self):
        # Table I camera; pixel (u 159, v 119) is half a pixel left of and above
        # the principal point: world direction just left of +x and just above
        # the horizon -> column 18, row 4 of the 36 x 10 mask (see
        # test/core/depth_history_test.cpp).
        info_pub = rospy.Publisher("/camera/camera_info", CameraInfo, queue_size=1, latch=True)
        depth_pub = rospy.Publisher("/camera/depth/image_raw", Image, queue_size=1)
        info = CameraInfo()
        info.header.frame_id = "camera"
        info.width, info.height = 320, 240
        info.K = [262.5, 0, 159.5, 0, 262.5, 119.5, 0, 0, 1]
        info_pub.publish(info)
        self.assertTrue(self.wait_for(lambda: depth_pub.get_num_connections() > 0, 10.0))
        time.sleep(0.5)
        depth = np.full((240, 320), 2.0, dtype=np.float32)
        depth[119, 159] = 0.0
        img = gain_image(depth)
        img.header.frame_id = "camera"
        get_masks = rospy.ServiceProxy("/depth_history/get_masks", GetHistoryMasks)
        p = Point(*START)
        for _ in range(50):
            img.header.stamp = rospy.Time.now()
            depth_pub.publish(img)
            time.sleep(0.1)
            mask = np.frombuffer(get_masks(positions=[p], width=36, height=10).masks[0].data, dtype=np.uint8)
            if (mask == 0).any():
                break
        self.assertEqual(int((mask == 0).sum()), 1, mask.reshape(10, 36))
        self.assertEqual(mask[4 * 36 + 18], 0)
        # Another cell is untouched.
        other = get_masks(positions=[Point(3.0, 3.0, 1.0)], width=36, height=10).masks[0]
        self.assertTrue(all(b == 1 for b in bytearray(other.data)))


if __name__ == "__main__":
    import rostest
    rospy.init_node("test_planner_node")
    rostest.rosrun(PKG, "planner_node", PlannerNodeTest, sys.argv)

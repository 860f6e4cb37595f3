#!/usr/bin/env python3
"""rostest: the planner on bad input: services that hang, a start pose in
unknown or occupied space.

Same scripted room as test_planner_node.py (wall at x in [2.0, 2.2] for
y < 3 m, frontiers behind it, MAV at (1, 1, 1)); planner/service_timeout_s is
1 s. background_map/compute_gains sleeps 3 s on its first HANG_CALLS calls
and then answers late with its best yaw at -pi/2; later calls answer at once
with the best yaw at +pi/2. depth_history/get_masks sleeps 3 s on its first
call. object_map/compute_gains does not exist.

Empty map (a full MapBlocks without blocks): a path request reports
"waiting for the map (the replica is empty)" and publishes nothing.

Expected: while background gains time out the planner reports "service
background_map/compute_gains timed out after 1.0 s" in its status, counts it
in service_timeouts, publishes no path and keeps iterating on its own; once
the service answers it publishes a collision-free path whose end yaw is
+pi/2 (a late answer is never used), saying that the history timed out.
Then the gain service goes away (a path request reports it and publishes
nothing) and comes back (the next request publishes a path again).

Start in unknown space (x = 4.1 m; beyond x = 4 m is unknown): the path
escapes, i.e. starts at the MAV, first moves into known free space where
the sphere of R + clearance margin (0.165 m) is free (x <= 3.835 m), keeping
R/2 from occupied voxels, and is collision-free at R from there on.

Start inside the wall: every iteration reports "the current position is not
in free space and no escape was found", publishes no path, and the fifth in a
row (planner/max_failed_iterations) ends the exploration with
"no_reachable_candidate".
"""
import math
import os
import sys
import threading
import time
import unittest

import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Path
from sensor_msgs.msg import PointCloud2

from semantic_exploration.msg import DropCounts, ExplorationStatus, MapBlocks
from semantic_exploration.srv import (ComputeGains, ComputeGainsResponse, GetHistoryMasks,
                                      GetHistoryMasksResponse, GetMap, GetMapResponse, PlanOnce)
from sensor_msgs.msg import Image

# test_planner_node.py lies beside this file's real path (a catkin devel-space relay runs this file from elsewhere).
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from test_planner_node import (FRONTIER_POINTS, R, START, assert_path_safe, blocks_msg, cloud,  # noqa: E402
                               gain_image, room)

PKG = "semantic_exploration"
HANG_CALLS = 3  # compute_gains calls that hang
HANG_S = 3.0    # > planner/service_timeout_s (1 s, see the .test)
CLEARANCE = R + 0.04  # planner/clearance_margin_m
MAX_FAILED = 5  # planner/max_failed_iterations
TIMEOUT_TEXT = "service background_map/compute_gains timed out after 1.0 s"


def yaw_peak(w, h, yaw):
    img = np.zeros((h, w), dtype=np.float32)
    centre = int(round((yaw + math.pi) / (2 * math.pi) * w)) % w
    for d in range(-3, 3):
        img[:, (centre + d) % w] = 0.5
    return img


class PlannerBadInputTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.grid = room()
        cls.lock = threading.Lock()
        cls.gains_calls = 0
        cls.fail_gains = 0  # compute_gains calls still to answer with an error
        cls.masks_calls = 0
        cls.normal_answers = []  # rospy time of each prompt compute_gains answer
        cls.paths, cls.status = [], []
        rospy.Subscriber("/planner/path", Path, lambda m: cls.paths.append((time.time(), m)))
        rospy.Subscriber("/planner/status", ExplorationStatus, lambda m: cls.status.append(m))
        cls.gains_srv = rospy.Service("/background_map/compute_gains", ComputeGains, cls.compute_gains)
        rospy.Service("/depth_history/get_masks", GetHistoryMasks, cls.get_masks)
        cls.get_map_calls = 0
        rospy.Service("/background_map/get_map", GetMap, cls.get_map)
        cls.map_pub = rospy.Publisher("/background_map/map_update", MapBlocks, queue_size=5, latch=True)
        cls.frontier_pub = rospy.Publisher("/background_map/frontiers", PointCloud2, queue_size=1, latch=True)
        cls.tf = tf2_ros.StaticTransformBroadcaster()
        cls.move_to(START)
        cls.frontier_pub.publish(cloud(FRONTIER_POINTS))
        rospy.wait_for_service("/planner/plan_once", timeout=30.0)
        # First an empty map (a full update without blocks), then the room.
        cls.map_pub.publish(blocks_msg(np.zeros((0, 0, 0), dtype=np.int8), 1, True))
        time.sleep(1.0)
        cls.empty_map_result = rospy.ServiceProxy("/planner/plan_once", PlanOnce)()
        cls.paths_before_map = len(cls.paths)
        cls.map_pub.publish(blocks_msg(cls.grid, 2, True))

    @classmethod
    def move_to(cls, p):
        t = TransformStamped()
        t.header.frame_id = "world"
        t.child_frame_id = "body"
        t.header.stamp = rospy.Time.now()
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = p
        t.transform.rotation.w = 1.0
        cls.tf.sendTransform([t])

    @classmethod
    def get_map(cls, _req):
        with cls.lock:
            cls.get_map_calls += 1
        return GetMapResponse(map=blocks_msg(cls.grid, 7, True))

    @classmethod
    def compute_gains(cls, req):
        with cls.lock:
            cls.gains_calls += 1
            hang = cls.gains_calls <= HANG_CALLS
            fail = cls.fail_gains > 0
            cls.fail_gains -= 1 if fail else 0
        if fail:  # the caller gets no answer, as from a connection lost under load
            raise rospy.ServiceException("test: no answer this time")
        w, h = req.width, req.height
        if hang:
            time.sleep(HANG_S)
        res = ComputeGainsResponse()
        img = yaw_peak(w, h, -math.pi / 2 if hang else math.pi / 2)
        for _ in req.positions:
            res.entropy_gain.append(gain_image(img))
            res.distance_gain.append(gain_image(np.zeros((h, w), dtype=np.float32)))
            res.hit_depth.append(gain_image(np.full((h, w), 10.0, dtype=np.float32)))
        if not hang:
            with cls.lock:
                cls.normal_answers.append(time.time())
        return res

    @classmethod
    def get_masks(cls, req):
        with cls.lock:
            cls.masks_calls += 1
            hang = cls.masks_calls == 1
        if hang:
            time.sleep(HANG_S)
        res = GetHistoryMasksResponse()
        for _ in req.positions:
            m = Image()
            m.width, m.height, m.step, m.encoding = req.width, req.height, req.width, "mono8"
            m.data = bytes([1]) * (req.width * req.height)
            res.masks.append(m)
        return res

    def wait_for(self, cond, timeout):
        deadline = time.time() + timeout
        while time.time() < deadline and not cond():
            time.sleep(0.05)
        return cond()

    def assert_safe(self, path, start=START, escaped=False):
        """Safe (assert_path_safe) and ending at the prompt answer's yaw, +pi/2."""
        assert_path_safe(self, self.grid, path, start, escaped)
        o = path.poses[-1].pose.orientation
        self.assertAlmostEqual(2 * math.atan2(o.z, o.w), math.pi / 2, places=3,
                               msg="the end yaw is not the prompt answer's (a late answer was used?)")

    def test_0_empty_map_is_reported(self):
        self.assertFalse(self.empty_map_result.success)
        self.assertEqual(self.empty_map_result.message, "waiting for the map (the replica is empty)")
        self.assertEqual(self.paths_before_map, 0)
        self.assertTrue(any(s.message == "waiting for the map (the replica is empty)" and
                            s.state == ExplorationStatus.STATE_WAITING for s in self.status))

    def test_1_timeouts_are_reported_and_retried_until_the_service_answers(self):
        # The planner iterates on its own (retry_period_s 0.5 s); no path while gains hang.
        self.assertTrue(self.wait_for(lambda: len(self.paths) > 0, 90.0), "no path once the service answered")
        t_path, path = self.paths[0]
        with self.lock:
            first_answer = self.normal_answers[0] if self.normal_answers else None
        self.assertIsNotNone(first_answer, "a path was published before compute_gains ever answered promptly")
        self.assertGreaterEqual(t_path, first_answer)
        timed_out = [s for s in self.status if TIMEOUT_TEXT in s.message]
        self.assertGreaterEqual(len(timed_out), HANG_CALLS, [s.message for s in self.status])
        iterations = [s.iteration for s in timed_out]
        self.assertEqual(iterations, sorted(set(iterations)), "one timeout report per iteration, iterations grow")
        for s in timed_out:
            self.assertEqual(s.state, ExplorationStatus.STATE_WAITING, s.message)
            self.assertEqual(s.termination_reason, "")
        self.assertGreaterEqual(timed_out[-1].service_timeouts, HANG_CALLS)
        self.assertGreaterEqual(self.gains_calls, HANG_CALLS + 1)
        self.assert_safe(path)
        # The iteration that published the path went on without the hung history.
        done = [s for s in self.status if s.state == ExplorationStatus.STATE_EXECUTING]
        self.assertTrue(done, [s.message for s in self.status])
        self.assertGreater(done[0].iteration, iterations[-1])
        self.assertIn("service depth_history/get_masks timed out after 1.0 s", done[0].message)
        self.assertIn("planned without the history", done[0].message)
        self.assertGreaterEqual(done[0].service_timeouts, HANG_CALLS + 1)

    def test_2_a_service_that_goes_away_and_returns(self):
        plan_once = rospy.ServiceProxy("/planner/plan_once", PlanOnce)
        self.gains_srv.shutdown()
        n_paths = len(self.paths)
        res = plan_once()
        self.assertFalse(res.success)
        self.assertIn("background_map/compute_gains timed out after 1.0 s", res.message)
        time.sleep(0.5)
        self.assertEqual(len(self.paths), n_paths, "a path was published without gains")
        type(self).gains_srv = rospy.Service("/background_map/compute_gains", ComputeGains, self.compute_gains)
        res = plan_once()
        self.assertTrue(res.success, res.message)
        self.assertTrue(self.wait_for(lambda: len(self.paths) > n_paths, 10.0), "no path once the service returned")
        self.assert_safe(self.paths[-1][1])


    def test_2b_a_call_without_an_answer_is_made_once_more(self):
        """A compute_gains call that comes back without an answer is made once
        more at once, and the iteration plans as if nothing had happened (a
        deterministic run whose call lost its answer went another way). Two
        calls in a row without an answer fail the iteration: once more, not
        more."""
        plan_once = rospy.ServiceProxy("/planner/plan_once", PlanOnce)
        with self.lock:
            type(self).fail_gains = 1
        n_paths = len(self.paths)
        res = plan_once()
        self.assertTrue(res.success, res.message)
        self.assertNotIn("gain evaluation failed", res.message)
        self.assertTrue(self.wait_for(lambda: len(self.paths) > n_paths, 10.0), "no path after the retried call")
        self.assert_safe(self.paths[-1][1])
        with self.lock:
            self.assertEqual(self.fail_gains, 0, "the call that failed was not made again")
            type(self).fail_gains = 2
            calls0 = self.gains_calls
        n_paths = len(self.paths)
        res = plan_once()
        self.assertFalse(res.success, res.message)
        self.assertIn("gain evaluation failed: service background_map/compute_gains failed", res.message)
        time.sleep(0.5)
        self.assertEqual(len(self.paths), n_paths, "a path was published without gains")
        with self.lock:
            self.assertEqual(self.fail_gains, 0)
            self.assertEqual(self.gains_calls - calls0, 2, "the failed call was made other than twice")

    def test_3_start_in_unknown_space_escapes(self):
        start = (4.1, 1.0, 1.0)
        self.move_to(start)
        time.sleep(1.0)  # the new static transform reaches the planner
        n_paths = len(self.paths)
        res = rospy.ServiceProxy("/planner/plan_once", PlanOnce)()
        self.assertTrue(res.success, res.message)
        self.assertTrue(self.wait_for(lambda: len(self.paths) > n_paths, 10.0))
        path = self.paths[-1][1]
        self.assertGreaterEqual(len(path.poses), 2)
        self.assert_safe(path, start=start, escaped=True)
        p1 = path.poses[1].pose.position
        self.assertLessEqual(p1.x, 4.0 - CLEARANCE + 1e-3, "the escape does not reach known free space")
        self.assertLess(math.dist(start, (p1.x, p1.y, p1.z)), 1.0)

    def test_3a_malformed_frontier_clouds_are_dropped(self):
        """A frontier cloud with point_step 0 (an iterator never advances) or with
        data that is not row_step x height bytes (an iterator reads past the
        end) is dropped as bad_frontiers; the planner keeps answering and
        plans from the last good cloud."""
        drops = {}
        sub = rospy.Subscriber("/dropped_input", DropCounts,
                               lambda m: drops.update(dict(zip(m.reasons, m.counts))) if m.node == "/planner" else None)
        good = cloud(FRONTIER_POINTS)
        zero_step = cloud([(3.95, 1.0, 1.0)])
        zero_step.point_step, zero_step.row_step = 0, 0
        long_data = cloud([(3.95, 1.0, 1.0)])
        long_data.point_step, long_data.row_step = 12, 12
        long_data.data = bytes(13)
        try:
            for n, bad in enumerate((zero_step, long_data), start=1):
                self.frontier_pub.publish(bad)
                self.assertTrue(self.wait_for(lambda: drops.get("bad_frontiers", 0) >= n, 10.0), drops)
                res = rospy.ServiceProxy("/planner/plan_once", PlanOnce)()  # answers: not hung
                self.assertTrue(res.success, res.message)
        finally:
            self.frontier_pub.publish(good)
            sub.unregister()

    def test_3b_a_restarted_map_is_resynced(self):
        """background_map restarted: its updates count from 1 again. An update
        below the replica's sequence is not ignored as stale (its blocks would
        be merged onto the old map) but triggers a get_map resync."""
        self.map_pub.publish(blocks_msg(self.grid, 100, True))
        time.sleep(1.0)
        with self.lock:
            before = self.get_map_calls
        self.map_pub.publish(blocks_msg(self.grid, 1, False))
        self.assertTrue(self.wait_for(lambda: self.get_map_calls > before, 10.0),
                        "no get_map resync after a sequence restarting at 1")

    def test_4_start_in_occupied_space_is_reported_until_termination(self):
        start = (2.1, 1.0, 1.0)  # inside the wall
        self.move_to(start)
        time.sleep(1.0)
        n_paths = len(self.paths)
        res = rospy.ServiceProxy("/planner/plan_once", PlanOnce)()
        self.assertFalse(res.success)
        self.assertTrue(res.message.startswith("the current position is not in free space and no escape was found"),
                        res.message)
        # Not executing a path any more: the planner retries on its own until it gives up.
        self.assertTrue(self.wait_for(
            lambda: any(s.state == ExplorationStatus.STATE_FINISHED for s in self.status), 60.0),
            [s.message for s in self.status[-5:]])
        fin = [s for s in self.status if s.state == ExplorationStatus.STATE_FINISHED][0]
        self.assertEqual(fin.termination_reason, "no_reachable_candidate")
        final = {s.iteration: s for s in self.status  # the last report of each iteration
                 if s.state != ExplorationStatus.STATE_PLANNING and not s.message.startswith("waiting")}
        for it in range(fin.iteration - MAX_FAILED + 1, fin.iteration + 1):
            self.assertIn(it, final)
            self.assertIn("not in free space", final[it].message)
            self.assertEqual(final[it].candidates_reachable, 0)
        time.sleep(0.5)
        self.assertEqual(len(self.paths), n_paths, "a path was published from inside the wall")


if __name__ == "__main__":
    import rostest
    rospy.init_node("test_planner_bad_input")
    rostest.rosrun(PKG, "planner_bad_input", PlannerBadInputTest, sys.argv)

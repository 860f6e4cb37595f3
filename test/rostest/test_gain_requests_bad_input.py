#!/usr/bin/env python3
"""rostest: oversized service requests are refused, naming the limit, and frames go on
(see gain_requests_bad_input.test)."""
import os
import sys
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import Point
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import CameraInfo, Image

from semantic_exploration.msg import DropCounts, FrameIntegrated, MatchedDetections
from semantic_exploration.srv import ComputeGains, ComputeGainsRequest, GetHistoryMasks, GetHistoryMasksRequest, \
    RenderInstances, RenderInstancesRequest

# test_object_map_bad_input.py lies beside this file's real path (a catkin devel-space relay runs this file from elsewhere).
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from test_object_map_bad_input import camera_info, image, start_camera_broadcast  # noqa: E402

PKG = "semantic_exploration"
W, H = 320, 240
MAPS = ("background_map", "object_map")


class TooLargeRequests(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("gain_requests_bad_input_test")
        cls.lock = threading.Lock()
        cls.done, cls.drops, cls.log = {}, {}, []
        cls.tf = tf2_ros.TransformBroadcaster()
        cls.pub_info = rospy.Publisher("/camera/camera_info", CameraInfo, queue_size=10, latch=True)
        cls.pub_depth = rospy.Publisher("/camera/depth/image_raw", Image, queue_size=10)
        cls.pub_rgb = rospy.Publisher("/camera/rgb/image_raw", Image, queue_size=10)
        cls.pub_matched = rospy.Publisher("/matched_detections", MatchedDetections, queue_size=10)

        def on_done(m):
            with cls.lock:
                cls.done.setdefault(m.node, {})[m.header.stamp.to_nsec()] = m

        def on_drops(m):
            with cls.lock:
                cls.drops[m.node.lstrip("/")] = dict(zip(m.reasons, m.counts))

        def on_log(m):
            if m.level >= Log.WARN:
                with cls.lock:
                    cls.log.append((m.name.lstrip("/"), m.msg))

        rospy.Subscriber("/frame_integrated", FrameIntegrated, on_done, queue_size=50)
        rospy.Subscriber("/dropped_input", DropCounts, on_drops, queue_size=10)
        rospy.Subscriber("/rosout", Log, on_log, queue_size=100)
        cls.stop = False

        cls.camera_xyz = (0.0, 0.0, 1.0)  # looking along world +x
        start_camera_broadcast(cls)
        cls.pub_info.publish(camera_info(W, H))
        end = time.monotonic() + 30
        while time.monotonic() < end and cls.pub_depth.get_num_connections() < 3:
            time.sleep(0.1)
        for s in ("/background_map/compute_gains", "/object_map/compute_gains", "/object_map/render_instances",
                  "/depth_history/get_masks"):
            rospy.wait_for_service(s, timeout=30)
        time.sleep(1.0)

    @classmethod
    def tearDownClass(cls):
        cls.stop = True

    def send_frame(self):
        """One frame (a wall at 2 m); True if background_map and object_map both report it integrated."""
        stamp = rospy.Time.now() - rospy.Duration(0.05)
        depth = np.full((H, W), 2.0, np.float32)
        matched = MatchedDetections()
        matched.header.stamp, matched.header.frame_id = stamp, "camera"
        matched.instance_image = image(np.zeros((H, W), np.uint16), "16UC1", stamp)
        self.pub_depth.publish(image(depth, "32FC1", stamp))
        self.pub_rgb.publish(image(np.full((H, W, 3), 90, np.uint8), "rgb8", stamp))
        self.pub_matched.publish(matched)
        key = stamp.to_nsec()
        end = time.monotonic() + 10
        while time.monotonic() < end:
            with self.lock:
                got = [self.done.get(n, {}).get(key) for n in MAPS]
            if all(got):
                return all(g.integrated for g in got)
            time.sleep(0.02)
        return False

    def refused(self, service, srv_type, request):
        """Calls service with request; True if it was refused (a ServiceException)."""
        try:
            rospy.ServiceProxy(service, srv_type)(request)
        except rospy.ServiceException:
            return True
        return False

    def drops_of(self, node, reason, expected):
        """node's count of `reason` once it reached `expected` (or after 3 s)."""
        end = time.monotonic() + 3
        while True:
            with self.lock:
                n = self.drops.get(node, {}).get(reason, 0)
            if n >= expected or time.monotonic() > end:
                return n
            time.sleep(0.05)

    def logged(self, node, text):
        end = time.monotonic() + 3
        while time.monotonic() < end:
            with self.lock:
                if any(n == node and text in m for n, m in self.log):
                    return True
            time.sleep(0.05)
        return False

    def gains_request(self, n_positions, w, h):
        req = ComputeGainsRequest()
        req.positions = [Point(0.0, 0.0, 1.0) for _ in range(n_positions)]
        req.width, req.height = w, h
        return req

    def test_too_large_requests_are_refused_and_frames_go_on(self):
        self.assertTrue(self.send_frame(), "the first frame was not integrated")
        expected = {"background_map": 0, "object_map": 0, "depth_history": 0}
        for node in MAPS:
            service = "/%s/compute_gains" % node
            # 20000 x 20000 px per image: 4e8 rays (the limit is 360 x 180 = 64800 px).
            self.assertTrue(self.refused(service, ComputeGains, self.gains_request(1, 20000, 20000)))
            expected[node] += 1
            self.assertEqual(self.drops_of(node, "request_too_large", expected[node]), expected[node])
            self.assertTrue(self.logged(node, "20000 x 20000 px per image is over the limit of 64800 px "
                                              "(SphericalGrid::kMaxPixels)"))
            self.assertTrue(self.send_frame(), "no frame integrated after %s refused 20000 x 20000" % node)
            # 2000 positions (the limit is 1024 per request).
            # (The log names each limit too, but throttled per reason: test_core_spherical_grid checks the texts.)
            self.assertTrue(self.refused(service, ComputeGains, self.gains_request(2000, 36, 10)))
            expected[node] += 1
            # 1000 positions x 360 px = 360000 rays (the limit is 262144).
            self.assertTrue(self.refused(service, ComputeGains, self.gains_request(1000, 36, 10)))
            expected[node] += 1
            self.assertEqual(self.drops_of(node, "request_too_large", expected[node]), expected[node])
            # A request of the planner's size is still answered, an image per position.
            resp = rospy.ServiceProxy(service, ComputeGains)(self.gains_request(20, 36, 10))
            self.assertEqual(len(resp.distance_gain), 20)
            self.assertEqual((resp.distance_gain[0].width, resp.distance_gain[0].height), (36, 10))

        # render_instances with a 20000 x 20000 camera (the cap is 8192 px a side).
        req = RenderInstancesRequest()
        req.pose.position.z = 1.0
        req.pose.orientation.x, req.pose.orientation.y, req.pose.orientation.z, req.pose.orientation.w = \
            -0.5, 0.5, -0.5, 0.5
        req.camera_info = camera_info(20000, 20000)
        self.assertTrue(self.refused("/object_map/render_instances", RenderInstances, req))
        expected["object_map"] += 1
        n = expected["object_map"]
        self.assertEqual(self.drops_of("object_map", "request_too_large", n), n)
        req.camera_info = camera_info(W, H)
        self.assertEqual(rospy.ServiceProxy("/object_map/render_instances", RenderInstances)(req).object_ids.width, W)

        # get_masks for 2000 positions.
        masks = GetHistoryMasksRequest()
        masks.positions = [Point(0.0, 0.0, 1.0) for _ in range(2000)]
        masks.width, masks.height = 36, 10
        self.assertTrue(self.refused("/depth_history/get_masks", GetHistoryMasks, masks))
        self.assertEqual(self.drops_of("depth_history", "request_too_large", 1), 1)
        self.assertTrue(self.send_frame(), "no frame integrated after the refused requests")


if __name__ == "__main__":
    rostest.rosrun(PKG, "gain_requests_bad_input", TooLargeRequests)

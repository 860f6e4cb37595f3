#!/usr/bin/env python3
"""rostest: bad camera_info to instance_matching and depth_history (see camera_info_bad_input.test)."""
import os
import sys
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import CameraInfo, Image

from semantic_exploration.msg import Detection, Detections, DropCounts, FrameIntegrated, MatchedDetections

# test_object_map_bad_input.py lies beside this file's real path (a catkin devel-space relay runs this file from elsewhere).
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from test_object_map_bad_input import camera_info, image, start_camera_broadcast  # noqa: E402


PKG = "semantic_exploration"
W, H = 320, 240
CHAIR = 1  # class id of "chair" in config/semantic.yaml
NODES = ("/instance_matching", "/depth_history")


class BadCameraInfo(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("camera_info_bad_input_test")
        cls.lock = threading.Lock()
        cls.matched, cls.done, cls.drops, cls.warnings = {}, {}, {}, []
        cls.tf = tf2_ros.TransformBroadcaster()
        cls.pub_info = rospy.Publisher("/camera/camera_info", CameraInfo, queue_size=10)
        cls.pub_depth = rospy.Publisher("/camera/depth/image_raw", Image, queue_size=10)
        cls.pub_det = rospy.Publisher("/detections", Detections, queue_size=10)

        def on_matched(m):
            with cls.lock:
                cls.matched[m.header.stamp.to_nsec()] = m

        def on_done(m):
            if m.node == "depth_history":
                with cls.lock:
                    cls.done[m.header.stamp.to_nsec()] = m

        def on_drops(m):
            with cls.lock:
                cls.drops[m.node] = dict(zip(m.reasons, m.counts))

        def on_log(m):
            if m.level == Log.WARN and "distortion" in m.msg:
                with cls.lock:
                    cls.warnings.append((m.name, m.msg))

        rospy.Subscriber("/matched_detections", MatchedDetections, on_matched, queue_size=10)
        rospy.Subscriber("/frame_integrated", FrameIntegrated, on_done, queue_size=10)
        rospy.Subscriber("/dropped_input", DropCounts, on_drops, queue_size=10)
        rospy.Subscriber("/rosout", Log, on_log, queue_size=100)
        cls.stop = False

        cls.camera_xyz = (0.0, 0.0, 1.0)  # looking along world +x
        start_camera_broadcast(cls)
        end = time.monotonic() + 30
        while time.monotonic() < end and not (cls.pub_depth.get_num_connections() >= 2 and
                                              cls.pub_det.get_num_connections() >= 1 and
                                              cls.pub_info.get_num_connections() >= 2):
            time.sleep(0.1)
        time.sleep(1.0)

    @classmethod
    def tearDownClass(cls):
        cls.stop = True

    def send_info(self, info):
        self.pub_info.publish(info)
        time.sleep(0.3)  # camera_info and frames travel on different connections

    def send_frame(self):
        """One depth frame (a wall at 2 m, a hole of invalid depth) with a chair detection;
        returns (matched_detections, depth_history's frame_integrated) for it (None if not seen)."""
        stamp = rospy.Time.now() - rospy.Duration(0.05)
        depth = np.full((H, W), 2.0, np.float32)
        depth[:, :40] = 0.0  # invalid: depth_history records these directions
        inst = np.zeros((H, W), np.uint16)
        inst[80:160, 120:200] = 1
        det = Detections()
        det.header.stamp, det.header.frame_id = stamp, "camera"
        det.instance_image = image(inst, "16UC1", stamp)
        d = Detection()
        d.instance_id, d.class_id, d.class_name, d.confidence = 1, CHAIR, "chair", 0.9
        det.detections.append(d)
        self.pub_depth.publish(image(depth, "32FC1", stamp))
        self.pub_det.publish(det)
        key = stamp.to_nsec()
        end = time.monotonic() + 10
        while time.monotonic() < end:
            with self.lock:
                if key in self.matched and key in self.done:
                    break
            time.sleep(0.02)
        with self.lock:
            return self.matched.get(key), self.done.get(key)

    def drop_count(self, node, reason):
        with self.lock:
            return self.drops.get(node, {}).get(reason, 0)

    def wait_drops(self, reason, at_least):
        end = time.monotonic() + 5
        while time.monotonic() < end and any(self.drop_count(n, reason) < at_least for n in NODES):
            time.sleep(0.05)
        return {n: self.drop_count(n, reason) for n in NODES}

    def test_bad_camera_info_is_dropped_and_nodes_keep_running(self):
        # 1. 100000 x 100000 px with a valid K: over the size cap, refused by both nodes.
        self.send_info(camera_info(100000, 100000))
        matched, done = self.send_frame()
        self.assertIsNotNone(matched, "instance_matching answered no frame after the oversized camera_info")
        self.assertIsNotNone(done, "depth_history answered no frame after the oversized camera_info")
        self.assertTrue(done.integrated)
        self.assertEqual((matched.instance_image.width, matched.instance_image.height), (W, H))
        self.assertEqual(self.wait_drops("bad_camera_info", 1), {n: 1 for n in NODES})

        # 2. Within the cap but not the depth frames' size (640 x 480 vs 320 x 240): refused too.
        self.send_info(camera_info(640, 480))
        matched, done = self.send_frame()
        self.assertIsNotNone(matched)
        self.assertTrue(done is not None and done.integrated)
        self.assertEqual(self.wait_drops("bad_camera_info", 2), {n: 2 for n in NODES})
        with self.lock:
            self.assertNotIn("size_mismatch", self.drops.get("/instance_matching", {}))

        # 3. The right size with lens distortion: used (K only), and one warning per node names what is ignored.
        for _ in range(3):
            self.send_info(camera_info(W, H, D=(0.1, -0.25, 0.001, 0.0, 0.05), model="plumb_bob"))
        matched, done = self.send_frame()
        self.assertTrue(done is not None and done.integrated)
        time.sleep(1.0)
        with self.lock:
            warnings = list(self.warnings)
        for node in NODES:
            mine = [m for n, m in warnings if n == node]
            self.assertEqual(len(mine), 1, "%s: distortion warnings %s" % (node, mine))
            self.assertIn("plumb_bob", mine[0])
            self.assertIn("0.1, -0.25, 0.001, 0, 0.05", mine[0])
            self.assertIn("ignored", mine[0])
        self.assertEqual(self.wait_drops("bad_camera_info", 2), {n: 2 for n in NODES})


if __name__ == "__main__":
    rostest.rosrun(PKG, "camera_info_bad_input", BadCameraInfo)

#!/usr/bin/env python3
"""rostest: bad input to instance_matching and object_map (see object_map_bad_input.test)."""
import math
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import CameraInfo, Image

from semantic_exploration.msg import Detection, Detections, DropCounts, FrameIntegrated, MatchedDetections, \
    ObjectArray

PKG = "semantic_exploration"
W, H = 320, 240
CHAIR = 1  # class id of "chair" in config/semantic.yaml


def image(arr, encoding, stamp):
    """arr as a sensor_msgs/Image in frame "camera". Shared by the camera-fed bad-input rostests."""
    m = Image()
    m.header.stamp = stamp
    m.header.frame_id = "camera"
    m.height, m.width = arr.shape[:2]
    m.encoding = encoding
    m.step = arr.strides[0]
    m.data = arr.tobytes()
    return m


def camera_info(w, h, D=(), model=""):
    """CameraInfo of a w x h camera, f = 262.5 px, centred, distortion D of `model`
    (none by default). Shared by the camera-fed bad-input rostests."""
    ci = CameraInfo()
    ci.header.frame_id = "camera"
    ci.width, ci.height = w, h
    ci.K = [262.5, 0.0, (w - 1) / 2.0, 0.0, 262.5, (h - 1) / 2.0, 0.0, 0.0, 1.0]
    ci.D = list(D)
    ci.distortion_model = model
    return ci



def start_camera_broadcast(owner):
    """Broadcasts tf world -> camera at 50 Hz on owner.tf until owner.stop:
    the camera at owner.camera_xyz (world, m) looking along world +x (optical
    frame: z forward = world x, x right = world -y, y down = world -z).
    Shared by the camera-fed bad-input rostests."""
    def broadcast():
        r = rospy.Rate(50)
        while not rospy.is_shutdown() and not owner.stop:
            t = TransformStamped()
            t.header.stamp = rospy.Time.now()
            t.header.frame_id, t.child_frame_id = "world", "camera"
            tr = t.transform.translation
            tr.x, tr.y, tr.z = owner.camera_xyz
            q = t.transform.rotation
            q.x, q.y, q.z, q.w = -0.5, 0.5, -0.5, 0.5
            owner.tf.sendTransform(t)
            r.sleep()

    thread = threading.Thread(target=broadcast, daemon=True)
    thread.start()
    return thread


class BadInput(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("object_map_bad_input_test")
        cls.lock = threading.Lock()
        cls.matched, cls.done, cls.matching_done, cls.objects = {}, {}, {}, None
        cls.tf = tf2_ros.TransformBroadcaster()
        cls.pub_depth = rospy.Publisher("/camera/depth/image_raw", Image, queue_size=10)
        cls.pub_rgb = rospy.Publisher("/camera/rgb/image_raw", Image, queue_size=10)
        cls.pub_det = rospy.Publisher("/detections", Detections, queue_size=10)

        def on_matched(m):
            with cls.lock:
                cls.matched[m.header.stamp.to_nsec()] = m

        def on_done(m):
            with cls.lock:
                if m.node == "object_map":
                    cls.done[m.header.stamp.to_nsec()] = m
                elif m.node == "instance_matching":  # its reports feed the run's CPU budget
                    cls.matching_done[m.header.stamp.to_nsec()] = m

        def on_objects(m):
            with cls.lock:
                cls.objects = m

        rospy.Subscriber("/matched_detections", MatchedDetections, on_matched, queue_size=10)
        rospy.Subscriber("/frame_integrated", FrameIntegrated, on_done, queue_size=10)
        rospy.Subscriber("/object_map/objects", ObjectArray, on_objects, queue_size=10)
        cls.drops = {}

        def on_drops(m):
            with cls.lock:
                cls.drops[m.node.lstrip("/")] = dict(zip(m.reasons, m.counts))

        rospy.Subscriber("/dropped_input", DropCounts, on_drops, queue_size=10)
        # Camera 2 m in front of a wall (depth 2 m everywhere), looking along world +x.
        cls.stop = False
        cls.camera_xyz = (0.0, 0.0, 1.0)  # where the broadcast puts the camera, world, m

        cls.thread = start_camera_broadcast(cls)
        for topic in ("/camera/depth/image_raw", "/detections"):
            end = time.monotonic() + 30
            while time.monotonic() < end:
                pub = cls.pub_depth if topic.startswith("/camera") else cls.pub_det
                if pub.get_num_connections() > 0:
                    break
                time.sleep(0.1)
        time.sleep(1.0)

    @classmethod
    def tearDownClass(cls):
        cls.stop = True

    def send(self, instances, detections, stamp=None):
        """Publishes one frame; returns (matched, frame_integrated) for it (None if not seen)."""
        stamp = stamp or rospy.Time.now() - rospy.Duration(0.05)
        depth = np.full((H, W), 2.0, np.float32)
        depth[80:160, 120:200] = 1.5  # a "chair" in front of the wall
        rgb = np.full((H, W, 3), 90, np.uint8)
        det = Detections()
        det.header.stamp = stamp
        det.header.frame_id = "camera"
        det.instance_image = image(instances.astype(np.uint16), "16UC1", stamp)
        for det_ in detections:
            iid, cid = det_[:2]
            name = det_[2] if len(det_) > 2 else ("chair" if cid == CHAIR else "?")
            d = Detection()
            d.instance_id, d.class_id, d.class_name, d.confidence = iid, cid, name, 0.9
            det.detections.append(d)
        self.pub_depth.publish(image(depth, "32FC1", stamp))
        self.pub_rgb.publish(image(rgb, "rgb8", stamp))
        self.pub_det.publish(det)
        key = stamp.to_nsec()
        end = time.monotonic() + 10
        while time.monotonic() < end:
            with self.lock:
                if key in self.matched and key in self.done:
                    return self.matched[key], self.done[key]
            time.sleep(0.02)
        with self.lock:
            return self.matched.get(key), self.done.get(key)

    def matching_report(self, stamp):
        """instance_matching's frame_integrated for stamp (None if none came within 5 s)."""
        end = time.monotonic() + 5
        while time.monotonic() < end:
            with self.lock:
                if stamp.to_nsec() in self.matching_done:
                    return self.matching_done[stamp.to_nsec()]
            time.sleep(0.02)
        return None

    def chair_mask(self):
        m = np.zeros((H, W), np.uint16)
        m[80:160, 120:200] = 1
        return m

    def test_bad_input_is_dropped_and_nodes_keep_running(self):
        # 1. Instance image of another size than depth: no detections go on, the frame is still handled.
        matched, done = self.send(np.ones((100, 100), np.uint16), [(1, CHAIR)])
        self.assertIsNotNone(matched)
        self.assertEqual(len(matched.detections), 0)
        self.assertIsNotNone(done)
        mine = self.matching_report(matched.header.stamp)  # instance_matching reports the frame too, as not matched
        self.assertIsNotNone(mine, "instance_matching reported no frame_integrated")
        self.assertFalse(mine.integrated)

        # 2. Unknown class id: that detection is left out and its pixels cleared.
        matched, done = self.send(self.chair_mask(), [(1, 999)])
        self.assertEqual(len(matched.detections), 0)
        self.assertFalse(np.frombuffer(matched.instance_image.data, np.uint16).any())
        self.assertTrue(done.integrated)

        # 3. A mask whose instance id is not listed is ignored; the listed chair becomes object 1.
        inst = self.chair_mask()
        inst[10:40, 10:40] = 7
        matched, done = self.send(inst, [(1, CHAIR)])
        self.assertEqual(len(matched.detections), 1)
        self.assertEqual(matched.detections[0].object_id, 0)
        self.assertEqual(matched.detections[0].mask_pixels, 80 * 80)
        img = np.frombuffer(matched.instance_image.data, np.uint16)
        self.assertFalse((img == 7).any())
        self.assertTrue(done.integrated)
        mine = self.matching_report(matched.header.stamp)
        self.assertTrue(mine is not None and mine.integrated, "instance_matching's report of a matched frame")

        # 4. Stale tf (a stamp long before any transform): dropped, reported as not integrated.
        matched, done = self.send(self.chair_mask(), [(1, CHAIR)], stamp=rospy.Time.now() - rospy.Duration(100.0))
        self.assertIsNotNone(done)
        self.assertFalse(done.integrated)

        # 5. The nodes still work: the same chair is matched to object 1, not duplicated.
        for _ in range(3):
            matched, done = self.send(self.chair_mask(), [(1, CHAIR)])
            self.assertTrue(done.integrated)
        self.assertEqual(matched.detections[0].object_id, 1)
        self.assertGreater(matched.detections[0].iou, 0.8)
        time.sleep(0.5)
        with self.lock:
            objects = self.objects
        self.assertEqual([o.id for o in objects.objects], [1])
        self.assertAlmostEqual(objects.objects[0].centroid.x, 1.5, delta=0.03)
        self.assertAlmostEqual(objects.objects[0].centroid.z, 1.0, delta=0.1)

    def test_camera_far_from_the_origin_is_refused(self):
        # UTM-like coordinates: the object maps cannot hold surfaces there (20-bit voxel keys, float positions).
        type(self).camera_xyz = (5e5, 5e6, 1.0)
        time.sleep(0.5)  # the frame's pose must not be interpolated from the origin pose
        matched, done = self.send(self.chair_mask(), [(1, CHAIR)])
        type(self).camera_xyz = (0.0, 0.0, 1.0)
        self.assertIsNotNone(matched, "instance_matching answered no frame from (5e5, 5e6, 1)")
        self.assertEqual(len(matched.detections), 0)
        self.assertIsNotNone(done, "object_map answered no frame from (5e5, 5e6, 1)")
        self.assertFalse(done.integrated)
        end = time.monotonic() + 3
        while time.monotonic() < end:
            with self.lock:
                counts = {n: self.drops.get(n, {}).get("out_of_bounds", 0) for n in ("instance_matching", "object_map")}
            if all(counts.values()):
                break
            time.sleep(0.05)
        self.assertEqual(counts, {"instance_matching": 1, "object_map": 1})
        time.sleep(0.5)
        with self.lock:
            objects = self.objects
        # No object was made from that frame (test methods run in name order: the chair of the first is there).
        self.assertTrue(objects is None or all(abs(o.centroid.x) < 100 for o in objects.objects))

    def test_class_name_must_match_class_id(self):
        # Class id 1 is "chair" here; a detector with another class table names it "table".
        matched, done = self.send(self.chair_mask(), [(1, CHAIR, "table")])
        self.assertIsNotNone(matched)
        self.assertEqual(len(matched.detections), 0)
        self.assertFalse(np.frombuffer(matched.instance_image.data, np.uint16).any())  # its pixels cleared
        self.assertTrue(done.integrated)
        end = time.monotonic() + 3
        while time.monotonic() < end:
            with self.lock:
                n = self.drops.get("instance_matching", {}).get("class_mismatch", 0)
            if n:
                break
            time.sleep(0.05)
        self.assertEqual(n, 1)
        # An empty class_name is not checked (the id alone names the class).
        matched, done = self.send(self.chair_mask(), [(1, CHAIR, "")])
        self.assertEqual(len(matched.detections), 1)


if __name__ == "__main__":
    rostest.rosrun(PKG, "object_map_bad_input", BadInput)

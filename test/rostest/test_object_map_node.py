#!/usr/bin/env python3
"""rostest for instance_matching + object_map on the example scene (see object_map.test).

Flies a loop round the table twice. Checks: exactly one chair object per
ground-truth chair (a chair seen again is matched, not duplicated), each
centroid within 10 cm (horizontally) of its chair's box centre, detections
that the detector missed (the chair was visible in the ground-truth instance
image but not detected) did not stop the object from being kept up to date,
and ~save writes a PLY per object plus objects.json.
"""
import json
import math
import os
import tempfile
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
from sensor_msgs.msg import Image

from semantic_exploration.msg import Detections, FrameIntegrated, MatchedDetections, ObjectArray
from semantic_exploration.srv import SaveMap

PKG = "semantic_exploration"
HERE = os.path.dirname(os.path.abspath(__file__))


def chairs_from_house(path):
    """Box centres of the 'chair' objects of a .house file."""
    cats, out = {}, []
    with open(path) as f:
        for line in f:
            t = line.split()
            if t and t[0] == "C":
                cats[int(t[1])] = t[3]
    with open(path) as f:
        for line in f:
            t = line.split()
            if t and t[0] == "O" and cats.get(int(t[3])) == "chair":
                out.append(np.array([float(t[4]), float(t[5]), float(t[6])]))
    return out


def find_house():
    for cand in (os.path.join(HERE, "..", "data", "example.house"),
                 os.path.join(HERE, "..", "..", "share", PKG, "test", "data", "example.house")):
        if os.path.isfile(cand):
            return cand
    import rospkg
    return os.path.join(rospkg.RosPack().get_path(PKG), "test", "data", "example.house")


class ObjectMapTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("object_map_test")
        cls.lock = threading.Lock()
        cls.objects = None
        cls.goals = []
        cls.frames = {"integrated": 0, "dropped": 0}
        cls.visible = {}   # ground-truth instance id -> frames it covers >= 400 px
        cls.detected = {}  # instance id -> frames it was detected in
        cls.matched = []

        def on_objects(m):
            with cls.lock:
                cls.objects = m

        def on_goal(m):
            with cls.lock:
                cls.goals.append(m)

        def on_done(m):
            if m.node == "object_map":
                with cls.lock:
                    cls.frames["integrated" if m.integrated else "dropped"] += 1

        def on_gt(m):
            ids = np.frombuffer(m.data, np.uint16).reshape(m.height, m.width)
            u, n = np.unique(ids[ids > 0], return_counts=True)
            with cls.lock:
                for i, c in zip(u, n):
                    if c >= 400:
                        cls.visible[int(i)] = cls.visible.get(int(i), 0) + 1

        def on_det(m):
            with cls.lock:
                for d in m.detections:
                    cls.detected[d.instance_id] = cls.detected.get(d.instance_id, 0) + 1

        def on_matched(m):
            with cls.lock:
                cls.matched.append(m)

        rospy.Subscriber("/object_map/objects", ObjectArray, on_objects, queue_size=10)
        rospy.Subscriber("/mav/goal_reached", PoseStamped, on_goal, queue_size=10)
        rospy.Subscriber("/frame_integrated", FrameIntegrated, on_done, queue_size=100)
        rospy.Subscriber("/camera/instance_gt", Image, on_gt, queue_size=100)
        rospy.Subscriber("/detections", Detections, on_det, queue_size=100)
        rospy.Subscriber("/matched_detections", MatchedDetections, on_matched, queue_size=100)
        cls.path_pub = rospy.Publisher("/planner/path", Path, queue_size=1, latch=True)
        rospy.wait_for_service("/object_map/save", timeout=60)

    @classmethod
    def fly(cls, waypoints, timeout=180.0):
        n0 = len(cls.goals)
        m = Path()
        m.header.frame_id = "world"
        m.header.stamp = rospy.Time.now()
        for x, y, z, yaw in waypoints:
            p = PoseStamped()
            p.header.frame_id = "world"
            p.pose.position.x, p.pose.position.y, p.pose.position.z = x, y, z
            p.pose.orientation.z, p.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
            m.poses.append(p)
        cls.path_pub.publish(m)
        end = time.monotonic() + timeout
        while time.monotonic() < end and not rospy.is_shutdown():
            with cls.lock:
                if len(cls.goals) > n0:
                    return True
            time.sleep(0.05)
        return False

    def test_loop_round_the_table(self):
        table = (2.15, 1.76)

        def face(x, y):
            return math.atan2(table[1] - y, table[0] - x)

        loop = [(x, y, 1.4, face(x, y)) for x, y in
                ((0.6, 0.9), (1.6, 0.8), (3.1, 0.9), (3.1, 2.6), (2.0, 2.6), (0.6, 2.6), (0.6, 1.6))]
        self.assertTrue(self.fly(loop), "first loop not completed")
        with self.lock:
            first = self.objects
        self.assertTrue(self.fly(loop), "second loop not completed")
        time.sleep(2.0)
        with self.lock:
            objects = self.objects
            frames = dict(self.frames)
            visible, detected = dict(self.visible), dict(self.detected)
        self.assertIsNotNone(objects)
        rospy.loginfo("object_map test: %s frames; objects: %s", frames,
                      [(o.id, o.class_name, round(o.centroid.x, 3), round(o.centroid.y, 3), o.voxel_count,
                        o.detection_count) for o in objects.objects])
        self.assertGreater(frames["integrated"], 50)

        truth = chairs_from_house(find_house())
        self.assertEqual(len(truth), 4)
        chairs = [o for o in objects.objects if o.class_name == "chair"]
        # One object per chair: seen again on the second loop, each chair is matched, not duplicated.
        self.assertEqual(len(chairs), len(truth), "chair objects: %s" % [(o.id, o.voxel_count) for o in chairs])
        self.assertEqual(len(first.objects), len(chairs))
        used = set()
        for t in truth:
            d = [math.hypot(o.centroid.x - t[0], o.centroid.y - t[1]) for o in chairs]
            i = int(np.argmin(d))
            self.assertLess(d[i], 0.10, "chair at (%.2f, %.2f): nearest object centroid %.3f m away" % (t[0], t[1], d[i]))
            self.assertNotIn(i, used)
            used.add(i)
            self.assertGreater(chairs[i].voxel_count, 200)
            self.assertGreaterEqual(chairs[i].observed_fraction, 0.0)
        # The detector missed chairs that were in view; the objects still exist and kept growing.
        missed = sum(max(0, visible.get(i, 0) - detected.get(i, 0)) for i in visible)
        self.assertGreater(missed, 0, "the detector never missed a visible chair; nothing was tested")
        for o in chairs:
            before = [p for p in first.objects if p.id == o.id][0]
            self.assertGreaterEqual(o.voxel_count, before.voxel_count * 0.9)

        d = tempfile.mkdtemp(prefix="semexp_object_map_test_")
        res = rospy.ServiceProxy("/object_map/save", SaveMap)(d)
        self.assertTrue(res.success, res.message)
        self.assertEqual(len(res.files), len(objects.objects) + 1)
        with open(os.path.join(d, "objects.json")) as f:
            doc = json.load(f)
        self.assertEqual(len(doc["objects"]), len(objects.objects))
        for p in res.files:
            self.assertTrue(os.path.getsize(p) > 0)


if __name__ == "__main__":
    rostest.rosrun(PKG, "object_map_sim", ObjectMapTest)

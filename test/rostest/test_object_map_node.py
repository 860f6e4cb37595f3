#!/usr/bin/env python3
"""rostest for instance_matching + object_map with the simulator (see object_map.test).

Scene: test/data/three_chairs_semantic.ply, a room with exactly three chairs
(A south-west, B at a table, C south-east), over 2 m apart. The MAV flies a
scripted path in legs (each leg ends when mav_sim reports goal_reached):

1. survey: A, B and C from several sides;
2. hidden: chair C is hidden from the detector (mav_sim ~hide_detections) while
   the MAV flies round to look at it from the west;
3. away: detections back on; the MAV turns west, C leaves the view;
4. back: the MAV flies north-east and looks at C again.

Checks, against known answers:
- exactly three chair objects at the end, the same ids as after the survey
  (no chair duplicated, none lost);
- hidden leg: C is in view (ground-truth instance image) but never detected,
  and its TSDF still gains data: ObjectInfo.undetected_count and weight_sum
  grow while detection_count stays put;
- C leaves the view for many frames and, seen again, its detections are
  matched to its object (object_id = C's id, never 0 = new);
- each object's centroid lies within 10 cm (3D) of its chair's ground truth.
  The map's centroid (ObjectInfo.centroid) is the mean of the object's surface
  voxel centres. The ground truth is the area-weighted centroid of the chair's
  mesh faces that a camera above the chairs can see: faces that point down
  (the seat's underside, the feet) are left out, as the MAV flies at 1.4 m,
  above every chair (top 0.86 m), and never sees them, so the map cannot hold
  them; counting them would pull the truth 1.2 cm down (1.5 cm in all) for a
  reason that is not a mapping error. The errors against the box centre (not a
  surface centroid: the backrest and seat pull the surface's centroid up and
  back) and against the all-faces centroid are logged too;
- the mesh topic carries, per object, a LINE_LIST box (the object's bbox) and
  a TEXT_VIEW_FACING label "chair #<id>";
- ~save writes a PLY per object plus objects.json.
"""
import json
import math
import os
import shutil
import tempfile
import threading
import time
import unittest

import numpy as np
import rospkg
import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
from sensor_msgs.msg import Image
from std_msgs.msg import UInt32MultiArray
from visualization_msgs.msg import Marker, MarkerArray

from semantic_exploration.msg import FrameIntegrated, MatchedDetections, ObjectArray
from semantic_exploration.sim.scene import load_scene
from semantic_exploration.srv import SaveMap

PKG = "semantic_exploration"
HERE = os.path.dirname(os.path.abspath(__file__))
VISIBLE_PX = 400  # a chair covering this many pixels of the ground-truth instance image is in view

SURVEY = [(0.6, 2.25, 1.4, -1.2), (2.0, 2.6, 1.4, -0.8), (2.0, 2.6, 1.4, 0.6), (4.2, 2.4, 1.4, 2.64),
          (4.6, 2.7, 1.4, -1.57)]
HIDDEN_LEG = (3.0, 1.2, 1.4, 0.0)   # C from the west
AWAY_LEG = (2.7, 1.5, 1.4, 3.0)     # facing west: C behind the camera
BACK_LEG = (5.2, 2.2, 1.4, -2.03)   # C from the north-east


def find_scene():
    for cand in (os.path.join(HERE, "..", "data", "three_chairs_semantic.ply"),
                 os.path.join(HERE, "..", "..", "share", PKG, "test", "data", "three_chairs_semantic.ply")):
        if os.path.isfile(cand):
            return cand
    return os.path.join(rospkg.RosPack().get_path(PKG), "test", "data", "three_chairs_semantic.ply")


def chair_truth(scene):
    """scene object id -> dict(box centre, all-faces centroid, seen-from-above centroid), m."""
    out = {}
    for oid, label in scene.objects.items():
        if label != "chair":
            continue
        tri = scene.vertices[scene.faces[scene.face_object == oid]]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area = 0.5 * np.linalg.norm(n, axis=1)
        centre = tri.mean(1)
        up_or_side = n[:, 2] >= -0.5 * np.linalg.norm(n, axis=1)  # not facing down
        v = tri.reshape(-1, 3)
        out[oid] = {"box": (v.min(0) + v.max(0)) / 2,
                    "all": (centre * area[:, None]).sum(0) / area.sum(),
                    "seen": (centre[up_or_side] * area[up_or_side, None]).sum(0) / area[up_or_side].sum()}
    return out


def image_array(m):
    return np.frombuffer(m.data, np.uint16).reshape(m.height, m.step // 2)[:, :m.width]


class ObjectMapTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("object_map_test")
        cls.scene = load_scene(find_scene())
        cls.truth = chair_truth(cls.scene)
        cls.lock = threading.Lock()
        cls.objects = None
        cls.goals = 0
        cls.integrated = {"yes": 0, "no": 0}
        cls.pending = {}   # stamp ns -> {"gt": array, "matched": msg} until both arrived
        cls.frames = {}    # stamp ns -> {chair id: (ground-truth pixels, [object ids of its matched detections])}
        cls.markers = {}   # (ns, id) -> Marker (the last ADD; DELETE removes it)

        def on_objects(m):
            with cls.lock:
                cls.objects = m

        def on_goal(_):
            with cls.lock:
                cls.goals += 1

        def on_done(m):
            if m.node == "object_map":
                with cls.lock:
                    cls.integrated["yes" if m.integrated else "no"] += 1

        def add(stamp, key, value):
            with cls.lock:
                p = cls.pending.setdefault(stamp.to_nsec(), {})
                p[key] = value
                if len(p) == 2:
                    del cls.pending[stamp.to_nsec()]
                    cls.frames[stamp.to_nsec()] = cls.frame_record(p["gt"], p["matched"])

        def on_markers(m):
            with cls.lock:
                for mk in m.markers:
                    if mk.action == Marker.ADD:
                        cls.markers[(mk.ns, mk.id)] = mk
                    elif mk.action == Marker.DELETE:
                        cls.markers.pop((mk.ns, mk.id), None)

        rospy.Subscriber("/object_map/objects", ObjectArray, on_objects, queue_size=10)
        rospy.Subscriber("/object_map/meshes", MarkerArray, on_markers, queue_size=10)
        rospy.Subscriber("/mav/goal_reached", PoseStamped, on_goal, queue_size=10)
        rospy.Subscriber("/frame_integrated", FrameIntegrated, on_done, queue_size=100)
        rospy.Subscriber("/camera/instance_gt", Image, lambda m: add(m.header.stamp, "gt", image_array(m).copy()),
                         queue_size=100)
        rospy.Subscriber("/matched_detections", MatchedDetections, lambda m: add(m.header.stamp, "matched", m),
                         queue_size=100)
        cls.path_pub = rospy.Publisher("/planner/path", Path, queue_size=1, latch=True)
        cls.hide_pub = rospy.Publisher("/mav_sim/hide_detections", UInt32MultiArray, queue_size=1, latch=True)
        rospy.wait_for_service("/object_map/save", timeout=60)

    @classmethod
    def frame_record(cls, gt, matched):
        inst = image_array(matched.instance_image)
        rec = {}
        for cid in cls.truth:
            on_chair = gt == cid
            ids = []
            for d in matched.detections:
                mask = inst == d.detection.instance_id
                if 2 * np.count_nonzero(mask & on_chair) > np.count_nonzero(mask):
                    ids.append(d.object_id)
            rec[cid] = (int(np.count_nonzero(on_chair)), ids)
        return rec

    @classmethod
    def fly(cls, waypoint, timeout=120.0):
        with cls.lock:
            n0 = cls.goals
        x, y, z, yaw = waypoint
        p = PoseStamped()
        p.header.frame_id = "world"
        p.pose.position.x, p.pose.position.y, p.pose.position.z = x, y, z
        p.pose.orientation.z, p.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        m = Path()
        m.header.frame_id = "world"
        m.header.stamp = rospy.Time.now()
        m.poses.append(p)
        cls.path_pub.publish(m)
        end = time.monotonic() + timeout
        while time.monotonic() < end and not rospy.is_shutdown():
            with cls.lock:
                if cls.goals > n0:
                    break
            time.sleep(0.05)
        else:
            return False
        time.sleep(1.0)  # hover: the last frames of the leg reach the map
        return True

    @classmethod
    def snapshot(cls):
        with cls.lock:
            return cls.objects

    def frames_between(self, a, b):
        """Frames with a.stamp < stamp <= b.stamp (ObjectArray stamps: the last integrated frame)."""
        lo, hi = a.header.stamp.to_nsec(), b.header.stamp.to_nsec()
        with self.lock:
            return [self.frames[t] for t in sorted(self.frames) if lo < t <= hi]

    def chairs_of(self, arr):
        return {o.id: o for o in arr.objects if o.class_name == "chair"}

    def test_scripted_flight_past_three_chairs(self):
        self.assertEqual(len(self.truth), 3)
        a_id, b_id, c_id = sorted(self.truth)
        for k, w in enumerate(SURVEY):
            self.assertTrue(self.fly(w), "survey leg %d not completed" % k)
        survey = self.snapshot()
        self.assertIsNotNone(survey)
        chairs = self.chairs_of(survey)
        self.assertEqual(len(chairs), 3, "chair objects after the survey: %s" % sorted(chairs))
        # Which object is which chair: the nearest centroid (the chairs are over 2 m apart).
        obj_of = {}
        for cid, t in self.truth.items():
            oid = min(chairs, key=lambda i: np.linalg.norm(np.array([chairs[i].centroid.x, chairs[i].centroid.y,
                                                                       chairs[i].centroid.z]) - t["seen"]))
            obj_of[cid] = oid
        self.assertEqual(len(set(obj_of.values())), 3, "two chairs map to one object: %s" % obj_of)
        c_obj = obj_of[c_id]

        # Hidden leg: C stays in view, the detector does not report it.
        self.hide_pub.publish(UInt32MultiArray(data=[c_id]))
        time.sleep(1.5)  # the request reaches mav_sim before the leg starts (the MAV hovers meanwhile)
        before = self.snapshot()
        self.assertTrue(self.fly(HIDDEN_LEG), "hidden leg not completed")
        after = self.snapshot()
        self.hide_pub.publish(UInt32MultiArray(data=[]))
        time.sleep(1.5)
        hidden = self.frames_between(before, after)
        in_view = [f for f in hidden if f[c_id][0] >= VISIBLE_PX]
        c0, c1 = self.chairs_of(before)[c_obj], self.chairs_of(after)[c_obj]
        rospy.loginfo("hidden leg: %d frames, C in view in %d; C undetected_count %d -> %d, weight_sum %.0f -> %.0f, "
                      "detection_count %d -> %d, surface voxels %d -> %d", len(hidden), len(in_view),
                      c0.undetected_count, c1.undetected_count, c0.weight_sum, c1.weight_sum, c0.detection_count,
                      c1.detection_count, c0.voxel_count, c1.voxel_count)
        self.assertGreaterEqual(len(in_view), 10, "C was not in view on the hidden leg; nothing was tested")
        self.assertEqual(sum(len(f[c_id][1]) for f in hidden), 0, "C was detected on the hidden leg")
        self.assertEqual(c1.detection_count, c0.detection_count)
        # In view but undetected, C was integrated (SDF and colour) in the frames that showed it.
        self.assertGreaterEqual(c1.undetected_count - c0.undetected_count, len(in_view) // 2)
        self.assertGreater(c1.weight_sum, c0.weight_sum)

        # Away: C leaves the view.
        self.assertTrue(self.fly(AWAY_LEG), "away leg not completed")
        away = self.snapshot()
        gone = [f for f in self.frames_between(after, away) if f[c_id][0] == 0]
        self.assertGreaterEqual(len(gone), 15, "C never left the view")
        # Back: C is seen again and matched to its object.
        self.assertTrue(self.fly(BACK_LEG), "back leg not completed")
        final = self.snapshot()
        back = [f for f in self.frames_between(away, final) if f[c_id][0] >= VISIBLE_PX]
        ids_back = [i for f in back for i in f[c_id][1]]
        rospy.loginfo("back leg: C in view in %d frames, its detections matched to %s", len(back), ids_back)
        self.assertGreaterEqual(len(back), 5, "C was not seen again")
        self.assertGreaterEqual(len(ids_back), 3, "C was not detected again")
        self.assertEqual(set(ids_back), {c_obj}, "C seen again was not matched to object %d" % c_obj)

        with self.lock:
            integrated = dict(self.integrated)
            frames = dict(self.frames)
        self.assertGreater(integrated["yes"], 100)
        # The random drops missed chairs in view too (besides the hidden leg).
        missed = sum(1 for f in frames.values() for cid in (a_id, b_id) if f[cid][0] >= VISIBLE_PX and not f[cid][1])
        self.assertGreater(missed, 0, "the detector never missed a visible chair")
        # Matched, not duplicated: the same three chair objects as after the survey, nothing else.
        chairs = self.chairs_of(final)
        self.assertEqual(sorted(chairs), sorted(obj_of.values()),
                         "objects: %s" % [(o.id, o.class_name, o.voxel_count) for o in final.objects])
        self.assertEqual(len(final.objects), 3)
        for cid, t in sorted(self.truth.items()):
            o = chairs[obj_of[cid]]
            c = np.array([o.centroid.x, o.centroid.y, o.centroid.z])
            err = {k: float(np.linalg.norm(c - v)) for k, v in t.items()}
            rospy.loginfo("chair %d -> object %d: centroid (%.3f, %.3f, %.3f), error %.3f m (seen-from-above "
                          "surface; box centre %.3f, all faces %.3f), error vector %s, %d surface voxels, "
                          "%d detections, %d undetected", cid, o.id, c[0], c[1], c[2], err["seen"], err["box"],
                          err["all"], np.round(c - t["seen"], 3).tolist(), o.voxel_count, o.detection_count,
                          o.undetected_count)
            self.assertLess(err["seen"], 0.10, "chair %d: object %d's centroid %.3f m from the truth" %
                            (cid, o.id, err["seen"]))
            self.assertGreater(o.voxel_count, 300)

        # rviz markers: a box and a label per object.
        time.sleep(0.5)
        with self.lock:
            markers = dict(self.markers)
        for o in final.objects:
            box = markers.get(("object_boxes", o.id))
            label = markers.get(("object_labels", o.id))
            self.assertIsNotNone(box, "no box marker for object %d" % o.id)
            self.assertIsNotNone(label, "no label marker for object %d" % o.id)
            self.assertEqual(box.type, Marker.LINE_LIST)
            self.assertEqual(len(box.points), 24)  # 12 edges
            lo = [min(p.x for p in box.points), min(p.y for p in box.points), min(p.z for p in box.points)]
            hi = [max(p.x for p in box.points), max(p.y for p in box.points), max(p.z for p in box.points)]
            self.assertTrue(np.allclose(lo, [o.bbox_min.x, o.bbox_min.y, o.bbox_min.z], atol=0.05))
            self.assertTrue(np.allclose(hi, [o.bbox_max.x, o.bbox_max.y, o.bbox_max.z], atol=0.05))
            self.assertEqual(label.type, Marker.TEXT_VIEW_FACING)
            self.assertEqual(label.text, "chair #%d" % o.id)
            self.assertGreater(label.pose.position.z, o.bbox_max.z)
            mesh = markers.get(("object_meshes", o.id))
            self.assertIsNotNone(mesh, "no mesh marker for object %d (an empty mesh is deleted)" % o.id)
            self.assertEqual(mesh.type, Marker.TRIANGLE_LIST)
            self.assertGreater(len(mesh.points), 3 * 100, "object %d's mesh has %d triangles" %
                               (o.id, len(mesh.points) // 3))
        self.assertFalse([k for k in markers if k[1] not in chairs], "markers of objects that do not exist")

        d = tempfile.mkdtemp(prefix="semexp_object_map_test_")
        self.addCleanup(shutil.rmtree, d, True)  # also when an assertion below fails
        res = rospy.ServiceProxy("/object_map/save", SaveMap)(d)
        self.assertTrue(res.success, res.message)
        self.assertEqual(len(res.files), len(final.objects) + 1)
        with open(os.path.join(d, "objects.json")) as f:
            doc = json.load(f)
        self.assertEqual(sorted(o["id"] for o in doc["objects"]), sorted(chairs))
        self.assertTrue(all(o["undetected_count"] >= 0 and o["weight_sum"] > 0 for o in doc["objects"]))
        for p in res.files:
            self.assertTrue(os.path.getsize(p) > 0)
            if p.endswith(".ply"):  # a mesh with vertices, not a header alone
                with open(p, "rb") as f:
                    header = f.read(512).split(b"end_header")[0].decode("ascii", "replace")
                vertices = [int(line.split()[2]) for line in header.splitlines() if line.startswith("element vertex")]
                self.assertTrue(vertices and vertices[0] > 100, "%s: %s vertices" % (p, vertices))


if __name__ == "__main__":
    rostest.rosrun(PKG, "object_map_sim", ObjectMapTest)

#!/usr/bin/env python3
"""rostest (soak.test): randomised input to every C++ mapping and planning
node, from a fixed seed. For each subscribed topic ~messages messages and for
each service ~requests requests with random sizes, encodings, steps, NaN/inf
fields, arrays of unrelated lengths and stamps going backwards
(soak_messages.py). Afterwards every node is the process it was, answers (a
broken camera_info is counted by each camera node, each service answers a
valid request), has counted every message whose layout alone is unusable
(each broken depth frame reported as not integrated, one drop per frame that
was not integrated, each broken camera_info, colour image and frontier
cloud, each non-finite object), and its peak RSS stays under ~max_rss_mb.

One line per topic and service goes to the log (rosout and stdout) with the
counts; docs/BENCHMARKS.md quotes them."""
import io
import os
import random
import sys
import threading
import time
import unittest
import xmlrpc.client

import genpy
import rosgraph
import rospy
import tf2_ros
from geometry_msgs.msg import Point, PoseStamped, TransformStamped
from sensor_msgs.msg import CameraInfo, Image, PointCloud2, PointField
from std_msgs.msg import String

from semantic_exploration.msg import (DropCounts, Detections, FrameIntegrated, MapBlocks, MapStats,
                                      MatchedDetections, ObjectArray)
from semantic_exploration.srv import (ComputeGains, ComputeGainsRequest, GetHistoryMasks, GetHistoryMasksRequest,
                                      GetMap, GetMapRequest, PlanOnce, RenderInstances, RenderInstancesRequest,
                                      SaveMap)

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import soak_messages as sm  # noqa: E402

NODES = ("background_map", "depth_history", "instance_matching", "object_map", "planner")
CAMERA_NODES = ("background_map", "depth_history", "instance_matching", "object_map")
FRAME_NODES = ("background_map", "depth_history")  # one frame_integrated per depth frame
NOT_PER_FRAME = ("frame_gap", "bad_rgb")  # counted per missing frame / per colour image, not per depth frame


def raw_message_type(msg_class):
    """A message type that publishes any bytes under msg_class's type (for nodes that read a topic raw)."""

    class Raw(genpy.Message):
        _type, _md5sum, _full_text, _has_header = msg_class._type, msg_class._md5sum, msg_class._full_text, False
        __slots__ = ["buff"]
        _slot_types = ["uint8[]"]

        def __init__(self, buff=b""):
            self.buff = buff

        def serialize(self, out):
            out.write(self.buff)

    Raw.__name__ = "Raw" + msg_class.__name__
    return Raw


def serialised(msg):
    """The bytes msg is sent as."""
    b = io.BytesIO()
    msg.serialize(b)
    return b.getvalue()


def node_pid(name):
    try:
        uri = rosgraph.Master("/soak").lookupNode("/" + name)
        code, _, pid = xmlrpc.client.ServerProxy(uri).getPid("/soak")
        return pid if code == 1 else None
    except Exception:  # not registered, or dead
        return None


def rss_mb(pid):
    """(current, peak) resident set size of pid, MB."""
    with open("/proc/%d/status" % pid) as f:
        kv = dict(line.split(":", 1) for line in f if ":" in line)
    return int(kv["VmRSS"].split()[0]) / 1024.0, int(kv["VmHWM"].split()[0]) / 1024.0


def describe(m):
    return "%s %dx%d step %d, %d bytes, stamp %.3f, frame '%s'%s" % (
        m.encoding, m.width, m.height, m.step, len(m.data), m.header.stamp.to_sec(), m.header.frame_id,
        ", big-endian" if m.is_bigendian else "")


def camera_info(stamp):
    m = CameraInfo()
    m.header.stamp, m.header.frame_id = stamp, "camera"
    m.width, m.height = sm.W, sm.H
    m.K = [262.5, 0, 159.5, 0, 262.5, 119.5, 0, 0, 1]
    m.P = [262.5, 0, 159.5, 0, 0, 262.5, 119.5, 0, 0, 0, 1, 0]
    return m


def depth_frame(stamp, metres=3.0):
    m = Image()
    m.header.stamp, m.header.frame_id = stamp, "camera"
    m.width, m.height, m.encoding, m.step = sm.W, sm.H, "32FC1", sm.W * 4
    m.data = sm.struct.pack("<f", metres) * (sm.W * sm.H)
    return m


def wait_for(test, cond, timeout_s, what=None):
    """Polls cond() until it holds (True) or timeout_s pass: then fails `test` naming `what`,
    or returns False without one. A TestCase method of both soaks (as _wait_for)."""
    deadline = time.time() + timeout_s
    while time.time() < deadline and not rospy.is_shutdown():
        if cond():
            return True
        time.sleep(0.002)
    if what:
        test.fail("timed out after %.1f s waiting for %s" % (timeout_s, what))
    return False


class Soak(unittest.TestCase):
    def setUp(self):
        self.rng = random.Random(rospy.get_param("~seed", 15))
        self.n_msgs = rospy.get_param("~messages", 200)
        self.n_reqs = rospy.get_param("~requests", 40)
        self.max_rss_mb = rospy.get_param("~max_rss_mb", 400.0)
        self.lock = threading.Lock()
        self.drops = {n: {} for n in NODES}
        self.frames = {n: [] for n in NODES}  # FrameIntegrated.integrated per node, in order
        rospy.Subscriber("/dropped_input", DropCounts, self._on_drops, queue_size=1000)
        rospy.Subscriber("/frame_integrated", FrameIntegrated, self._on_frame, queue_size=1000)
        self.static_tf = tf2_ros.StaticTransformBroadcaster()
        t = TransformStamped()  # the camera at (0, 0, 1.5) looking along world +x
        t.header.frame_id, t.child_frame_id = "world", "camera"
        t.transform.translation.z = 1.5
        q = t.transform.rotation
        q.x, q.y, q.z, q.w = -0.5, 0.5, -0.5, 0.5
        self.static_tf.sendTransform(t)
        self.t_s = 100.0  # stamps advance from here
        for n in NODES:
            self._wait_for(lambda: node_pid(n) is not None, 30.0, "/%s to start" % n)
        self.pids = {n: node_pid(n) for n in NODES}
        self.rss0 = {n: rss_mb(self.pids[n])[0] for n in NODES}
        self.report = []

    # ------------------------------------------------------------ bookkeeping
    def _on_drops(self, m):
        with self.lock:
            self.drops.setdefault(m.node.lstrip("/"), {}).update(dict(zip(m.reasons, m.counts)))

    def _on_frame(self, m):
        with self.lock:
            self.frames.setdefault(m.node, []).append(m.integrated)

    def _dropped(self, node, exclude=()):
        with self.lock:
            return sum(c for r, c in self.drops.get(node, {}).items() if r not in exclude)

    def _count(self, node, reason):
        with self.lock:
            return self.drops.get(node, {}).get(reason, 0)

    def _n_frames(self, node):
        with self.lock:
            return len(self.frames[node])

    _wait_for = wait_for

    def _stamp(self):
        self.t_s += 0.1
        return sm.stamp(self.rng, self.t_s)

    def _publisher(self, topic, cls):
        pub = rospy.Publisher(topic, cls, queue_size=1000)

        def all_connected():  # every subscriber the master lists, not only the first
            subs = [s for t, s in rosgraph.Master("/soak").getSystemState()[1] if t == topic]
            return bool(subs) and pub.get_num_connections() >= len(subs[0])
        self._wait_for(all_connected, 20.0, "every subscriber of " + topic)
        time.sleep(0.1)
        return pub

    def _log(self, line):
        rospy.loginfo("soak: " + line)
        print("soak: " + line)
        self.report.append(line)

    # ------------------------------------------------------------ phases
    def _camera_info(self):
        pub = self._publisher("/camera/camera_info", CameraInfo)
        broken = 0
        for i in range(self.n_msgs):
            r = self.rng.random()
            m = camera_info(self._stamp()) if r < 0.5 else sm.fill(self.rng, CameraInfo())
            if r < 0.5:  # a valid one with a defect or two
                if self.rng.random() < 0.5:
                    m.K = list(m.K)
                    m.K[self.rng.choice([0, 2, 4, 5])] = self.rng.choice(sm.SPECIAL_FLOATS)
                if self.rng.random() < 0.3:
                    m.width, m.height = self.rng.choice([(0, 0), (100000, 100000), (640, 480), (sm.W, sm.H)])
                if self.rng.random() < 0.3:
                    m.D = [self.rng.choice(sm.SPECIAL_FLOATS) for _ in range(self.rng.randint(0, 8))]
            bad = not (sm.finite(m.K[0]) and sm.finite(m.K[4]) and m.K[0] > 0 and m.K[4] > 0) \
                or m.width == 0 or m.height == 0
            before = {n: self._count(n, "bad_camera_info") for n in CAMERA_NODES}
            pub.publish(m)
            if bad:
                broken += 1
                for n in CAMERA_NODES:
                    self._wait_for(lambda: self._count(n, "bad_camera_info") > before[n], 5.0,
                                   "%s to count broken camera_info %d" % (n, i))
            else:
                time.sleep(0.02)  # queue size 1: let every node take it
        pub.publish(camera_info(self._stamp()))  # the camera the later phases use
        time.sleep(0.5)
        self._log("camera_info: %d sent, %d broken (each counted as bad_camera_info by %s)"
                  % (self.n_msgs, broken, ", ".join(CAMERA_NODES)))
        pub.unregister()

    def _depth(self):
        pub = self._publisher("/camera/depth/image_raw", Image)
        first = {n: self._n_frames(n) for n in FRAME_NODES}
        drops0 = {n: self._dropped(n, NOT_PER_FRAME) for n in FRAME_NODES}
        broken_at = []
        for i in range(self.n_msgs):
            m, bad = sm.image(self.rng, sm.DEPTH, self._stamp())
            if bad:
                broken_at.append(i)
            pub.publish(m)
            for n in FRAME_NODES:
                self._wait_for(lambda: self._n_frames(n) >= first[n] + i + 1, 10.0,
                               "frame_integrated from %s for depth frame %d (%s; the node %s)"
                               % (n, i, describe(m), "runs" if node_pid(n) else "died"))
        pub.unregister()
        for n in FRAME_NODES:
            with self.lock:
                done = self.frames[n][first[n]:]
            self.assertEqual(len(done), self.n_msgs, n)
            for i in broken_at:
                self.assertFalse(done[i], "%s integrated broken depth frame %d" % (n, i))
            refused = done.count(False)
            self._wait_for(lambda: self._dropped(n, NOT_PER_FRAME) - drops0[n] >= refused, 5.0)
            self.assertEqual(self._dropped(n, NOT_PER_FRAME) - drops0[n], refused,
                             "%s: one drop per frame not integrated" % n)
            self._log("depth -> %s: %d sent, %d broken, %d integrated, %d dropped and counted"
                      % (n, self.n_msgs, len(broken_at), done.count(True), refused))

    def _colour(self):
        """Colour images, each with a valid depth frame of its stamp: background_map pairs them."""
        rgb = self._publisher("/camera/rgb/image_raw", Image)
        depth = self._publisher("/camera/depth/image_raw", Image)
        first = self._n_frames("background_map")
        bad_rgb0 = self._count("background_map", "bad_rgb")
        broken = 0
        for i in range(self.n_msgs):
            self.t_s += 0.1
            stamp = genpy.Time.from_sec(self.t_s)
            m, bad = sm.image(self.rng, sm.COLOUR, stamp)
            broken += bad
            rgb.publish(m)
            time.sleep(0.005)
            depth.publish(depth_frame(stamp))
            self._wait_for(lambda: self._n_frames("background_map") >= first + i + 1, 10.0,
                           "frame_integrated from background_map for colour frame %d" % i)
        rgb.unregister()
        depth.unregister()
        counted = self._count("background_map", "bad_rgb") - bad_rgb0
        self.assertGreaterEqual(counted, broken, "every broken colour image counted as bad_rgb")
        self.assertLessEqual(counted, self.n_msgs)
        self._log("rgb -> background_map: %d sent, %d broken, %d counted as bad_rgb" % (self.n_msgs, broken, counted))

    def _detections(self, topic, cls, node):
        """Random (matched) detections, each with valid depth and colour of its stamp."""
        det = self._publisher(topic, cls)
        depth = self._publisher("/camera/depth/image_raw", Image)
        rgb = self._publisher("/camera/rgb/image_raw", Image)
        first = self._n_frames("object_map")
        drops0 = self._dropped(node)
        broken = 0
        for i in range(self.n_msgs // 2):
            self.t_s += 0.1
            stamp = genpy.Time.from_sec(self.t_s)
            m = sm.fill(self.rng, cls())
            m.header.stamp = stamp
            if self.rng.random() < 0.7:
                m.instance_image, bad = sm.image(self.rng, ("16UC1",), stamp)
                broken += bad
            colour = depth_frame(stamp)
            colour.encoding, colour.step = "mono8", sm.W
            colour.data = bytes(sm.W * sm.H)
            det.publish(m)
            depth.publish(depth_frame(stamp))
            rgb.publish(colour)
            # object_map reports a frame only if instance_matching passed it on: no failure here
            self._wait_for(lambda: self._n_frames("object_map") >= first + i + 1, 2.0)
        for p in (det, depth, rgb):
            p.unregister()
        time.sleep(0.5)
        handled = self._n_frames("object_map") - first
        counted = self._dropped(node) - drops0
        self.assertGreaterEqual(counted, broken, "%s counts every broken instance image" % node)
        self._log("%s -> %s: %d sent, %d with a broken instance image, %d drops counted, %d frames reached "
                  "object_map" % (topic, node, self.n_msgs // 2, broken, counted, handled))

    def _planner_topics(self):
        time.sleep(1.5)  # background_map's last clouds and stats are out
        topics = [("/background_map/map_update", MapBlocks), ("/background_map/frontiers", PointCloud2),
                  ("/object_map/objects", ObjectArray), ("/mav/goal_reached", PoseStamped),
                  ("/background_map/stats", MapStats), ("/mav/path_rejected", String)]
        for topic, cls in topics:
            pub = self._publisher(topic, cls)
            expected, sent = 0, 0
            before = self._dropped("planner", ("service_timeout",))
            for i in range(self.n_msgs):
                m = self._frontiers() if cls is PointCloud2 and self.rng.random() < 0.7 else sm.fill(self.rng, cls())
                bad = self._planner_bad(m)
                b0 = self._dropped("planner", ("service_timeout",))
                pub.publish(m)
                sent += 1
                expected += bad
                if bad:
                    self._wait_for(lambda: self._dropped("planner", ("service_timeout",)) >= b0 + bad, 5.0,
                                   "the planner to count %d drops of %s message %d" % (bad, topic, i))
                else:
                    time.sleep(0.005)
            pub.unregister()
            counted = self._dropped("planner", ("service_timeout",)) - before
            self.assertGreaterEqual(counted, expected)
            self._log("%s -> planner: %d sent, %d drops determinable, %d counted" % (topic, sent, expected, counted))

    def _frontiers(self):
        m = PointCloud2()
        m.header.stamp = self._stamp()
        m.fields = [PointField(name=c, offset=4 * k, datatype=PointField.FLOAT32, count=1)
                    for k, c in enumerate("xyz")]
        m.point_step = self.rng.choice([0, 1, 12, 12, 16, 13])
        m.height = self.rng.choice([0, 1, 1, 2])
        m.width = self.rng.choice([0, 1, 10, 1000])
        m.row_step = max(0, m.width * m.point_step + self.rng.choice([0, 0, 0, 4, -1]))
        n = max(0, m.row_step * m.height + self.rng.choice([0, 0, 0, 1, -1]))
        m.data = sm.struct.pack("<%df" % (n // 4), *[self.rng.choice(sm.SPECIAL_FLOATS + (1.0, 2.0))
                                                      for _ in range(n // 4)]) + bytes(n % 4)
        return m

    @staticmethod
    def _planner_bad(m):
        """Drops the planner must count for m (0 where it is usable or that is not determinable here)."""
        if isinstance(m, PointCloud2):
            xyz = {f.name for f in m.fields if f.datatype == PointField.FLOAT32} >= {"x", "y", "z"}
            return int(not xyz or m.is_bigendian or m.point_step < 12 or m.row_step < m.width * m.point_step
                       or len(m.data) != m.row_step * m.height)
        if isinstance(m, MapBlocks):
            return int(m.encoding != MapBlocks.ENCODING_LOG_ODDS_I8)
        if isinstance(m, MapStats):
            v, share = m.explored_volume_m3, m.surface_observed_share
            return int(not (sm.finite(v) and v >= 0) or not (share == -1 or (sm.finite(share) and 0 <= share <= 1)))
        if isinstance(m, ObjectArray):
            def ok(o):
                v = [o.bbox_min.x, o.bbox_min.y, o.bbox_min.z, o.bbox_max.x, o.bbox_max.y, o.bbox_max.z,
                     o.centroid.x, o.centroid.y, o.centroid.z]
                return all(sm.finite(x) or isinstance(x, int) for x in v) and sm.finite(o.observed_fraction) \
                    and 0 <= o.observed_fraction <= 1
            return sum(not ok(o) for o in m.objects)
        return 0

    def _services(self, tmp):
        """Random requests to every service; each must be answered (a refusal is an answer)."""
        services = [("/background_map/compute_gains", ComputeGains, ComputeGainsRequest),
                    ("/object_map/compute_gains", ComputeGains, ComputeGainsRequest),
                    ("/depth_history/get_masks", GetHistoryMasks, GetHistoryMasksRequest),
                    ("/object_map/render_instances", RenderInstances, RenderInstancesRequest),
                    ("/background_map/get_map", GetMap, GetMapRequest),
                    ("/background_map/save", SaveMap, None), ("/object_map/save", SaveMap, None),
                    ("/planner/plan_once", PlanOnce, None)]
        for name, srv, req_cls in services:
            rospy.wait_for_service(name, 10.0)
            proxy = rospy.ServiceProxy(name, srv)
            n = self.n_reqs if req_cls is not None else self.n_reqs // 4
            answered = refused = 0
            node = name.split("/")[1]
            drops0 = self._dropped(node, ("service_timeout",))
            for i in range(n):
                if srv is SaveMap:
                    req = [self.rng.choice(["", "relative/dir", os.path.join(tmp, "..", "x"), "/proc/none/x",
                                            os.path.join(tmp, "save%d" % i)])]
                elif srv is PlanOnce:
                    req = []
                else:
                    req = [sm.fill(self.rng, req_cls())]
                    if hasattr(req[0], "positions") and self.rng.random() < 0.5:  # sizes near the limits
                        r = req[0]
                        r.width, r.height = self.rng.choice([(36, 10), (360, 180), (361, 180), (65535, 65535)])
                        r.positions = [Point(self.rng.uniform(-12, 12), self.rng.uniform(-12, 12), 1.0)
                                       for _ in range(self.rng.choice([0, 1, 20, 1025]))]
                try:
                    proxy(*req)
                    answered += 1
                except rospy.ServiceException as e:  # refused (the service returned false) or the node died
                    self.assertIsNotNone(node_pid(name.split("/")[1]), "%s died on request %d: %s" % (name, i, e))
                    refused += 1
            counted = ""
            if req_cls is not None and srv is not GetMap:  # a refused request is a counted drop
                self._wait_for(lambda: self._dropped(node, ("service_timeout",)) - drops0 >= refused, 5.0)
                counted = self._dropped(node, ("service_timeout",)) - drops0
                self.assertGreaterEqual(counted, refused, "%s counts every refused request" % name)
                counted = ", %d drops counted" % counted
            self._log("%s: %d requests, %d answered, %d refused%s" % (name, n, answered, refused, counted))

    # ------------------------------------------------------------ the soak
    def test_soak(self):
        t0 = time.time()
        import tempfile
        tmp = tempfile.mkdtemp(prefix="semexp_soak_")
        self._camera_info()
        self._depth()
        self._colour()
        self._detections("/detections", Detections, "instance_matching")
        self._detections("/matched_detections", MatchedDetections, "object_map")
        self._planner_topics()
        self._services(tmp)
        # Alive and answering: the same processes; a broken camera_info is counted by every camera node.
        for n in NODES:
            self.assertEqual(node_pid(n), self.pids[n], "/%s was restarted or died" % n)
        pub = self._publisher("/camera/camera_info", CameraInfo)
        before = {n: self._count(n, "bad_camera_info") for n in CAMERA_NODES}
        ping = camera_info(self._stamp())
        ping.K = [0.0] * 9
        pub.publish(ping)
        for n in CAMERA_NODES:
            self._wait_for(lambda: self._count(n, "bad_camera_info") > before[n], 5.0, "%s to answer the ping" % n)
        self.assertTrue(rospy.ServiceProxy("/planner/plan_once", PlanOnce)().message)
        for n in NODES:
            rss, peak = rss_mb(self.pids[n])
            self._log("%s: RSS %.0f MB at the start, %.0f MB at the end, peak %.0f MB, %d drops counted"
                      % (n, self.rss0[n], rss, peak, self._dropped(n)))
            self.assertLess(peak, self.max_rss_mb, "/%s peak RSS" % n)
        self._log("total %.0f s wall" % (time.time() - t0))


if __name__ == "__main__":
    import rostest
    rospy.init_node("soak")
    rostest.rosrun("semantic_exploration", "soak", Soak)

#!/usr/bin/env python3
"""rostest (soak_sim_detector.test): the randomised-input soak of soak.test
(same generator, soak_messages.py) for the two nodes it leaves out: the
detector and mav_sim.

detector: the test builds the hand-computed ONNX model of
test/detector/make_seg_model.py (the one test_detector_node.py and the detector
gtest use) and starts the node on it, its inputs and output remapped under
/soak so that the simulator's frames do not reach it. ~messages camera_info
messages (each broken one, size 0 or beyond PinholeCamera's caps, counted as
bad_camera_info) and ~messages colour images (each answered by one detections
message or one counted drop; each broken one counted).

mav_sim: ~messages paths on planner/path (random Path messages, raw random
bytes and oversized pose counts; each one whose frame, values, pose count or
bytes alone make it unusable answered on mav/path_rejected),
~requests scene switches on ~load_scene (random unreadable paths: each
logged as a rejected scene, frames keep coming), ~messages ~hide_detections and frame_integrated messages.

Afterwards both are the processes they were, answer a ping (a size-0
camera_info is counted; a path in another frame is rejected; a valid colour
frame gives detections), the simulator still publishes frames, and each
peak RSS (VmHWM) is under its bound (~detector_max_rss_mb,
~sim_max_rss_mb). One line per input to the log; docs/BENCHMARKS.md quotes them."""
import os
import random
import struct
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import genpy
import rospkg
import rospy
from nav_msgs.msg import Path
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import Header, String, UInt32MultiArray

from semantic_exploration.msg import Detections, DropCounts, FrameIntegrated

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import soak_messages as sm  # noqa: E402
from test_soak import camera_info, node_pid, raw_message_type, rss_mb, serialised, wait_for  # noqa: E402

MAX_SIDE_PX, MAX_PIXELS = 8192, 4096 * 4096  # PinholeCamera::kMaxSidePx, kMaxPixels (core/camera.hpp)


RawPath = raw_message_type(Path)  # mav_sim reads this topic raw


class SoakSimDetector(unittest.TestCase):
    def setUp(self):
        self.rng = random.Random(rospy.get_param("~seed", 15))
        self.n_msgs = rospy.get_param("~messages", 200)
        self.n_reqs = rospy.get_param("~requests", 20)
        self.lock = threading.Lock()
        self.drops, self.outputs, self.rejected, self.depth_frames, self.scenes_rejected = {}, 0, [], 0, 0
        self.report = []
        rospy.Subscriber("/dropped_input", DropCounts, self._on_drops, queue_size=1000)
        rospy.Subscriber("/soak/detections", Detections, self._on_output, queue_size=1000)
        rospy.Subscriber("/mav/path_rejected", String, self._on_rejected, queue_size=1000)
        rospy.Subscriber("/camera/depth/image_raw", rospy.AnyMsg, self._on_depth, queue_size=10)
        rospy.Subscriber("/rosout", Log, self._on_log, queue_size=1000)
        self.launch = self._start_detector()
        for n in ("detector", "mav_sim"):
            self._wait_for(lambda: node_pid(n) is not None, 60.0, "/%s to start" % n)
        self.pids = {n: node_pid(n) for n in ("detector", "mav_sim")}
        self.rss0 = {n: rss_mb(p)[0] for n, p in self.pids.items()}

    def tearDown(self):
        self.launch.stop()

    def _start_detector(self):
        import roslaunch
        model = os.path.join(tempfile.mkdtemp(prefix="semexp_soak_"), "scene.onnx")
        make = os.path.join(rospkg.RosPack().get_path("semantic_exploration"), "test", "detector", "make_seg_model.py")
        subprocess.check_call([os.environ.get("SEMEXP_PYTHON", "/usr/bin/python3"), make, model, "--variant", "scene"])
        rospy.set_param("/detector/detector/model_path", model)
        launch = roslaunch.scriptapi.ROSLaunch()
        launch.start()
        remap = [("camera/rgb/image_raw", "/soak/camera/rgb/image_raw"),
                 ("camera/camera_info", "/soak/camera/camera_info"), ("detections", "/soak/detections")]
        launch.launch(roslaunch.core.Node("semantic_exploration", "detector_node", name="detector",
                                          remap_args=remap, output="log"))
        return launch

    # ------------------------------------------------------------ bookkeeping
    def _on_drops(self, m):
        with self.lock:
            self.drops.setdefault(m.node.lstrip("/"), {}).update(dict(zip(m.reasons, m.counts)))

    def _on_output(self, _):
        with self.lock:
            self.outputs += 1

    def _on_rejected(self, m):
        with self.lock:
            self.rejected.append(m.data)

    def _on_log(self, m):
        if m.name.endswith("mav_sim") and "rejected scene" in m.msg:
            with self.lock:
                self.scenes_rejected += 1

    def _on_depth(self, _):
        with self.lock:
            self.depth_frames += 1

    def _get(self, attr):
        with self.lock:
            v = getattr(self, attr)
            return len(v) if isinstance(v, list) else v

    def _dropped(self, reason=None):
        with self.lock:
            d = self.drops.get("detector", {})
            return d.get(reason, 0) if reason else sum(d.values())

    _wait_for = wait_for

    def _publisher(self, topic, cls):
        pub = rospy.Publisher(topic, cls, queue_size=1000)
        self._wait_for(lambda: pub.get_num_connections() > 0, 20.0, "a subscriber of " + topic)
        time.sleep(0.2)
        return pub

    def _log(self, line):
        rospy.loginfo("soak: " + line)
        print("soak: " + line)
        self.report.append(line)

    # ------------------------------------------------------------ detector
    def _detector_camera_info(self, pub):
        broken = 0
        for i in range(self.n_msgs):
            m = camera_info(genpy.Time.from_sec(100 + 0.1 * i))
            if self.rng.random() < 0.5:
                m = sm.fill(self.rng, CameraInfo())
            elif self.rng.random() < 0.5:
                m.width, m.height = self.rng.choice([(0, 0), (0, 5), (100000, 100000), (65535, 65535),
                                                     (MAX_SIDE_PX + 1, 1), (640, 480)])
            bad = m.width == 0 or m.height == 0 or m.width > MAX_SIDE_PX or m.height > MAX_SIDE_PX or \
                m.width * m.height > MAX_PIXELS
            before = self._dropped("bad_camera_info")
            pub.publish(m)
            if bad:
                broken += 1
                self._wait_for(lambda: self._dropped("bad_camera_info") > before, 5.0,
                               "the detector to count broken camera_info %d (%dx%d)" % (i, m.width, m.height))
            else:
                time.sleep(0.01)
            if i % 5 == 4:  # a frame at the size just set: the node must survive segmenting at it
                self._colour_frame(pub_colour=self.colour_pub, what="after camera_info %d" % i)
        pub.publish(camera_info(genpy.Time.from_sec(200)))  # the camera the colour phase uses
        time.sleep(0.3)
        self._log("camera_info -> detector: %d sent, %d broken (each counted as bad_camera_info)"
                  % (self.n_msgs, broken))

    def _colour_frame(self, pub_colour, what, m=None):
        """Publishes one image; waits for the detector's answer (detections or a counted drop)."""
        if m is None:
            m = Image(encoding="bgr8", width=sm.W, height=sm.H, step=3 * sm.W, data=bytes(3 * sm.W * sm.H))
        n0 = self._get("outputs") + self._dropped()
        pub_colour.publish(m)
        self._wait_for(lambda: self._get("outputs") + self._dropped() > n0, 10.0,
                       "the detector to answer a colour frame %s (%s %dx%d)" % (what, m.encoding, m.width, m.height))

    def _detector_colour(self):
        out0, drops0, bad0 = self._get("outputs"), self._dropped(), self._dropped("bad_colour")
        broken = 0
        for i in range(self.n_msgs):
            m, bad = sm.image(self.rng, sm.COLOUR, genpy.Time.from_sec(300 + 0.1 * i))
            broken += bad
            self._colour_frame(self.colour_pub, "%d" % i, m)
        answered = self._get("outputs") - out0
        dropped = self._dropped() - drops0
        self.assertEqual(answered + dropped, self.n_msgs, "one answer or one counted drop per colour frame")
        self.assertGreaterEqual(self._dropped("bad_colour") - bad0, broken, "every broken colour image counted")
        self._log("rgb -> detector: %d sent, %d broken, %d detections messages, %d drops counted"
                  % (self.n_msgs, broken, answered, dropped))

    # ------------------------------------------------------------ mav_sim
    def _random_path(self):
        r = self.rng.random()
        if r < 0.15:  # raw bytes: short, garbage, or a header claiming a huge pose count
            if self.rng.random() < 0.5:
                return RawPath(bytes(self.rng.getrandbits(8) for _ in range(self.rng.randint(0, 40)))), 1
            return RawPath(struct.pack("<IIII5sI", 0, 0, 0, 5, b"world", 2 ** 31) + bytes(64)), 1
        p = sm.fill(self.rng, Path())
        if r < 0.6:  # in the world frame, some poses in the house, a few broken
            p.header.frame_id = self.rng.choice(["world", "", "/world"])
            for q in p.poses:
                q.pose.position.x, q.pose.position.y = self.rng.uniform(0, 8), self.rng.uniform(0, 6)
                q.pose.position.z = self.rng.uniform(0.5, 2.5)
                q.pose.orientation.x = q.pose.orientation.y = 0.0
                q.pose.orientation.z, q.pose.orientation.w = self.rng.uniform(-1, 1), 1.0
                if self.rng.random() < 0.05:
                    q.pose.position.x = self.rng.choice(sm.SPECIAL_FLOATS)
        frame_ok = p.header.frame_id.lstrip("/") in ("", "world")
        values_ok = all(sm.finite(v) or isinstance(v, int) for q in p.poses for v in (
            q.pose.position.x, q.pose.position.y, q.pose.position.z, q.pose.orientation.x, q.pose.orientation.y,
            q.pose.orientation.z, q.pose.orientation.w))
        quat_ok = values_ok and all(abs(q.pose.orientation.x) + abs(q.pose.orientation.y) + abs(q.pose.orientation.z)
                                    + abs(q.pose.orientation.w) > 1e-5 for q in p.poses)
        return p, int(not (frame_ok and values_ok and quat_ok))

    def _sim_paths(self):
        pub = self._publisher("/planner/path", RawPath)
        rej0, determinable = self._get("rejected"), 0
        for i in range(self.n_msgs):
            m, bad = self._random_path()
            if not isinstance(m, RawPath):
                m = RawPath(serialised(m))
            determinable += bad
            r0 = self._get("rejected")
            pub.publish(m)
            if bad:
                self._wait_for(lambda: self._get("rejected") > r0, 5.0, "mav_sim to reject path %d" % i)
            else:
                time.sleep(0.01)
        time.sleep(0.5)
        rejected = self._get("rejected") - rej0
        self.assertGreaterEqual(rejected, determinable)
        self.assertLessEqual(rejected, self.n_msgs)
        self._log("planner/path -> mav_sim: %d sent, %d unusable by their frame, values, count or bytes, "
                  "%d rejected on mav/path_rejected" % (self.n_msgs, determinable, rejected))
        return pub

    def _sim_other_topics(self):
        scene = self._publisher("/mav_sim/load_scene", String)
        frames0, rejected0 = self._get("depth_frames"), self._get("scenes_rejected")
        for i in range(self.n_reqs):  # none of them a readable scene ("" would generate one)
            scene.publish(String(self.rng.choice(["/nonexistent.ply", "/proc/self/status;x.json", "a" * 300,
                                                  "/dev/null", "/tmp;/tmp", "\u00e9.ply", "x;y", "/etc/hostname"])))
            time.sleep(0.05)
        self._wait_for(lambda: self._get("scenes_rejected") >= rejected0 + self.n_reqs, 20.0,
                       "mav_sim to reject each of %d unreadable scenes" % self.n_reqs)
        hide = self._publisher("/mav_sim/hide_detections", UInt32MultiArray)
        done = self._publisher("/frame_integrated", FrameIntegrated)
        for i in range(self.n_msgs):
            hide.publish(sm.fill(self.rng, UInt32MultiArray()))
            done.publish(sm.fill(self.rng, FrameIntegrated()))
            time.sleep(0.005)
        hide.publish(UInt32MultiArray())
        self._wait_for(lambda: self._get("depth_frames") >= frames0 + 10, 20.0, "frames from mav_sim after the soak")
        self._log("mav_sim: %d ~load_scene (unreadable, %d logged as rejected), %d ~hide_detections, "
                  "%d frame_integrated; %d depth frames during these"
                  % (self.n_reqs, self._get("scenes_rejected") - rejected0, self.n_msgs, self.n_msgs,
                     self._get("depth_frames") - frames0))
        for p in (scene, hide, done):
            p.unregister()

    # ------------------------------------------------------------ the soak
    def test_soak(self):
        t0 = time.time()
        info = self._publisher("/soak/camera/camera_info", CameraInfo)
        self.colour_pub = self._publisher("/soak/camera/rgb/image_raw", Image)
        self._detector_camera_info(info)
        self._detector_colour()
        paths = self._sim_paths()
        self._sim_other_topics()
        for n, pid in self.pids.items():
            self.assertEqual(node_pid(n), pid, "/%s was restarted or died" % n)
        # Pings: each node answers.
        before = self._dropped("bad_camera_info")
        info.publish(CameraInfo(width=0, height=0))
        self._wait_for(lambda: self._dropped("bad_camera_info") > before, 5.0, "the detector to answer the ping")
        out0 = self._get("outputs")
        self._colour_frame(self.colour_pub, "(ping)")
        self.assertEqual(self._get("outputs"), out0 + 1, "a valid frame gives detections")
        r0 = self._get("rejected")
        paths.publish(RawPath(serialised(Path(header=Header(frame_id="nowhere")))))
        self._wait_for(lambda: self._get("rejected") > r0, 5.0, "mav_sim to answer the ping")
        bounds = {"detector": rospy.get_param("~detector_max_rss_mb", 200.0),
                  "mav_sim": rospy.get_param("~sim_max_rss_mb", 500.0)}
        for n, pid in self.pids.items():
            rss, peak = rss_mb(pid)
            self._log("%s: RSS %.0f MB at the start, %.0f MB at the end, peak %.0f MB (bound %.0f MB)"
                      % (n, self.rss0[n], rss, peak, bounds[n]))
            self.assertLess(peak, bounds[n], "/%s peak RSS" % n)
        self._log("total %.0f s wall" % (time.time() - t0))


if __name__ == "__main__":
    import rostest
    rospy.init_node("soak_sim_detector")
    rostest.rosrun("semantic_exploration", "soak_sim_detector", SoakSimDetector)

"""The detector node (issue 17) on a private ROS master with the hand-computed
test model of test/detector/make_seg_model.py (built here with python3-onnx):
a 256 x 192 bgr8 frame gives the instances test/core/detector_test.cpp
computes, at camera_info's 128 x 96 (nearest neighbour); a frame of an
unknown encoding is dropped and counted on /dropped_input; a missing model
stops the node at start-up naming detector/model_path. Skipped where ROS is
not sourced or the package is not built."""
import json
import os
import shutil
import subprocess
import sys
import time

import pytest

if __name__ == "__main__":  # a child process: no pytest to load conftest
    import conftest  # noqa: F401

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MAKE_MODEL = os.path.join(ROOT, "test", "detector", "make_seg_model.py")

ROS_SOURCED = shutil.which("roslaunch") is not None and (
    "ROS_PACKAGE_PATH" in os.environ or "CMAKE_PREFIX_PATH" in os.environ)

# In place of config/detector.yaml (an override file would be merged into its class_map).
DETECTOR_CONFIG = """detector:
  input_size: [128, 128]
  model_classes: [person, chair, couch]
  class_map: {chair: chair, couch: sofa}
"""


def _env(port, home):
    return dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port, ROS_HOSTNAME="127.0.0.1", ROS_HOME=home)


def _start(cmd, env, log):
    return subprocess.Popen(cmd, env=env, stdout=open(log, "w"), stderr=subprocess.STDOUT, start_new_session=True)


def node_phase(work):
    """In a child process (one rospy node per process): runs the node, feeds
    it frames, writes what came back to result.json."""
    import numpy as np
    import rviz_screenshot as rs
    import run_mission as mission
    model = os.path.join(work, "scene.onnx")
    subprocess.check_call([sys.executable, MAKE_MODEL, model, "--variant", "scene"])
    config = os.path.join(work, "detector.yaml")
    with open(config, "w") as f:
        f.write(DETECTOR_CONFIG)
    port = mission._free_port()
    env = _env(port, os.path.join(work, "ros_home"))
    procs = [_start(["roscore", "-p", str(port)], env, os.path.join(work, "roscore.log"))]
    try:
        time.sleep(2.0)
        procs.append(_start(["roslaunch", "-p", str(port), "semantic_exploration", "detector.launch",
                             "model:=" + model, "detector_config:=" + config], env, os.path.join(work, "detector.log")))
        os.environ.update(ROS_MASTER_URI=env["ROS_MASTER_URI"], ROS_HOSTNAME="127.0.0.1", ROS_HOME=env["ROS_HOME"])
        import rospy
        from sensor_msgs.msg import CameraInfo, Image
        from semantic_exploration.msg import Detections, DropCounts
        rospy.init_node("detector_test", disable_signals=True)
        got, drops = [], {}
        rospy.Subscriber("/detections", Detections, got.append, queue_size=10)
        rospy.Subscriber("/dropped_input", DropCounts, lambda m: drops.__setitem__(m.node, dict(zip(m.reasons, m.counts))),
                         queue_size=10)
        pub_info = rospy.Publisher("/camera/camera_info", CameraInfo, queue_size=1, latch=True)
        pub_img = rospy.Publisher("/camera/rgb/image_raw", Image, queue_size=1)
        info = CameraInfo(width=128, height=96)
        info.header.frame_id = "camera_color_optical_frame"
        pub_info.publish(info)

        def frame(encoding, stamp):
            img = Image(height=192, width=256, encoding=encoding, step=256 * 3)
            img.data = np.full((192, 256, 3), 77, np.uint8).tobytes()
            img.header.stamp = rospy.Time(stamp)
            img.header.frame_id = "camera_color_optical_frame"
            return img

        deadline = time.time() + 60.0
        while not got or got[-1].instance_image.width != 128:  # until the node is up and has the camera_info
            assert procs[-1].poll() is None, "the detector stopped (see detector.log)"
            assert time.time() < deadline, "no detections of camera_info's size"
            pub_img.publish(frame("bgr8", 1.0))
            time.sleep(0.5)
        pub_img.publish(frame("32FC3", 2.0))  # no colour encoding
        while drops.get("/detector", {}).get("bad_colour", 0) < 1:
            assert time.time() < deadline, "the bad frame was not counted: %s" % drops
            time.sleep(0.2)
        pub_img.publish(frame("bgr8", 3.0))  # the node goes on after it
        while got[-1].header.stamp != rospy.Time(3.0):
            assert time.time() < deadline, "no detections after the bad frame"
            time.sleep(0.2)
        d = got[-1]
        ids = np.frombuffer(bytes(d.instance_image.data), np.uint16).reshape(d.instance_image.height, -1)
        result = {"encoding": d.instance_image.encoding, "shape": list(ids.shape),
                  "frame_id": d.header.frame_id, "drops": drops.get("/detector", {}),
                  "pixels": {str(k): int((ids == k).sum()) for k in np.unique(ids)},
                  "detections": [[x.instance_id, x.class_id, x.class_name, round(x.confidence, 4), x.pixel_count]
                                 for x in d.detections]}
        with open(os.path.join(work, "result.json"), "w") as f:
            json.dump(result, f)
    finally:
        for p in reversed(procs):
            rs._stop(p, grace_s=10.0)


@pytest.mark.skipif(not ROS_SOURCED, reason="ROS environment not sourced")
def test_detector_node_publishes_the_hand_computed_instances(tmp_path):
    work = str(tmp_path)
    proc = subprocess.run([sys.executable, __file__, work], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=180)
    logs = proc.stdout + "".join(open(os.path.join(work, f)).read() for f in ("detector.log",)
                                 if os.path.exists(os.path.join(work, f)))
    assert proc.returncode == 0, logs
    with open(os.path.join(work, "result.json")) as f:
        r = json.load(f)
    assert r["encoding"] == "16UC1" and r["shape"] == [96, 128]
    assert r["frame_id"] == "camera_color_optical_frame"
    # test/core/detector_test.cpp: A (chair), B (sofa), A' (sofa), E (chair) at half the colour size;
    # class ids from config/semantic.yaml's classes/names (chair 1, sofa 3).
    assert r["detections"] == [[1, 1, "chair", 0.9, 1024], [2, 3, "sofa", 0.7, 512], [3, 3, "sofa", 0.6, 64],
                               [4, 1, "chair", 0.4, 128]]
    assert r["pixels"] == {"0": 96 * 128 - 1024 - 512 - 64 - 128, "1": 1024, "2": 512, "3": 64, "4": 128}
    assert r["drops"] == {"bad_colour": 1}


@pytest.mark.skipif(not ROS_SOURCED, reason="ROS environment not sourced")
def test_a_missing_model_stops_the_node_naming_the_parameter(tmp_path):
    import run_mission as mission
    work = str(tmp_path)
    port = mission._free_port()
    env = _env(port, os.path.join(work, "ros_home"))
    proc = subprocess.run(["roslaunch", "-p", str(port), "semantic_exploration", "detector.launch",
                           "model:=" + os.path.join(work, "missing.onnx")], env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, universal_newlines=True, timeout=60)
    assert "invalid parameter 'detector/model_path'" in proc.stdout, proc.stdout
    assert "missing.onnx" in proc.stdout and "output1 [1, 32, H/4, W/4]" in proc.stdout, proc.stdout


if __name__ == "__main__":
    node_phase(sys.argv[1])

"""mav_sim start-up in lockstep (issue 7): /clock at the first frame's time
and the latched camera_info arrive before the first frame, and a lockstep node that connects to the depth
topic only after the first frames went out does not stall the simulator (it
cannot report frames it never got); once connected it paces the simulator.

The lockstep node is this test's child process ("late_node"): it subscribes
/clock and the colour image at once, the depth image only after the first
colour frame arrived, and reports each depth frame it gets on frame_integrated,
like a mapping node. lockstep_timeout_s is 600 s, so one frame waited for in
vain would end the test by its deadline. Skipped where ROS is not sourced."""
import json
import os
import shutil
import sys
import time

import pytest

if __name__ == "__main__":  # a child process: no pytest to load conftest
    import conftest  # noqa: F401

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ROS_SOURCED = shutil.which("roslaunch") is not None and (
    "ROS_PACKAGE_PATH" in os.environ or "CMAKE_PREFIX_PATH" in os.environ)
EXAMPLE = os.path.join(ROOT, "test", "data", "example_semantic.ply")
NODE = "late_node"
FRAMES = 30  # depth frames the child reports before it stops
START_S = 1.0  # sim.yaml start_time_s


def child(work):
    """The late lockstep node; writes events.json."""
    import rospy
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import CameraInfo, Image
    from std_msgs.msg import Header
    from semantic_exploration.msg import FrameIntegrated
    rospy.init_node(NODE, disable_signals=True)
    ev = {"clock_before_first_frame": None, "first_rgb": None, "depth": [], "rgb_after_stop": [],
          "camera_info_before_first_frame": None}
    state = {"clock": None, "stopped": False}

    def on_clock(m):
        state["clock"] = m.clock.to_sec()

    def on_rgb(m):
        t = m.header.stamp.to_sec()
        if ev["first_rgb"] is None:
            ev["first_rgb"], ev["clock_before_first_frame"] = t, state["clock"]
            ev["camera_info_before_first_frame"] = state.get("info")
        if state["stopped"]:
            ev["rgb_after_stop"].append(t)

    report = rospy.Publisher("/frame_integrated", FrameIntegrated, queue_size=50)

    def on_depth(m):
        if state["stopped"]:
            return
        ev["depth"].append(m.header.stamp.to_sec())
        report.publish(FrameIntegrated(header=Header(stamp=m.header.stamp), node=NODE, integrated=True))
        if len(ev["depth"]) >= FRAMES:
            state["stopped"] = True

    rospy.Subscriber("/clock", Clock, on_clock, queue_size=10)
    rospy.Subscriber("/camera/camera_info", CameraInfo,
                     lambda m: state.setdefault("info", m.header.stamp.to_sec()), queue_size=10)
    rospy.Subscriber("/camera/rgb/image_raw", Image, on_rgb, queue_size=50)
    deadline = time.time() + 90.0
    while ev["first_rgb"] is None and time.time() < deadline:
        time.sleep(0.05)
    rospy.Subscriber("/camera/depth/image_raw", Image, on_depth, queue_size=50)
    while not state["stopped"] and time.time() < deadline:
        time.sleep(0.05)
    time.sleep(3.0)  # the simulator must now wait for this node's report of the last frame
    with open(os.path.join(work, "events.json"), "w") as f:
        json.dump(ev, f)


@pytest.mark.skipif(not ROS_SOURCED, reason="ROS environment (roslaunch) not sourced")
def test_clock_first_and_a_late_lockstep_node_does_not_stall(tmp_path):
    import sim_child
    work = str(tmp_path)
    over = os.path.join(work, "sim_overrides.yaml")
    with open(over, "w") as f:
        f.write("lockstep_timeout_s: 600.0\nlockstep_startup_timeout_s: 2.0\n")
    procs = []
    try:
        env = sim_child.master(work, procs)
        kid = sim_child.start_child(__file__, work, env)
        procs.append(kid)
        time.sleep(2.0)  # the child is registered (not subscribed to depth) before the simulator starts
        procs.append(sim_child.start_sim(work, env, "scene:=" + EXAMPLE, "overrides:=" + over, "lockstep:=true",
                                         "real_time_factor:=0", "lockstep_nodes:=[%s]" % NODE))
        ev = sim_child.child_events(kid, work, 150, "the child did not finish: the simulator stalled?")
    finally:
        sim_child.stop_all(procs)
    print({k: v if not isinstance(v, list) else v[:5] + ["..."] for k, v in ev.items()})
    # frame 0 is the first frame, and the clock had reached it before it arrived
    assert ev["first_rgb"] == pytest.approx(START_S)
    assert ev["clock_before_first_frame"] is not None and ev["clock_before_first_frame"] >= START_S - 1e-9
    # the intrinsics had arrived before it too (latched, sent on connection): a camera node refuses depth
    # before any camera_info, and one frame image overtaking its camera_info made a deterministic run
    # start a frame later than its twin
    assert ev["camera_info_before_first_frame"] == pytest.approx(START_S)
    # the late node missed the first frame(s) but got FRAMES consecutive ones afterwards
    d = ev["depth"]
    assert len(d) == FRAMES, len(d)
    assert d[0] > START_S
    assert all(b - a == pytest.approx(0.1) for a, b in zip(d, d[1:])), d
    # and it paces the simulator: after its last report at most the next frame goes out
    assert all(t <= d[-1] + 0.1 + 1e-6 for t in ev["rgb_after_stop"]), (d[-1], ev["rgb_after_stop"])


if __name__ == "__main__":
    child(sys.argv[1])

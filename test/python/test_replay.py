"""Replay test (issue 7): a short lockstep simulation of a generated 6 x 5 m
house is recorded with record.launch; the bag is played with replay.launch
into fresh mapping nodes at a reduced rate; the replayed background map must
know the same volume as the live one (within 1%), have the same occupied
voxels (all but 1%), and the object map must hold the same objects (class,
centroid within 5 cm).

The test paces the live simulator as one of its lockstep nodes and holds it
after the last frame, so the saved live maps and the bag hold the same frames. Skipped where ROS is not sourced or
the package is not built."""
import argparse
import json
import os
import shutil
import subprocess
import sys
import threading
import time

import pytest

if __name__ == "__main__":  # a child process: no pytest to load conftest
    import conftest  # noqa: F401


ROS_SOURCED = shutil.which("roslaunch") is not None and shutil.which("rosbag") is not None and (
    "ROS_PACKAGE_PATH" in os.environ or "CMAKE_PREFIX_PATH" in os.environ)

SIM_S = 25.0  # sim seconds of the live run
REPLAY_RATE = 0.5  # bag playback rate: the nodes keep up without lockstep
VOLUME_TOL = 0.01  # relative known-volume difference allowed
CENTROID_TOL_M = 0.05
GATE = "replay_test_gate"  # lockstep node name under which the test paces the live simulator
DEPTH = "/camera/depth/image_raw"
# Frames that may be lost while the nodes start (depth before camera_info or
# the first tf, on the live run and on the replay alike); the same bound on both.
STARTUP_FRAMES = 2
DROP_FIELDS = ("dropped_bad_depth", "dropped_size_mismatch", "dropped_no_tf", "dropped_out_of_bounds",
               "dropped_no_camera_info")


def _ros_env(port, home):
    return dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port, ROS_HOSTNAME="127.0.0.1", ROS_HOME=home)


def _start(cmd, env, log):
    return subprocess.Popen(cmd, env=env, stdout=open(log, "w"), stderr=subprocess.STDOUT, start_new_session=True)


def _wait_master(env, proc, timeout_s=30.0):
    import rosgraph
    master = rosgraph.Master("/replay_test", master_uri=env["ROS_MASTER_URI"])
    deadline = time.time() + timeout_s
    while True:
        try:
            master.getPid()
            return master
        except Exception:
            if proc.poll() is not None or time.time() > deadline:
                raise RuntimeError("ROS master on %s did not come up" % env["ROS_MASTER_URI"])
            time.sleep(0.3)


def _wait_subscribed(master, topic, node_prefix, timeout_s=30.0):
    deadline = time.time() + timeout_s
    while time.time() < deadline:
        _, subs, _ = master.getSystemState()
        if any(t == topic and any(n.startswith(node_prefix) for n in nodes) for t, nodes in subs):
            return
        time.sleep(0.3)
    raise RuntimeError("%s does not subscribe to %s" % (node_prefix, topic))


def _node_py(env, name):
    """Makes this process a rospy node on env's master (one per process: the
    replay phase runs in a child process, see _replay_phase)."""
    os.environ.update(ROS_MASTER_URI=env["ROS_MASTER_URI"], ROS_HOSTNAME="127.0.0.1", ROS_HOME=env["ROS_HOME"])
    import rospy
    rospy.init_node(name, anonymous=True, disable_signals=True)
    return rospy


def _bag_last_depth_stamp(bag_path):
    import rosbag
    last = None
    n = 0
    with rosbag.Bag(bag_path) as bag:
        for _, msg, _ in bag.read_messages(topics=[DEPTH]):
            last = msg.header.stamp
            n += 1
    return last, n


def _objects(path):
    with open(os.path.join(path, "objects.json")) as f:
        return json.load(f)["objects"]


def _occupied(ply):
    """Occupied voxel centres of a saved background map, as integer mm."""
    import numpy as np
    import run_mission as mission
    mission._import_package()
    from semantic_exploration.eval import metrics
    pts = np.asarray(metrics.read_ply_vertices(ply))[:, :3]
    return set(map(tuple, np.round(pts * 1000.0).astype(np.int64).tolist()))


def live_phase(work):
    """Records a lockstep run and freezes it: the test is one of the
    simulator's lockstep nodes (GATE) and stops answering after SIM_S, so the
    simulator waits after its last frame while the live maps are saved and the
    recorder stops; bag and live maps then hold the same frames. Returns
    (bag, live stats at the bag's last frame, depth frames in the bag)."""
    import rviz_screenshot as rs
    import run_mission as mission
    ply, gt = mission.prepare_scene(argparse.Namespace(scene="", seed=0, size=[6.0, 5.0, 3.0]), work)
    overrides = os.path.join(work, "overrides.yaml")
    mission.write_overrides(overrides, gt, ["chair"])
    sim_overrides = os.path.join(work, "sim_overrides.yaml")
    with open(sim_overrides, "w") as f:
        f.write("lockstep_timeout_s: 600.0  # the gate holds the simulator while the maps are saved\n")
    port = mission._free_port()
    env = _ros_env(port, os.path.join(work, "ros_home_live"))
    bag = os.path.join(work, "run.bag")
    procs = []
    try:
        # master, mapping nodes, recorder, then the simulator: bag and maps start with the same first frame
        procs.append(_start(["roscore", "-p", str(port)], env, os.path.join(work, "roscore.log")))
        master = _wait_master(env, procs[-1])
        master.setParam("/use_sim_time", True)
        procs.append(_start(["roslaunch", "semantic_exploration", "exploration.launch", "overrides:=" + overrides,
                             "classes_of_interest:=[chair]", "output:=log"], env,
                            os.path.join(work, "exploration.log")))
        _wait_subscribed(master, DEPTH, "/background_map", timeout_s=60.0)
        _wait_subscribed(master, DEPTH, "/object_map", timeout_s=60.0)
        rec = _start(["roslaunch", "semantic_exploration", "record.launch", "bag:=" + bag], env,
                     os.path.join(work, "record.log"))
        procs.append(rec)
        _wait_subscribed(master, DEPTH, "/record")
        rospy = _node_py(env, "replay_test_live")
        from semantic_exploration.msg import FrameIntegrated, MapStats
        from std_msgs.msg import Header
        history = {}
        rospy.Subscriber("/background_map/stats", MapStats,
                         lambda m: history.__setitem__(m.header.stamp.to_nsec(), m), queue_size=100)
        gate_pub = rospy.Publisher("/frame_integrated", FrameIntegrated, queue_size=50)
        from sensor_msgs.msg import CameraInfo
        gate = {"open": True, "frame": None, "since": 0.0, "reports": {}, "unstuck": 0}

        def on_info(msg):  # one camera_info per frame, with the frame's stamp
            gate["frame"], gate["since"] = msg.header.stamp, time.time()

        def on_integrated(msg):
            n = msg.node.rsplit("/", 1)[-1]
            gate["reports"][n] = max(gate["reports"].get(n, 0), msg.header.stamp.to_nsec())
        rospy.Subscriber("/camera/camera_info", CameraInfo, on_info, queue_size=50)
        rospy.Subscriber("/frame_integrated", FrameIntegrated, on_integrated, queue_size=50)

        def pace():
            """Reports each frame as GATE while open (wall-timed: sim time stops
            while the simulator waits). A frame that a mapping node never got
            (its subscription still connecting when the first frame went out)
            would hold the simulator for good: after 3 s it is reported as
            handled-not-integrated on that node's behalf, and counted."""
            while gate["open"]:
                f = gate["frame"]
                if f is not None:
                    gate_pub.publish(FrameIntegrated(header=Header(stamp=f), node=GATE, integrated=True))
                    if time.time() - gate["since"] > 3.0:
                        for n in ("background_map", "object_map"):
                            if gate["reports"].get(n, 0) < f.to_nsec():
                                gate_pub.publish(FrameIntegrated(header=Header(stamp=f), node=n, integrated=False))
                                gate["unstuck"] += 1
                                gate["since"] = time.time()
                time.sleep(0.1)
        repeater = threading.Thread(target=pace, daemon=True)
        repeater.start()
        sim = _start(["roslaunch", "semantic_exploration", "sim_only.launch", "scene:=" + ply,
                      "overrides:=" + sim_overrides, "lockstep:=true", "real_time_factor:=0",
                      "lockstep_nodes:=[background_map, object_map, %s]" % GATE, "output:=log"], env,
                     os.path.join(work, "sim.log"))
        procs.append(sim)
        deadline = time.time() + 120.0
        while rospy.get_time() < SIM_S:
            assert sim.poll() is None, "the simulation stopped (see %s)" % os.path.join(work, "sim.log")
            assert time.time() < deadline, "the live run reached only %.1f s sim time" % rospy.get_time()
            time.sleep(0.2)
        gate["open"] = False
        repeater.join()
        time.sleep(3.0)  # the last frame reaches the maps and the bag; the simulator waits for the gate
        mission.call_save("/background_map/save", os.path.join(work, "live_map"))
        saved = mission.call_save("/object_map/save", os.path.join(work, "live_objects"))
        assert saved["success"], saved
        rs._stop(rec, grace_s=15.0)  # SIGINT: rosbag closes the bag
        last, n_frames = _bag_last_depth_stamp(bag)
        assert last is not None and n_frames > 0.5 * SIM_S * 10, "bag holds %d depth frames" % n_frames
        assert max(history) == last.to_nsec(), "the live map went on after the bag's last frame"
        return bag, history[last.to_nsec()], n_frames, gate["unstuck"]
    finally:
        for p in reversed(procs):
            rs._stop(p, grace_s=20.0)


def replay_phase(work, bag):
    """replay.launch on a fresh master; writes replay.json with the final stats."""
    import rviz_screenshot as rs
    import run_mission as mission
    overrides = os.path.join(work, "overrides.yaml")
    port = mission._free_port()
    env = _ros_env(port, os.path.join(work, "ros_home_replay"))
    launch = _start(["roslaunch", "-p", str(port), "semantic_exploration", "replay.launch", "bag:=" + bag,
                     "rate:=%g" % REPLAY_RATE, "overrides:=" + overrides, "classes_of_interest:=[chair]",
                     "output:=log"], env, os.path.join(work, "replay.log"))
    try:
        _wait_master(env, launch)
        rospy = _node_py(env, "replay_test_replay")
        from semantic_exploration.msg import MapStats
        latest = {}
        rospy.Subscriber("/background_map/stats", MapStats, lambda m: latest.__setitem__("s", m), queue_size=100)
        master = _wait_master(env, launch)
        deadline = time.time() + 150.0
        _wait_replay_done(master, launch, os.path.join(work, "replay.log"), deadline)
        mission.call_save("/background_map/save", os.path.join(work, "replay_map"))
        saved = mission.call_save("/object_map/save", os.path.join(work, "replay_objects"))
        assert saved["success"], saved
        s = latest["s"]
        with open(os.path.join(work, "replay.json"), "w") as f:
            json.dump({k: getattr(s, k) for k in ("explored_volume_m3", "occupied_volume_m3", "free_volume_m3",
                                                  "frames_integrated") + DROP_FIELDS}, f)
    finally:
        rs._stop(launch, grace_s=20.0)


def _wait_replay_done(master, launch, log, deadline):
    """Waits until replay.launch's rosbag play has started and ended (it runs
    until the bag ends), then 2 s for the last frames and stats."""
    _wait_subscribed(master, "/clock", "/background_map", timeout_s=60.0)
    while not any(n.startswith("/play") for n in _nodes(master)):
        assert time.time() < deadline, "rosbag play did not start"
        time.sleep(0.2)
    while any(n.startswith("/play") for n in _nodes(master)):
        assert launch.poll() is None, "replay.launch stopped (see %s)" % log
        assert time.time() < deadline, "the replay did not finish"
        time.sleep(0.5)
    time.sleep(2.0)


def _nodes(master):
    pubs, subs, srvs = master.getSystemState()
    return {n for group in (pubs, subs, srvs) for _, nodes in group for n in nodes}


def _run_phase(args, log, timeout_s=240.0):
    """Runs one phase of this file in a child process; on timeout SIGINT lets
    it stop what it started (its finally blocks). Returns (exit code, output)."""
    import rviz_screenshot as rs
    with open(log, "w") as f:
        proc = subprocess.Popen([sys.executable, __file__] + args, stdout=f, stderr=subprocess.STDOUT,
                                start_new_session=True)
        try:
            code = proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            rs._stop(proc, grace_s=90.0)
            code = "timeout after %.0f s" % timeout_s
    with open(log) as f:
        return code, f.read()


@pytest.mark.skipif(not ROS_SOURCED, reason="ROS environment (roslaunch, rosbag) not sourced")
def test_replay_matches_live(tmp_path):
    work = str(tmp_path)
    t0 = time.time()
    # each phase in its own process: rospy allows one node per process and one master
    live = _run_phase(["live", work], os.path.join(work, "live_phase.log"))
    print(live[1])
    assert live[0] == 0, live[1]
    with open(os.path.join(work, "live.json")) as f:
        lv = json.load(f)
    rp = _run_phase(["replay", work, lv["bag"]], os.path.join(work, "replay_phase.log"))
    print(rp[1])
    assert rp[0] == 0, rp[1]
    with open(os.path.join(work, "replay.json")) as f:
        rv = json.load(f)
    print("live at the bag's last frame: %s\nreplay: %s\nwall time %.0f s" % (lv["stats"], rv, time.time() - t0))
    # the replay handles every frame of the bag (nothing lost to a queue) but the
    # first: its depth image may come before any camera_info or the first tf
    # (counted, or once in six runs not counted; the maps were identical each time)
    assert rv["frames_integrated"] + sum(rv[k] for k in DROP_FIELDS) >= lv["n_frames"] - 1, (rv, lv["n_frames"])
    assert rv["dropped_no_camera_info"] + rv["dropped_no_tf"] <= STARTUP_FRAMES, rv
    assert rv["dropped_bad_depth"] == rv["dropped_size_mismatch"] == rv["dropped_out_of_bounds"] == 0, rv
    # the bag may lack the live run's first frame: rosbag record (sim time) drops
    # what arrives before the first /clock
    # at most the startup frames are missing from the live map (their reports were made for it)
    assert lv["unstuck"] <= STARTUP_FRAMES
    assert lv["stats"]["frames_integrated"] >= lv["n_frames"] - STARTUP_FRAMES, (
        "live map integrated %d of the bag's %d frames" % (lv["stats"]["frames_integrated"], lv["n_frames"]))
    live_v = lv["stats"]["explored_volume_m3"]
    assert live_v > 1.0
    assert abs(rv["explored_volume_m3"] - live_v) <= VOLUME_TOL * live_v, (rv["explored_volume_m3"], live_v)
    live_occ, replay_occ = (_occupied(os.path.join(work, d, "occupied.ply")) for d in ("live_map", "replay_map"))
    differ = len(live_occ ^ replay_occ)
    print("occupied voxels: live %d, replay %d, in one only %d" % (len(live_occ), len(replay_occ), differ))
    assert differ <= VOLUME_TOL * len(live_occ)
    live_objs = _objects(os.path.join(work, "live_objects"))
    replay_objs = _objects(os.path.join(work, "replay_objects"))
    print("objects live %s\nobjects replay %s" % (
        [(o["class_name"], o["centroid"]) for o in live_objs], [(o["class_name"], o["centroid"]) for o in replay_objs]))
    assert len(replay_objs) == len(live_objs)
    unmatched = list(replay_objs)
    for o in live_objs:
        near = [r for r in unmatched if r["class_name"] == o["class_name"] and
                max(abs(a - b) for a, b in zip(r["centroid"], o["centroid"])) <= CENTROID_TOL_M]
        assert near, "live object %s has no replayed counterpart" % o
        unmatched.remove(near[0])


def _main(argv):
    phase, work = argv[0], argv[1]
    if phase == "live":
        bag, stats, n, unstuck = live_phase(work)
        with open(os.path.join(work, "live.json"), "w") as f:
            json.dump({"bag": bag, "n_frames": n, "unstuck": unstuck, "stats": {
                k: getattr(stats, k) for k in ("explored_volume_m3", "occupied_volume_m3", "free_volume_m3",
                                               "frames_integrated") + DROP_FIELDS}}, f)
    else:
        replay_phase(work, argv[2])
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))

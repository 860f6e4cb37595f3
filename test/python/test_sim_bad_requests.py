"""mav_sim against malformed requests (issue 15, items 9 and 10): a scene file
whose readers' own checks miss a defect is a rejected scene, not an exception
out of the simulator's loop; a path longer than mav/max_path_poses is rejected
from its header alone, before it is deserialised; a path is checked once, not
again on the physics loop. The last test runs mav_sim (roscore and
sim_only.launch) and sends it both, from a child process that records what
comes back. Skipped where ROS is not sourced."""
import json
import os
import shutil
import struct
import sys
import time

import numpy as np
import pytest

if __name__ == "__main__":  # a child process: no pytest to load conftest
    import conftest  # noqa: F401

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from semantic_exploration.sim.config import from_dict  # noqa: E402
from semantic_exploration.sim.scene import SceneError  # noqa: E402
from semantic_exploration.sim import simulator as simulator_module  # noqa: E402
from semantic_exploration.sim.simulator import PathError, load_simulator, path_pose_count  # noqa: E402

ROS_SOURCED = shutil.which("roslaunch") is not None and (
    "ROS_PACKAGE_PATH" in os.environ or "CMAKE_PREFIX_PATH" in os.environ)
EXAMPLE = os.path.join(ROOT, "test", "data", "example_semantic.ply")
HUGE = 1000000  # poses in the oversized path


def write_ascii_ply(path, vertex_props, face_props, face_rows):
    """A small ASCII PLY: 3 vertices of a triangle, `face_rows` lines for the face element."""
    lines = ["ply", "format ascii 1.0", "element vertex 3"] + ["property float %s" % p for p in vertex_props]
    lines += ["element face %d" % len(face_rows)] + face_props + ["end_header"]
    verts = {"x": (0, 1, 0), "y": (0, 0, 1), "z": (0, 0, 0)}
    for i in range(3):
        lines.append(" ".join(str(verts.get(p, (0, 0, 0))[i]) for p in vertex_props))
    lines += face_rows
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def malformed_scene(directory):
    """A PLY whose face element has only `object_id` (no vertex indices), with a JSON label table."""
    ply, labels = os.path.join(str(directory), "bad.ply"), os.path.join(str(directory), "bad.json")
    write_ascii_ply(ply, ["x", "y", "z"], ["property int object_id"], ["3"])
    with open(labels, "w") as f:
        json.dump({"3": "chair"}, f)
    return ply, labels


def test_malformed_scene_files_are_scene_errors(tmp_path, monkeypatch):
    ply, labels = malformed_scene(tmp_path)
    with pytest.raises(SceneError, match="face element lacks vertex_indices"):
        load_simulator(from_dict({}), ply, labels)
    write_ascii_ply(ply, ["x", "y"], ["property list uchar int vertex_indices", "property int object_id"],
                    ["3 0 1 2 3"])
    with pytest.raises(SceneError, match="vertex element lacks x/y/z"):
        load_simulator(from_dict({}), ply, labels)

    # Whatever else a reader trips over (KeyError, IndexError, AttributeError, TypeError) is a SceneError too.
    def broken(cfg):
        raise IndexError("index 3 is out of bounds for axis 0 with size 3")

    monkeypatch.setattr(simulator_module.Simulator, "from_config", staticmethod(broken))
    with pytest.raises(SceneError, match=r"malformed scene \(IndexError: index 3 is out of bounds"):
        load_simulator(from_dict({}), ply, labels)


def serialized_path(n_poses, frame="world", xyz=(0.5, 1.5, 1.2)):
    """nav_msgs/Path as ROS serialises it (header, then n PoseStamped with empty frame ids)."""
    head = struct.pack("<III", 0, 0, 0) + struct.pack("<I", len(frame)) + frame.encode() + struct.pack("<I", n_poses)
    pose = np.zeros(n_poses, dtype=[("hdr", "<u4", 4), ("p", "<f8", 3), ("q", "<f8", 4)])
    pose["p"] = xyz
    pose["q"][:, 3] = 1.0
    return head + pose.tobytes()


def test_path_length_is_read_from_the_header():
    assert path_pose_count(serialized_path(3)) == 3
    assert path_pose_count(serialized_path(HUGE, frame="")) == HUGE
    assert len(serialized_path(2)) == 16 + 5 + 4 + 2 * 72
    with pytest.raises(PathError, match="truncated"):
        path_pose_count(serialized_path(3)[:18])


def test_long_paths_are_rejected_and_a_checked_path_is_not_checked_again(monkeypatch):
    sim = load_simulator(from_dict({"mav": {"max_path_poses": 5}}), EXAMPLE)
    x, y, z, yaw = sim.start
    wps = [(x, y, z, yaw)] * 6
    with pytest.raises(PathError, match="6 poses are more than mav/max_path_poses = 5"):
        sim.check_path(wps)
    ok = sim.check_path(wps[:5])
    calls = []
    monkeypatch.setattr(sim, "check_path", lambda w: calls.append(len(w)) or list(w))
    sim.set_path(ok, checked=True)
    assert calls == []
    sim.set_path(ok)
    assert calls == [5]


def child(work):
    """Talks to mav_sim: a malformed scene, then a path of HUGE poses; writes events.json."""
    import rospy
    from nav_msgs.msg import Path
    from rosgraph_msgs.msg import Log
    from sensor_msgs.msg import Image
    from std_msgs.msg import String

    class RawPath(Path):
        """A Path published from bytes already serialised."""
        __slots__ = ["raw"]

        def serialize(self, buff):
            buff.write(self.raw)

    rospy.init_node("bad_requests_test", disable_signals=True)
    ev = {"frames": [], "rejected_paths": [], "scene_errors": [], "frames_after": []}
    phase = {"after": False}

    def on_depth(m):
        ev["frames"].append(m.header.stamp.to_sec())
        if phase["after"]:
            ev["frames_after"].append(m.header.stamp.to_sec())

    def on_log(m):
        if m.name.endswith("mav_sim") and "rejected scene" in m.msg:
            ev["scene_errors"].append(m.msg)

    rospy.Subscriber("/camera/depth/image_raw", Image, on_depth, queue_size=50)
    rospy.Subscriber("/mav/path_rejected", String, lambda m: ev["rejected_paths"].append(m.data), queue_size=10)
    rospy.Subscriber("/rosout", Log, on_log, queue_size=100)
    scene_pub = rospy.Publisher("/mav_sim/load_scene", String, queue_size=1, latch=True)
    path_pub = rospy.Publisher("/planner/path", RawPath, queue_size=1, latch=True)

    def wait(cond, timeout_s):
        end = time.time() + timeout_s
        while not cond() and time.time() < end:
            time.sleep(0.05)
        return cond()

    wait(lambda: len(ev["frames"]) >= 5, 90.0)
    bad_ply, bad_json = malformed_scene(work)
    scene_pub.publish(String(bad_ply + ";" + bad_json))
    wait(lambda: ev["scene_errors"], 30.0)
    n_before = len(ev["frames"])
    wait(lambda: len(ev["frames"]) >= n_before + 5, 30.0)  # the main loop survived the scene
    msg = RawPath()
    msg.raw = serialized_path(HUGE)  # all poses at the start: in bounds
    path_pub.publish(msg)
    wait(lambda: ev["rejected_paths"], 60.0)
    phase["after"] = True
    wait(lambda: len(ev["frames_after"]) >= 20, 60.0)
    with open(os.path.join(work, "events.json"), "w") as f:
        json.dump(ev, f)


@pytest.mark.skipif(not ROS_SOURCED, reason="ROS environment (roslaunch) not sourced")
def test_mav_sim_survives_a_malformed_scene_and_a_huge_path(tmp_path):
    import sim_child
    work = str(tmp_path)
    procs = []
    try:
        env = sim_child.master(work, procs)
        procs.append(sim_child.start_sim(work, env, "scene:=" + EXAMPLE))
        kid = sim_child.start_child(__file__, work, env)
        procs.append(kid)
        ev = sim_child.child_events(kid, work, 240, "the child did not finish")
    finally:
        sim_child.stop_all(procs)
    print({k: v if not isinstance(v, list) else v[:5] + ["..."] for k, v in ev.items()})
    assert ev["scene_errors"] and "face element lacks vertex_indices" in ev["scene_errors"][0], ev["scene_errors"]
    assert ev["rejected_paths"], "the %d-pose path was not rejected" % HUGE
    assert "path of %d poses: more than mav/max_path_poses = 1000" % HUGE in ev["rejected_paths"][0]
    # Frames go on after both, one per 0.1 s of sim time (camera/rate_hz 10), none skipped.
    after = ev["frames_after"]
    assert len(after) >= 20, len(after)
    assert all(b - a == pytest.approx(0.1) for a, b in zip(after, after[1:])), after


if __name__ == "__main__":
    child(sys.argv[1])

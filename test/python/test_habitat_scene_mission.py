"""A mission on a Habitat-style scene the house generator did not make: an
L-shaped corridor between two rooms built from boxes (habitat_primitives.py),
loaded from its ``_semantic.ply`` + ``.house``. The paper's classic baseline
(frontiers only) must end it ``explored`` by its own rule (no active frontier
voxel left), without a collision. A loose check besides: the map's explored
volume (free plus occupied) is at least 90% of the ground truth's explorable
free volume; leaving room B (27 m^3 of the 55 m^3) unvisited would fail it.

One deterministic lockstep mission: about 350 s of sim time, 2-4 min of wall
time on the 2-core machine. Skipped where ROS is not sourced."""
import json
import os
import shutil
import signal
import subprocess
import sys

import pytest

import habitat_primitives

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ROS_SOURCED = shutil.which("roslaunch") is not None and (
    "ROS_PACKAGE_PATH" in os.environ or "CMAKE_PREFIX_PATH" in os.environ)
SIM_LIMIT_S = 600.0  # a backstop: the mission measured ends explored at about 350 s


def test_the_scene_loads_as_habitat_with_its_categories(tmp_path):
    from semantic_exploration.sim.scene import load_scene
    scene = load_scene(habitat_primitives.write(str(tmp_path)))
    # Our ids are the file's 0-based object indices + 1.
    assert scene.objects == {1: "wall", 2: "floor", 3: "ceiling", 4: "cabinet", 5: "table"}
    assert scene.start == habitat_primitives.START
    lo, hi = scene.bounds
    assert list(lo) == pytest.approx([-0.1, -0.1, -0.1])
    assert list(hi) == pytest.approx([7.6, 8.1, habitat_primitives.HEIGHT_M + 0.1])
    # Every face carries one of the five objects.
    assert set(int(i) for i in set(scene.face_object.tolist())) == {1, 2, 3, 4, 5}


@pytest.mark.skipif(not ROS_SOURCED, reason="ROS environment (roslaunch) not sourced")
def test_classic_mission_on_an_l_shaped_corridor_ends_explored(tmp_path):
    ply = habitat_primitives.write(str(tmp_path / "scene"))
    out = tmp_path / "run"
    env = {k: v for k, v in os.environ.items() if k != "ROS_HOME"}  # the run's logs in out/ros_home
    proc = subprocess.Popen([sys.executable, os.path.join(ROOT, "scripts", "run_mission.py"), "--deterministic",
                             "--scene", ply, "--mode", "classic", "--sim-limit-s", str(SIM_LIMIT_S),
                             "--wall-limit-s", "1100", "--no-eval", "--out", str(out), "--progress-period-s", "60"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                            start_new_session=True)
    try:  # within the guard on the whole pytest run (scripts/run_tests.sh)
        output, _ = proc.communicate(timeout=1200)
    except subprocess.TimeoutExpired:  # SIGINT: run_mission stops the nodes it started
        os.killpg(proc.pid, signal.SIGINT)
        try:
            output, _ = proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            output, _ = proc.communicate()
    assert proc.returncode == 0, output
    with open(str(out / "summary.json")) as f:
        s = json.load(f)
    assert s["termination_reason"] == "explored", output
    assert s["collisions"] == 0, output
    assert s["sim_time_s"] < SIM_LIMIT_S
    assert s["explored_volume_m3"] >= 0.9 * s["explorable_free_volume_m3"], output

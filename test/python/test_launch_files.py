"""Every launch file parses, resolves its includes and args, and starts the
nodes the README says it does (checked with `roslaunch --nodes`, which needs
no master). Skipped where the package is not built and sourced."""
import os
import shutil
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# the mapping nodes and the display cut for rviz
MAPPING = {"/background_map", "/instance_matching", "/object_map", "/depth_history", "/display_cut"}

pytestmark = pytest.mark.skipif(shutil.which("roslaunch") is None or "ROS_PACKAGE_PATH" not in os.environ
                                and "CMAKE_PREFIX_PATH" not in os.environ,
                                reason="ROS environment not sourced")


def nodes(launch, *args):
    proc = subprocess.run(["roslaunch", "--nodes", "semantic_exploration", launch] + list(args),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=60)
    assert proc.returncode == 0, proc.stdout
    return set(line.strip() for line in proc.stdout.splitlines() if line.startswith("/"))


def test_exploration_launch():
    assert nodes("exploration.launch") == MAPPING | {"/planner"}
    assert nodes("exploration.launch", "planner:=false") == MAPPING


def test_sim_launch():
    assert nodes("sim.launch") == MAPPING | {"/planner", "/mav_sim"}
    assert nodes("sim.launch", "rviz:=true", "mode:=classic") == MAPPING | {"/planner", "/mav_sim", "/rviz"}
    assert nodes("sim.launch", "follow:=setpoints") == MAPPING | {"/planner", "/mav_sim", "/setpoint_streamer"}


def test_onboard_launch():
    assert nodes("onboard.launch") == MAPPING | {"/planner", "/T_BC"}
    assert nodes("onboard.launch", "pose_topic:=/vicon/pose", "publish_T_BC:=false") == \
        MAPPING | {"/planner", "/pose_to_tf"}
    assert nodes("onboard.launch", "detector:=true", "detector_model:=/tmp/m.onnx") == \
        MAPPING | {"/planner", "/T_BC", "/detector"}
    assert nodes("onboard.launch", "setpoints:=true", "pose_topic:=/mavros/local_position/pose") == \
        MAPPING | {"/planner", "/T_BC", "/pose_to_tf", "/setpoint_streamer"}


def test_detector_launch():
    assert nodes("detector.launch", "model:=/tmp/m.onnx") == {"/detector"}


def test_replay_and_record_launch():
    assert nodes("replay.launch", "bag:=/tmp/x.bag") == MAPPING | {"/play"}
    assert nodes("replay.launch", "bag:=/tmp/x.bag", "detector:=true", "detector_model:=/tmp/m.onnx") == \
        MAPPING | {"/play", "/detector"}
    assert nodes("record.launch") == {"/record"}


def test_every_launch_file_is_covered():
    launches = sorted(f for f in os.listdir(os.path.join(ROOT, "launch")) if f.endswith(".launch"))
    assert launches == ["detector.launch", "exploration.launch", "onboard.launch", "record.launch", "replay.launch", "sim.launch",
                        "sim_only.launch"]
    assert nodes("sim_only.launch") == {"/mav_sim"}

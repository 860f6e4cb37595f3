"""Deterministic runs (run_mission.py --deterministic, make experiments' default): two
missions of the same scene, seed and settings write the same timeseries.csv, byte for
byte, but for the columns that measure wall time.

Two lockstep missions of about 60 s of sim time in a generated 6 x 5 m house,
scored (the snapshot columns too): about 4 min wall on an idle 2-core machine.
Skipped where ROS is not sourced. Without --deterministic the two series differ
from the first path on (the planner's path arrives at a sim time set by the
machine's load)."""
import csv
import glob
import io
import json
import os
import shutil
import signal
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ROS_SOURCED = shutil.which("roslaunch") is not None and (
    "ROS_PACKAGE_PATH" in os.environ or "CMAKE_PREFIX_PATH" in os.environ)

#: columns that measure wall time (the run's clock, planning and integration time)
WALL_COLUMNS = {"wall_s", "planning_time_s", "integration_time_ms"}
SIM_LIMIT_S = 60.0


def without_wall_columns(path):
    """The file's text with the wall-time columns cut out, every other field as written."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    keep = [i for i, name in enumerate(rows[0]) if name not in WALL_COLUMNS]
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    for r in rows:
        w.writerow([r[i] for i in keep])
    return out.getvalue()


def mission(out):
    env = {k: v for k, v in os.environ.items() if k != "ROS_HOME"}  # the run's logs in out/ros_home
    proc = subprocess.Popen([sys.executable, os.path.join(ROOT, "scripts", "run_mission.py"), "--deterministic",
                             "--size", "6", "5", "3", "--seed", "0", "--sim-limit-s", str(SIM_LIMIT_S),
                             "--wall-limit-s", "400", "--out", str(out), "--progress-period-s", "30"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                            start_new_session=True)
    try:
        output, _ = proc.communicate(timeout=600)
    except subprocess.TimeoutExpired:  # SIGINT: run_mission stops the nodes it started
        os.killpg(proc.pid, signal.SIGINT)
        output, _ = proc.communicate(timeout=60)
    assert proc.returncode == 0, output
    return output


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("deterministic")
    return [(tmp / name, mission(tmp / name)) for name in ("a", "b")]


@pytest.mark.skipif(not ROS_SOURCED, reason="ROS environment (roslaunch) not sourced")
def test_two_deterministic_missions_write_the_same_time_series(two_runs):
    (a, out_a), (b, out_b) = two_runs
    for d, output in two_runs:
        with open(str(d / "summary.json")) as f:
            s = json.load(f)
        assert s["termination_reason"] == "sim_time_limit", output
        assert "deterministic" in s["planner_timing"] and "iterations" in s["planner_timing"]
        assert "| planner timing | OMPL stops after 1000 iterations per candidate; deterministic" in (
            d / "report.md").read_text()
        sim_log = "".join(open(p).read() for p in glob.glob(str(d / "ros_home" / "log" / "*" / "mav_sim*.log")))
        assert "mav_sim: following a path" in sim_log  # the simulator's log was found
        # Neither a lockstep timeout nor a path that did not come: each would let sim time run on.
        assert "lockstep: no frame_integrated" not in sim_log and "lockstep_planner:" not in sim_log
    text_a, text_b = without_wall_columns(str(a / "timeseries.csv")), without_wall_columns(str(b / "timeseries.csv"))
    rows = text_a.splitlines()
    # A row a second from 0 s to the stop (the first frame after 60 s) plus the last one, with every panel's column.
    assert len(rows) >= 1 + 61 + 1, text_a
    for col in ("explored_volume_m3", "ground_truth_found", "object_observed_share", "background_observed_share",
                "path_length_m", "background_rmse_m", "background_completeness"):
        assert col in rows[0].split(","), rows[0]
    assert float(rows[-1].split(",")[rows[0].split(",").index("path_length_m")]) > 1.0  # the MAV flew
    assert text_a == text_b

"""Bad input end to end (issue 7): a short lockstep mission (run_mission.py) of a
generated 6 x 5 m house with all three simulator faults at once -- 2 s of sim
time without world->body tf, a detector whose instance images have half the
depth resolution, 10% of camera frames not sent -- completes, writes its report,
and counts each kind of drop, consistent with what the simulator injected
(the simulator publishes its own fault counts on /mav_sim/faults).

About 1 min wall on an idle 2-core machine. Skipped where ROS is not sourced."""
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

SIM_LIMIT_S = 12.0
TF_GAP_S = (4.0, 6.0)  # sim time (the clock starts at 1 s); frames at 10 Hz
DETECTOR_SCALE = 0.5
FRAME_DROP = 0.1


@pytest.mark.skipif(not ROS_SOURCED, reason="ROS environment (roslaunch) not sourced")
def test_mission_with_faults_completes_and_counts_drops(tmp_path):
    faults = tmp_path / "faults.yaml"
    faults.write_text("faults:\n  tf_gap_s: [%g, %g]\n  detector_scale: %g\n  frame_drop_fraction: %g\n  seed: 3\n"
                      % (TF_GAP_S + (DETECTOR_SCALE, FRAME_DROP)))
    out = tmp_path / "run"
    env = dict(os.environ, ROS_HOME=str(tmp_path / "ros_home"))
    proc = subprocess.Popen([sys.executable, os.path.join(ROOT, "scripts", "run_mission.py"), "--size", "6", "5", "3",
                             "--sim-limit-s", str(SIM_LIMIT_S), "--wall-limit-s", "150", "--out", str(out),
                             "--sim-overrides", str(faults), "--progress-period-s", "5", "--no-eval"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                            start_new_session=True)
    try:
        output, _ = proc.communicate(timeout=240)
    except subprocess.TimeoutExpired:  # SIGINT: run_mission stops the nodes it started
        os.killpg(proc.pid, signal.SIGINT)
        output, _ = proc.communicate(timeout=60)
    print(output)
    assert proc.returncode == 0, output
    with open(out / "summary.json") as f:
        summary = json.load(f)
    assert summary["termination_reason"] == "sim_time_limit", summary["termination_reason"]
    report = (out / "report.md").read_text()
    drops = summary["dropped_input"]
    by_node, injected = drops["by_node"], drops["injected"]
    print(json.dumps(drops, indent=1))
    bg = by_node["background_map"]

    # tf gap: every frame sent inside it is dropped for want of a pose, by each
    # node that needs one. The gap's last frame may get a pose after all: the
    # simulator's physics runs on to the next frame while the nodes handle this
    # one, and tf2 then interpolates across the gap.
    n_gap = injected["frames_without_tf"]
    frames_in_gap = round((TF_GAP_S[1] - TF_GAP_S[0]) * 10) + 1
    assert frames_in_gap - 6 <= n_gap <= frames_in_gap  # minus the gap's frames that were not sent at all
    assert injected["poses_withheld"] >= n_gap
    for node in ("background_map", "object_map", "depth_history"):
        assert n_gap - 1 <= by_node[node].get("no_tf", 0) <= n_gap, (node, by_node[node], n_gap)

    # frame drops: the background map infers them from gaps in the depth stamps;
    # a frame dropped before the first or after the last one it got is invisible
    # to it, and so may be one while it still learns the camera period.
    n_dropped = injected["frames_dropped"]
    assert n_dropped > 0
    assert n_dropped - 3 <= bg.get("frame_gap", 0) <= n_dropped, (bg, n_dropped)

    # detector at another resolution: instance_matching refuses every such frame
    # (it reaches it before the tf check, so frames in the gap count here too).
    n_scaled = injected["detections_rescaled"]
    assert n_scaled >= 0.5 * (SIM_LIMIT_S - 1.0) * 10
    im = by_node["instance_matching"].get("size_mismatch", 0)
    assert n_scaled - 2 <= im <= n_scaled, (im, n_scaled)
    assert bg.get("size_mismatch", 0) == 0  # depth itself keeps its size

    # the report names each reason with its count
    assert "## Dropped input" in report
    headline = [line for line in report.splitlines() if line.startswith("dropped: ")][0]
    for what, n in (("depth frames without tf", bg["no_tf"]), ("camera frames missing", bg["frame_gap"]),
                    ("detection frames with mismatched size", im)):
        assert "%d %s" % (n, what) in headline, headline
    assert "| instance_matching | size_mismatch | %d |" % im in report

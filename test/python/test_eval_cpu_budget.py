"""The onboard CPU budget of a run's report (eval/cpu_budget.py through RunLog and
eval/report.py write_report) on a hand-built series of frame_integrated reports
with known medians, 95th percentiles and shares of one core."""
import argparse
import json
import random
from types import SimpleNamespace

import pytest

from semantic_exploration.eval import report as run_report
from semantic_exploration.eval.cpu_budget import CpuBudget, nearest_rank
from semantic_exploration.eval.runlog import RunLog


def report(node, stamp_s, cpu_ms):
    """A FrameIntegrated as RunLog reads it (fields by name)."""
    stamp = SimpleNamespace(to_sec=lambda: stamp_s)
    return SimpleNamespace(node=node, header=SimpleNamespace(stamp=stamp), integrated=True, cpu_ms=cpu_ms)


def recorded_run():
    """20 frames at 10 Hz. background_map: 1..20 ms shuffled (median = rank 10 -> 10 ms, p95 = rank 19
    -> 19 ms, mean 10.5 ms: 10.5% of one core at 10 Hz); object_map: 10 frames of 5 ms (5%);
    instance_matching: nine of 1 ms and one of 11 ms (median 1, p95 = rank 10 -> 11, mean 2: 2%);
    depth_history: 20 of 0.5 ms (0.5%). Total 18%. The mission's own lockstep reports do not count."""
    log = RunLog()
    bg = list(range(1, 21))
    random.Random(3).shuffle(bg)
    for i in range(20):
        t = 100.0 + 0.1 * i
        log.handle("/frame_integrated", report("/background_map", t, bg[i]))
        log.handle("/frame_integrated", report("/robot/depth_history", t, 0.5))  # any namespace
        log.handle("/frame_integrated", report("mission", t, 1000.0))
        if i % 2 == 0:
            log.handle("/frame_integrated", report("object_map", t, 5.0))
    for i, ms in enumerate([1.0] * 9 + [11.0]):
        log.handle("/frame_integrated", report("instance_matching", 100.0 + 0.2 * i, ms))
    return log


def test_nearest_rank():
    assert nearest_rank([], 50) == 0.0
    assert nearest_rank([4.5], 95) == 4.5
    assert nearest_rank([3.0, 1.0, 2.0, 4.0], 50) == 2.0   # rank ceil(2)
    assert nearest_rank([3.0, 1.0, 2.0, 4.0], 95) == 4.0   # rank ceil(3.8)


@pytest.mark.parametrize("rate_hz", [10.0, None])  # None: the rate of background_map's frames (10 Hz here)
def test_medians_p95_and_shares_of_a_recorded_series(rate_hz):
    s = recorded_run().cpu.summary(rate_hz)
    assert s["camera_rate_hz"] == pytest.approx(10.0)
    assert s["camera_rate_source"] == ("configured" if rate_hz else "measured")
    n = s["nodes"]
    assert list(n) == ["background_map", "object_map", "instance_matching", "depth_history"]
    assert (n["background_map"]["frames"], n["background_map"]["median_ms"], n["background_map"]["p95_ms"]) == \
        (20, 10.0, 19.0)
    assert n["background_map"]["core_share"] == pytest.approx(0.105)
    assert (n["object_map"]["frames"], n["object_map"]["median_ms"], n["object_map"]["p95_ms"]) == (10, 5.0, 5.0)
    assert n["object_map"]["core_share"] == pytest.approx(0.05)
    assert (n["instance_matching"]["median_ms"], n["instance_matching"]["p95_ms"]) == (1.0, 11.0)
    assert n["instance_matching"]["mean_ms"] == pytest.approx(2.0)
    assert n["instance_matching"]["core_share"] == pytest.approx(0.02)
    assert n["depth_history"]["core_share"] == pytest.approx(0.005)
    assert s["total_core_share"] == pytest.approx(0.18)
    assert s["target_holds"] is True
    assert s["target_line"] == "CPU target (mapping nodes at most 25.0% of one core): holds (18.0% of one core " \
                               "at 10 Hz)"


def test_over_the_target_and_without_reports():
    b = CpuBudget()
    for i in range(10):
        b.add("background_map", 0.1 * i, 30.0)  # 30 ms a frame at 10 Hz: 30% of one core
    s = b.summary(10.0)
    assert s["total_core_share"] == pytest.approx(0.30) and s["target_holds"] is False
    assert "does NOT hold (30.0% of one core at 10 Hz)" in s["target_line"]
    empty = CpuBudget().summary(10.0)
    assert empty["total_core_share"] is None and empty["target_holds"] is None
    assert "not measured" in empty["target_line"]


def test_report_and_summary_carry_the_cpu_table(tmp_path):
    gt_dir = tmp_path / "gt"
    gt_dir.mkdir()
    gt = {"scene": "house", "objects": [], "gt_dir": str(gt_dir)}
    args = argparse.Namespace(mode="semantic", seed=0, classes=["chair"], no_eval=True, camera_rate_hz=10.0)
    run_report.write_report(str(tmp_path), args, gt, recorded_run(), {}, 2.0, 5.0, "explored", None)
    report_lines = (tmp_path / "report.md").read_text().splitlines()
    i = report_lines.index("## Onboard CPU budget")
    table = report_lines[i:i + 14]
    assert "| background_map | 20 | 10.00 | 19.00 | 10.50 | 10.5% |" in table
    assert "| object_map | 10 | 5.00 | 5.00 | 5.00 | 5.0% |" in table
    assert "| instance_matching | 10 | 1.00 | 11.00 | 2.00 | 2.0% |" in table
    assert "| depth_history | 20 | 0.50 | 0.50 | 0.50 | 0.5% |" in table
    assert "| total | | | | | 18.0% |" in table
    assert "CPU target (mapping nodes at most 25.0% of one core): holds (18.0% of one core at 10 Hz)" in table
    s = json.loads((tmp_path / "summary.json").read_text())["cpu_budget"]
    assert s["nodes"]["background_map"]["p95_ms"] == 19.0 and s["total_core_share"] == pytest.approx(0.18)

"""The run report (eval/report.py) names the detector the simulator ran with."""
import argparse
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
from semantic_exploration.eval import report as run_report  # noqa: E402
from semantic_exploration.eval.runlog import RunLog  # noqa: E402


def test_detector_source(tmp_path):
    faults = tmp_path / "faults.yaml"
    faults.write_text("faults:\n  frame_drop_fraction: 0.1\n")
    assert run_report.detector_of("", 1200) == {"min_mask_pixels": 1200, "source": "config/sim.yaml"}
    assert run_report.detector_of(str(faults), 1200)["source"] == "config/sim.yaml"
    long_range = os.path.join(ROOT, "config", "detector_long_range.yaml")
    assert run_report.detector_of(long_range, 50) == {"min_mask_pixels": 50, "source": "detector_long_range.yaml"}


def test_report_and_summary_name_the_detector(tmp_path):
    gt_dir = tmp_path / "gt"
    gt_dir.mkdir()
    gt = {"scene": "house", "objects": [], "gt_dir": str(gt_dir)}
    args = argparse.Namespace(mode="semantic", seed=0, classes=["chair"], no_eval=True)
    det = {"min_mask_pixels": 1200, "source": "config/sim.yaml"}
    run_report.write_report(str(tmp_path), args, gt, RunLog(), {}, 10.0, 5.0, "explored", det)
    report = (tmp_path / "report.md").read_text().splitlines()
    assert "| detector | masks of at least 1200 px (config/sim.yaml; a whole chair detected from about 4 m) |" \
        in report
    assert json.loads((tmp_path / "summary.json").read_text())["detector"] == det
    run_report.write_report(str(tmp_path), args, gt, RunLog(), {}, 10.0, None, "end of bag")
    assert "| detector | unknown |" in (tmp_path / "report.md").read_text().splitlines()


def test_report_marks_the_objects_the_planner_retired(tmp_path):
    from types import SimpleNamespace as NS
    gt_dir = tmp_path / "gt"
    gt_dir.mkdir()
    gt = {"scene": "house", "objects": [], "gt_dir": str(gt_dir)}
    args = argparse.Namespace(mode="semantic", seed=0, classes=["chair"], no_eval=True)
    log = RunLog()
    log._on_status(NS(object_ids=[3, 5], retired_object_ids=[5], state=2, iteration=7))
    log._on_status(NS(object_ids=[], retired_object_ids=[], state=1, iteration=8))  # "planning": no lists
    log.objects = NS(objects=[NS(id=i, class_name="chair", centroid=NS(x=0.0, y=0.0, z=0.0), voxel_count=10,
                                 observed_fraction=f) for i, f in ((3, 0.95), (5, 0.87))])
    run_report.write_report(str(tmp_path), args, gt, log, {}, 10.0, 5.0, "explored")
    report = (tmp_path / "report.md").read_text().splitlines()
    assert "| 3 | chair | (0.00, 0.00, 0.00) | 10 | 95% | no |" in report
    assert "| 5 | chair | (0.00, 0.00, 0.00) | 10 | 87% | yes |" in report
    assert json.loads((tmp_path / "summary.json").read_text())["retired_objects"] == [5]

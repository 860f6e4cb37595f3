"""One report over campaigns already flown (eval/pool.py, run_experiments.py
--pool): runs paired across campaigns, DIR:MODE, the checks that keep a
pooled report honest (unreadable runs, repeated names, differing setups)
and the options --pool refuses."""
import json
import os
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
import run_experiments  # noqa: E402
from semantic_exploration.eval import pool  # noqa: E402

pytest.importorskip("matplotlib")


def flown(campaign, name, found_at_s, n_gt=2, end_s=200):
    """A run directory <campaign>/runs/<name> as run_mission.py leaves it: all found at found_at_s."""
    d = os.path.join(campaign, "runs", name)
    os.makedirs(d)
    with open(os.path.join(d, "timeseries.csv"), "w") as f:
        f.write("sim_s,explored_volume_m3,ground_truth_found\n0,0,0\n%d,5,%d\n%d,9,%d\n" % (
            found_at_s, n_gt, end_s, n_gt))
    with open(os.path.join(d, "summary.json"), "w") as f:
        json.dump({"ground_truth_objects": n_gt, "termination_reason": "sim_time_limit", "collisions": 0}, f)
    return d


def report_of(campaign, *lines):
    with open(os.path.join(campaign, "report.md"), "w") as f:
        f.write("# Experiment report\n\n" + "".join("- %s\n" % l for l in lines) + "- detector: x\n\nMedian ...\n")


def no_mission(cmd):
    raise AssertionError("--pool flies nothing")


@pytest.fixture
def two_campaigns(tmp_path):
    a, b = str(tmp_path / "houses_0_1"), str(tmp_path / "houses_2")
    for name, t in (("scene0_run0_semantic", 20), ("scene0_run0_classic", 40), ("scene1_run0_semantic", 30),
                    ("scene1_run0_classic", 50)):
        flown(a, name, t)
    flown(b, "scene2_run0_semantic", 90, end_s=400)  # flown with a longer limit
    flown(b, "scene2_run0_classic", 60, end_s=400)
    report_of(a, "scenes: generated seed 0, generated seed 1 (generated houses 8 x 6 x 3 m)",
              "protocol default: 1 run per method and scene (planner seeds 1-1), classes chair, 200 s sim per run")
    return a, b


def test_runs_pair_across_campaigns(tmp_path, two_campaigns):
    a, b = two_campaigns
    out = str(tmp_path / "pooled")
    assert run_experiments.main(["--pool", a, b, "--out", out], call=no_mission) == 0
    report = open(os.path.join(out, "report.md")).read()
    assert "- pooled: 4 runs of %s; scenes: generated seed 0, generated seed 1" % a in report
    assert "- pooled: 2 runs of %s\n" % b in report
    # medians over three runs per mode (30 against 50 s); the pairs cross the two campaigns
    assert ("semantic 30 s, classic 50 s (medians); in 3 paired runs semantic sooner in 2, later in 1, tied in 0 "
            "(two-sided sign test p = 1.000") in report
    # with a limit, b's runs (to 400 s) are left out as having run past it
    assert run_experiments.main(["--pool", a, b, "--sim-limit-s", "200", "--out", out], call=no_mission) == 0
    assert "in 2 paired runs" in open(os.path.join(out, "report.md")).read()


def test_an_ablation_against_another_campaigns_classic_runs(tmp_path, two_campaigns):
    a, b = two_campaigns
    ablation = str(tmp_path / "ablation")
    flown(ablation, "scene0_run0_semantic", 45)
    flown(ablation, "scene2_run0_semantic", 55)
    protocol = "protocol default: 1 run per method and scene (planner seeds 1-1), classes chair, 200 s sim per run"
    report_of(ablation, "scenes: generated seed 0 (generated houses 8 x 6 x 3 m)", protocol,
              "node overrides (--extra-overrides): no_bg.yaml (planner/a_bg 0.0)")
    report_of(b, "scenes: generated seed 2 (generated houses 8 x 6 x 3 m)", protocol,
              "node overrides (--extra-overrides): none")
    out = str(tmp_path / "pooled")
    assert run_experiments.main(["--pool", ablation, a + ":classic", b + ":classic", "--out", out],
                                call=no_mission) == 0
    report = open(os.path.join(out, "report.md")).read()
    assert "- pooled: 2 classic runs of %s; scenes: generated seed 0, generated seed 1" % a in report
    assert "in 2 paired runs semantic sooner in 1, later in 1, tied in 0" in report  # 45 s against 40 s (later), 55 s against 60 s (sooner)
    assert "- the pooled campaigns differ in: node overrides (pairs compare runs flown under" in report


def test_runs_that_cannot_be_paired_or_read(tmp_path, two_campaigns, capsys):
    a, b = two_campaigns
    os.remove(os.path.join(flown(b, "scene3_run0_semantic", 10), "summary.json"))  # a mission stopped midway
    rc, msgs = pool.pool_report([(a, None), (b, None)], ["classic", "semantic"], str(tmp_path / "out"))
    assert rc == 0 and any("scene3_run0_semantic has no timeseries.csv or summary.json" in m for m in msgs)
    empty = str(tmp_path / "empty")  # a campaign whose missions all failed
    os.makedirs(os.path.join(empty, "runs"))
    rc, msgs = pool.pool_report([(a, None), (b, None), (empty, None)], ["classic", "semantic"], str(tmp_path / "out"))
    assert rc == 0 and "no usable runs in %s" % empty in msgs
    flown(b, "scene0_run0_classic", 10)  # the same run name in both: pairs would be ambiguous
    rc, msgs = pool.pool_report([(a, None), (b, None)], ["classic", "semantic"], str(tmp_path / "out"))
    assert rc == 1 and "run scene0_run0_classic is in both %s and %s" % (a, b) in msgs[-1]


def test_entries_and_options_refused_at_start(tmp_path, two_campaigns, capsys):
    a, _ = two_campaigns
    modes = ["classic", "semantic"]
    assert pool.parse_entry(a + ":classic", modes) == (a, "classic", "")
    assert pool.parse_entry(a + "/", modes) == (a + "/", None, "")
    odd = tmp_path / "run:classic"  # a campaign directory whose own name ends like DIR:MODE
    os.makedirs(str(odd / "runs"))
    assert pool.parse_entry(str(odd), modes) == (str(odd), None, "")
    named = tmp_path / "classic"  # a directory named like a mode
    os.makedirs(str(named / "runs"))
    assert pool.parse_entry(str(named), modes) == (str(named), None, "")
    assert "clasic is not one of --modes" in pool.parse_entry(a + ":clasic", modes)[2]
    for argv, why in ((["--pool", str(tmp_path / "nothing")], "has no runs/ directory"),
                      (["--pool", a + ":clasic"], "clasic is not one of --modes (classic semantic)"),
                      (["--pool", a, "--out", os.path.join(a, "again")], "lies in the pooled campaign"),
                      (["--pool", a, "--out", a], "lies in the pooled campaign"),
                      (["--pool", a, "--jobs", "2", "--scenes", "4"], "--pool flies nothing: drop --scenes --jobs"),
                      (["--pool", a, "--out", str(named)], "holds a campaign (runs/)")):
        with pytest.raises(SystemExit):
            run_experiments.parse_args(argv)
        assert why in capsys.readouterr().err


def test_setups_that_differ_are_named():
    house = "scenes: generated seed 0 (generated houses %s)"
    same = pool.shared_setup([house % "8 x 6 x 3 m", "simulator overrides: none"])
    other = pool.shared_setup([house % "10 x 8 x 3 m", "simulator overrides: none"])
    assert same == {"house size": "8 x 6 x 3 m", "simulator overrides": "none", "classes and sim limit": "not stated",
                    "node overrides": "not stated", "planner timing": "not stated"}
    assert pool.differences([same, other]) == ["house size"]
    assert pool.differences([same, same, pool.shared_setup([])]) == []  # a campaign without a report states nothing
    # a report from before --extra-overrides existed against an ablation's
    ablation = pool.shared_setup([house % "8 x 6 x 3 m", "simulator overrides: none",
                                  "node overrides (--extra-overrides): no_bg.yaml (planner/a_bg 0.0)"])
    assert pool.differences([same, ablation]) == ["node overrides"]

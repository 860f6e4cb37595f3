"""scripts/run_experiments.py: scenes from generator seeds and scene files, the paper's
protocol (5 runs per method per scene), deterministic runs by default."""
import json
import os
import sys

import pytest
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
import run_experiments  # noqa: E402
from semantic_exploration.eval import experiments, overrides  # noqa: E402

DATA = os.path.join(HERE, "..", "data")
PLY = os.path.abspath(os.path.join(DATA, "example_semantic.ply"))


def test_paper_protocol_runs_five_per_method_and_scene_on_seeds_and_files(tmp_path):
    args = run_experiments.parse_args(["--scenes", "3", PLY, "--protocol", "paper"])
    assert args.runs == 5
    plan = run_experiments.plan_runs(args, str(tmp_path), "/x")
    assert len(plan) == 2 * 5 * 2
    assert [(r["scene"], r["run"], r["mode"]) for r in plan[:3]] == [
        ("scene3", 0, "classic"), ("scene3", 0, "semantic"), ("scene3", 1, "classic")]
    gen, loaded = plan[0]["cmd"], plan[10]["cmd"]
    assert gen[gen.index("--seed") + 1] == "3" and gen[gen.index("--size") + 1:gen.index("--size") + 4] == [
        "8.0", "6.0", "3.0"]
    assert "--scene" not in gen
    assert loaded[loaded.index("--scene") + 1] == PLY and "--seed" not in loaded and "--size" not in loaded
    assert plan[10]["scene"] == "example" and plan[10]["dir"] == os.path.join(
        str(tmp_path), "runs", "example_run0_classic")
    assert sorted({r["planner_seed"] for r in plan}) == [1, 2, 3, 4, 5]
    assert all("--deterministic" in r["cmd"] for r in plan)


def test_default_protocol_and_options():
    args = run_experiments.parse_args([])
    assert args.runs == 3 and [s["seed"] for s in args.scenes] == [0, 1, 2] and args.ompl_termination == "iterations"
    assert run_experiments.parse_args(["--runs", "2"]).runs == 2
    assert run_experiments.parse_args(["--protocol", "paper", "--runs", "5"]).runs == 5
    # The wall-time guard is run_mission.py's own (3 x the sim limit) unless given.
    cmd = run_experiments.plan_runs(args, "/o", "/x")[0]["cmd"]
    assert "--wall-limit-s" not in cmd and cmd[cmd.index("--sim-limit-s") + 1] == "200.0"
    given = run_experiments.parse_args(["--wall-limit-s", "5000", "--sim-limit-s", "2700"])
    cmd = run_experiments.plan_runs(given, "/o", "/x")[0]["cmd"]
    assert cmd[cmd.index("--wall-limit-s") + 1] == "5000.0" and cmd[cmd.index("--sim-limit-s") + 1] == "2700.0"
    assert args.jobs == 1
    timed = run_experiments.parse_args(["--ompl-termination", "time", "--scenes", "1"])
    assert all("--deterministic" not in r["cmd"] for r in run_experiments.plan_runs(timed, "/o", "/x"))


def test_bad_scenes_and_conflicting_runs_are_refused(capsys):
    with pytest.raises(SystemExit):
        run_experiments.parse_args(["--scenes", "no_such_scene_semantic.ply"])
    assert "neither a generator seed nor an existing scene file" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        run_experiments.parse_args(["--protocol", "paper", "--runs", "3"])
    assert "--protocol paper runs 5 runs per method per scene" in capsys.readouterr().err
    for bad, why in ((["--jobs", "0"], "--jobs must be at least 1"),
                     (["--sim-limit-s", "0"], "--sim-limit-s must be > 0"),
                     (["--wall-limit-s", "-5"], "--wall-limit-s must be > 0")):
        with pytest.raises(SystemExit):
            run_experiments.parse_args(bad)
        assert why in capsys.readouterr().err


def test_campaign_runs_every_mission_and_names_the_protocol(tmp_path):
    # The missions stand in: each writes a two-row time series; the campaign aggregates all 20.
    calls = []

    def fake_mission(cmd):
        calls.append(cmd)
        d = cmd[cmd.index("--out") + 1]
        os.makedirs(d)
        with open(os.path.join(d, "timeseries.csv"), "w") as f:
            f.write("sim_s,explored_volume_m3,ground_truth_found\n0,0,0\n10,5,%d\n" % (2 if "semantic" in cmd else 1))
        with open(os.path.join(d, "summary.json"), "w") as f:
            json.dump({"ground_truth_objects": 2, "termination_reason": "explored", "collisions": 0}, f)
        return 0

    pytest.importorskip("matplotlib")
    out = str(tmp_path / "campaign")
    assert run_experiments.main(["--scenes", "0", PLY, "--protocol", "paper", "--out", out], call=fake_mission) == 0
    assert len(calls) == 20
    with open(os.path.join(out, "runs", "planner_seed4.yaml")) as f:
        assert yaml.safe_load(f) == {"planner": {"seed": 5}}
    report = open(os.path.join(out, "report.md")).read()
    assert "- scenes: generated seed 0, example_semantic.ply (generated houses 8 x 6 x 3 m)" in report
    assert "- protocol paper: 5 runs per method and scene (planner seeds 1-5)" in report
    assert "| semantic | 10 | 100% |" in report and "| classic | 10 | 50% |" in report


def test_extra_overrides_reach_every_run_under_its_seed(tmp_path, capsys):
    extra = tmp_path / "no_background_gain.yaml"
    extra.write_text("planner:\n  a_ent: 0.5\n  a_bg: 0.0\n  a_obj: 0.5\n  yaw_step: !degrees 30\n"
                     "background_map:\n  gain_threads: 1\n")
    seen = {}

    def fake_mission(cmd):
        with open(cmd[cmd.index("--extra-overrides") + 1]) as f:
            seen[cmd[cmd.index("--out") + 1]] = f.read()
        return 1  # no time series: the campaign has nothing to aggregate

    out = str(tmp_path / "campaign")
    args = ["--scenes", "0", "--runs", "2", "--modes", "semantic", "--extra-overrides", str(extra), "--out", out]
    assert run_experiments.main(args, call=fake_mission) == 1
    assert len(seen) == 2
    for run in (0, 1):
        path = os.path.join(out, "runs", "planner_seed%d.yaml" % run)
        assert seen[os.path.join(out, "runs", "scene0_run%d_semantic" % run)] == open(path).read()
        doc = overrides.load(path)
        assert doc == {"planner": {"a_ent": 0.5, "a_bg": 0.0, "a_obj": 0.5, "seed": run + 1, "yaw_step": "30"},
                       "background_map": {"gain_threads": 1}}
        assert doc["planner"]["yaw_step"].tag == "!degrees"  # kept for rosparam to evaluate
    setup = run_experiments.describe_setup(run_experiments.parse_args(args), "", experiments.describe_yaml)
    assert ("node overrides (--extra-overrides): no_background_gain.yaml (planner/a_ent 0.5, planner/a_bg 0.0, "
            "planner/a_obj 0.5, planner/yaw_step !degrees 30, background_map/gain_threads 1)") in setup
    refused = {"- 1\n": "--extra-overrides: ",  # not a mapping
               "planner:\n  seed: 99\n": "sets planner/seed: each run sets its own",
               "planner:\n  p_frontier: 1.0\n  v_max: 2.0\n": "sets planner/p_frontier, which config/classic.yaml",
               "planner: 3\n": "planner must be a section of settings, not 3"}
    for text, why in refused.items():
        bad = tmp_path / "bad.yaml"
        bad.write_text(text)
        with pytest.raises(SystemExit):
            run_experiments.parse_args(["--extra-overrides", str(bad)])  # classic among the default --modes
        assert why in capsys.readouterr().err
    bad.write_text("planner:\n  v_max: 2.0\n")  # the same for both modes: allowed with classic
    assert run_experiments.parse_args(["--extra-overrides", str(bad)]).sim_limit_s == 200.0


def test_missions_flown_at_once_are_aggregated_in_plan_order_with_a_log_each(tmp_path):
    # Two at a time, the first mission finishing last: each mission's output goes to runs/<run>.log,
    # every seed file exists before any mission starts, a failed mission is left out, and the report
    # lists the runs in plan order.
    import subprocess
    import threading
    out = str(tmp_path / "campaign")
    finished = []
    second_done = threading.Event()

    def fake_mission(cmd, stdout=None, stderr=None):
        d = cmd[cmd.index("--out") + 1]
        seeds = sorted(f for f in os.listdir(os.path.join(out, "runs")) if f.startswith("planner_seed"))
        assert seeds == ["planner_seed0.yaml", "planner_seed1.yaml"]
        if d.endswith("scene0_run0_classic"):
            assert second_done.wait(10)  # in flight beside the second mission, and done after it
        assert stderr == subprocess.STDOUT and stdout.name == d + ".log"
        stdout.write("mission %s\n" % os.path.basename(d))
        finished.append(os.path.basename(d))
        if d.endswith("scene0_run0_semantic"):
            second_done.set()
        if d.endswith("run1_classic"):
            return 3
        os.makedirs(d)
        with open(os.path.join(d, "timeseries.csv"), "w") as f:
            f.write("sim_s,explored_volume_m3,ground_truth_found\n0,0,0\n10,5,2\n")
        with open(os.path.join(d, "summary.json"), "w") as f:
            json.dump({"ground_truth_objects": 2, "termination_reason": "explored", "sim_time_s": 10.0}, f)
        return 0

    pytest.importorskip("matplotlib")
    assert run_experiments.main(["--scenes", "0", "--runs", "2", "--jobs", "2", "--out", out], call=fake_mission) == 0
    assert finished.index("scene0_run0_semantic") < finished.index("scene0_run0_classic")  # out of plan order
    with open(os.path.join(out, "runs", "scene0_run1_semantic.log")) as f:
        assert f.read() == "mission scene0_run1_semantic\n"
    report = open(os.path.join(out, "report.md")).read()
    assert "- missions flown at once: 2" in report
    assert "| classic | 1 | 100% |" in report and "| semantic | 2 | 100% |" in report
    assert "- classic runs: runs/scene0_run0_classic\n" in report
    assert "- semantic runs: runs/scene0_run0_semantic, runs/scene0_run1_semantic\n" in report
    runs = [line.split(" | ")[0] for line in report.splitlines() if line.startswith("| runs/")]
    assert runs == ["| runs/scene0_run0_classic", "| runs/scene0_run0_semantic", "| runs/scene0_run1_semantic"]


#!/usr/bin/env python3
"""Runs N planner seeds x {classic, semantic} x scenes in lockstep simulation
and writes median / 10th-90th percentile curves (PNG), curves.csv and
report.md (the paper's Section V-B evaluation).

Example (what `make experiments` runs):
  run_experiments.py --scenes 0 1 2 --runs 3 --size 8 6 3 --sim-limit-s 200 --out results/experiments
(18 runs of about 2.5 min each on a 2-core machine)

Scenes are generator seeds (a generated --size house each) or scene files
(a Habitat-style <scene>_semantic.ply with its .house, or a mesh with a JSON
label table next to it, as mav_sim loads them), mixed freely:
  run_experiments.py --scenes 0 test/data/example_semantic.ply --protocol paper

--protocol paper runs the paper's protocol: 5 runs of each method on each
scene (the paper used six Matterport3D scenes). The default protocol runs
--runs (3) per method and scene.

Runs are deterministic by default (run_mission.py --deterministic: OMPL stops
after planner/ompl_iterations, the simulator lets the planner plan with sim
time stopped, every node works at frame boundaries; see README "Deterministic
runs"), so a rerun of the same campaign repeats each run's time series.
--ompl-termination time keeps the wall-time budgets instead.

Both modes run with config/sim.yaml's simulator settings (its detector misses
masks under 1200 px, so a whole chair is detected from about 4 m, the range
the paper's d_bg assumes), plus --sim-overrides if given, e.g.
config/detector_long_range.yaml (50 px: chairs from 10 m). The report names
the detector the runs used.

--pool writes one report over campaigns already flown (their runs/
directories), e.g. two sets of houses flown on different days:
  run_experiments.py --pool results/houses_0_2 results/houses_3_8 --out results/pooled
"""
import argparse
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

#: runs per method and scene of each protocol (None: --runs)
PROTOCOL_RUNS = {"default": None, "paper": 5}


def scene_spec(token: str) -> dict:
    """A --scenes entry: a generator seed (integer) or a scene file that exists."""
    try:
        return {"seed": int(token), "file": "", "name": "scene%d" % int(token)}
    except ValueError:
        pass
    path = os.path.abspath(token)
    if not os.path.isfile(path):
        raise argparse.ArgumentTypeError("scene '%s' is neither a generator seed nor an existing scene file" % token)
    stem = os.path.basename(path)
    stem = stem[:-len("_semantic.ply")] if stem.endswith("_semantic.ply") else os.path.splitext(stem)[0]
    return {"seed": 0, "file": path, "name": stem}


def _eval(name):
    """The module semantic_exploration.eval.<name>, the source tree's package first."""
    import importlib
    src = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src")
    if src not in sys.path:
        sys.path.insert(0, src)
    return importlib.import_module("semantic_exploration.eval." + name)


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", type=scene_spec, nargs="+", default=[scene_spec(s) for s in ("0", "1", "2")],
                    help="generator seeds and/or scene files (<scene>_semantic.ply + .house, or mesh + .json)")
    ap.add_argument("--protocol", choices=sorted(PROTOCOL_RUNS), default="default",
                    help="paper: 5 runs per method per scene (the paper's Section V); default: --runs")
    ap.add_argument("--runs", type=int, default=None, help="runs per scene and mode (planner seeds; default 3)")
    ap.add_argument("--modes", nargs="+", default=["classic", "semantic"])
    ap.add_argument("--size", type=float, nargs=3, default=[8.0, 6.0, 3.0], metavar=("X", "Y", "H"),
                    help="size of the generated houses (scene files keep their own)")
    ap.add_argument("--classes", nargs="+", default=["chair"])
    ap.add_argument("--sim-limit-s", type=float, default=None,
                    help="sim time per mission, s (default 200); with --pool, runs that ran far past it are left "
                    "out (default: none)")
    ap.add_argument("--wall-limit-s", type=float, default=None,
                    help="per mission: a guard against a stuck run (default run_mission.py's: 3 x --sim-limit-s, "
                    "at least 1800 s)")
    ap.add_argument("--jobs", type=int, default=1,
                    help="missions flown at once (each logs to runs/<run>.log when > 1); deterministic runs are meant "
                    "to repeat whatever runs beside them, but a loaded machine can part them (README "
                    "\"Deterministic runs\")")
    ap.add_argument("--out", default=os.path.join("results", "experiments"))
    ap.add_argument("--ompl-termination", choices=["iterations", "time"], default="iterations",
                    help="iterations (default): deterministic runs (run_mission.py --deterministic); "
                    "time: the planner's wall-time budgets (runs differ)")
    ap.add_argument("--sim-overrides", default="",
                    help="YAML for the simulator loaded after config/sim.yaml in every run, e.g. "
                    "config/detector_long_range.yaml")
    ap.add_argument("--extra-overrides", default="",
                    help="YAML of node parameters merged into every run, as run_mission.py --extra-overrides, "
                    "e.g. planner weights for an ablation (with --modes semantic: classic's weights are its "
                    "definition); planner/seed is each run's own")
    ap.add_argument("--pool", nargs="+", default=[], metavar="CAMPAIGN",
                    help="fly nothing: write the report over the runs of these campaign directories (their runs/) "
                    "into --out; DIR:MODE takes one mode's runs of DIR (e.g. an ablation's semantic runs against "
                    "another campaign's classic ones); run names must not repeat across them")
    args = ap.parse_args(argv)
    if args.sim_limit_s is not None and not args.sim_limit_s > 0:
        ap.error("--sim-limit-s must be > 0 s")
    if args.pool:
        return pool_args(ap, args)
    if args.sim_limit_s is None:
        args.sim_limit_s = 200.0
    if args.extra_overrides:
        check_extra_overrides(ap, args)
    fixed = PROTOCOL_RUNS[args.protocol]
    if fixed is not None and args.runs is not None and args.runs != fixed:
        ap.error("--protocol %s runs %d runs per method per scene; drop --runs %d" % (args.protocol, fixed, args.runs))
    args.runs = fixed if fixed is not None else (args.runs if args.runs is not None else 3)
    if args.runs < 1:
        ap.error("--runs must be at least 1")
    if args.jobs < 1:
        ap.error("--jobs must be at least 1")
    if args.wall_limit_s is not None and not args.wall_limit_s > 0:
        ap.error("--wall-limit-s must be > 0 s")
    return args


#: Options that only shape the missions flown; --pool flies none.
FLIGHT_OPTIONS = ("scenes", "protocol", "runs", "size", "classes", "wall_limit_s", "jobs", "ompl_termination",
                  "sim_overrides", "extra_overrides")
#: Planner settings that make the modes what they are (config/classic.yaml sets them for classic).
MODE_SETTINGS = ("a_ent", "a_bg", "a_obj", "p_frontier")


def pool_args(ap, args):
    """--pool: no flight option, readable entries, and an --out that is none of the pooled campaigns."""
    given = ["--" + o.replace("_", "-") for o in FLIGHT_OPTIONS if getattr(args, o) != ap.get_default(o)]
    if given:
        ap.error("--pool flies nothing: drop %s" % " ".join(given))
    pool = _eval("pool")
    entries = []
    out = os.path.realpath(args.out)
    for entry in args.pool:
        campaign, mode, why = pool.parse_entry(entry, args.modes)
        if why:
            ap.error("--pool %s: %s" % (entry, why))
        c = os.path.realpath(campaign)
        if out == c or out.startswith(c + os.sep):
            ap.error("--out %s lies in the pooled campaign %s: its report would be overwritten" % (args.out, campaign))
        entries.append((campaign, mode))
    if os.path.isdir(os.path.join(out, "runs")):  # make experiments' default --out is a campaign's
        ap.error("--out %s holds a campaign (runs/): its report would be overwritten; give --pool an --out of "
                 "its own" % args.out)
    args.pool = entries
    return args


def check_extra_overrides(ap, args):
    """Refuses an --extra-overrides that cannot be read, sets planner/seed (each run's own) or,
    with classic among --modes, changes what makes classic classic."""
    overrides = _eval("overrides")
    why = overrides.unreadable(args.extra_overrides)
    if why:
        ap.error("--extra-overrides: %s" % why)
    planner = overrides.load(args.extra_overrides).get("planner") or {}
    if not isinstance(planner, dict):
        ap.error("--extra-overrides: planner must be a section of settings, not %r" % (planner,))
    if "seed" in planner:
        ap.error("--extra-overrides sets planner/seed: each run sets its own (planner seeds 1-N)")
    defining = [k for k in MODE_SETTINGS if k in planner]
    if defining and "classic" in args.modes:
        ap.error("--extra-overrides sets planner/%s, which config/classic.yaml sets for the classic mode: the "
                 "classic runs would not be classic; fly such a change with --modes semantic" % ", planner/".join(
                     defining))


def plan_runs(args, out: str, here: str):
    """The campaign's missions in order: dicts of scene (name), run, mode, dir, and the
    run_mission.py command line (`overrides`: the planner-seed YAML it loads)."""
    sim_overrides = os.path.abspath(args.sim_overrides) if args.sim_overrides else ""
    runs = []
    for scene in args.scenes:
        for run in range(args.runs):
            for mode in args.modes:
                run_dir = os.path.join(out, "runs", "%s_run%d_%s" % (scene["name"], run, mode))
                overrides = os.path.join(out, "runs", "planner_seed%d.yaml" % run)
                where = ["--scene", scene["file"]] if scene["file"] else (
                    ["--seed", str(scene["seed"]), "--size"] + [str(v) for v in args.size])
                cmd = [sys.executable, os.path.join(here, "run_mission.py"), "--mode", mode] + where + [
                    "--classes"] + args.classes + [
                    "--out", run_dir, "--sim-limit-s", str(args.sim_limit_s), "--extra-overrides", overrides]
                if args.wall_limit_s is not None:
                    cmd += ["--wall-limit-s", str(args.wall_limit_s)]
                if args.ompl_termination == "iterations":
                    cmd.append("--deterministic")
                if sim_overrides:
                    cmd += ["--sim-overrides", sim_overrides]
                runs.append({"scene": scene["name"], "run": run, "mode": mode, "dir": run_dir, "cmd": cmd,
                             "overrides": overrides, "planner_seed": run + 1})
    return runs


def describe_setup(args, sim_overrides: str, describe_yaml) -> list:
    """The report's lines on how the runs were made."""
    scenes = ", ".join(s["file"] and os.path.basename(s["file"]) or "generated seed %d" % s["seed"]
                       for s in args.scenes)
    return ["scenes: %s (generated houses %g x %g x %g m)" % (scenes, *args.size),
            "protocol %s: %d run%s per method and scene (planner seeds 1-%d), classes %s, %g s sim per run" % (
                args.protocol, args.runs, "s" if args.runs != 1 else "", args.runs, " ".join(args.classes),
                args.sim_limit_s),
            "planner: %s" % ("deterministic (OMPL stops after planner/ompl_iterations; run_mission.py "
                             "--deterministic)" if args.ompl_termination == "iterations"
                             else "OMPL wall-time budget (planner/time_budget_s): runs are not repeatable"),
            "simulator overrides: %s" % (describe_yaml(sim_overrides) if sim_overrides else "none"),
            "node overrides (--extra-overrides): %s" % (
                describe_yaml(os.path.abspath(args.extra_overrides)) if args.extra_overrides else "none"),
            "missions flown at once: %d" % args.jobs]


def main(argv=None, call=subprocess.call):
    here = os.path.dirname(os.path.abspath(__file__))
    args = parse_args(argv)
    overrides, experiments = _eval("overrides"), _eval("experiments")
    if args.pool:
        rc, msgs = _eval("pool").pool_report(args.pool, args.modes, args.out, args.sim_limit_s)
        for m in msgs:
            print("[experiments] %s" % m)
        return rc

    out = os.path.abspath(args.out)
    sim_overrides = os.path.abspath(args.sim_overrides) if args.sim_overrides else ""
    setup = describe_setup(args, sim_overrides, experiments.describe_yaml)
    by_mode = {m: [] for m in args.modes}
    plan = plan_runs(args, out, here)
    t0 = time.time()
    extra = overrides.load(args.extra_overrides) if args.extra_overrides else {}
    for r in plan:  # every seed file before any mission reads one (missions of one run index share it)
        os.makedirs(os.path.dirname(r["overrides"]), exist_ok=True)
        seeded = overrides.merge(overrides.merge({}, extra), {"planner": {"seed": r["planner_seed"]}})
        overrides.write(r["overrides"], seeded,
                        "written by run_experiments.py: --extra-overrides, then the planner seed")

    def fly(k, r):
        """One mission; True if it left a time series to aggregate (a failure is reported at once)."""
        print("[experiments] run %d/%d: %s, run %d, %s (%.0f s so far)" % (
            k, len(plan), r["scene"], r["run"], r["mode"], time.time() - t0), flush=True)
        if args.jobs == 1:
            rc = call(r["cmd"])
        else:
            with open(r["dir"] + ".log", "w") as log:  # two missions' progress lines would interleave
                rc = call(r["cmd"], stdout=log, stderr=subprocess.STDOUT)
            print("[experiments] %s done (exit %d, %.0f s so far; log %s.log)" % (
                os.path.basename(r["dir"]), rc, time.time() - t0, r["dir"]), flush=True)
        if rc != 0 or not os.path.exists(os.path.join(r["dir"], "timeseries.csv")):
            print("[experiments] run %s failed (exit %d); left out of the curves" % (r["dir"], rc), flush=True)
            return False
        return True

    if args.jobs == 1:  # in this thread: Ctrl-C reaches subprocess.call, which stops the mission
        done = [fly(k, r) for k, r in enumerate(plan, 1)]
    else:
        with ThreadPoolExecutor(max_workers=args.jobs) as pool:
            done = list(pool.map(lambda kr: fly(*kr), enumerate(plan, 1)))
    for r, ok in zip(plan, done):  # in plan order, whatever order they finished in
        if not ok:
            continue
        run_data = experiments.read_run(r["dir"])
        why = experiments.implausible(run_data, args.sim_limit_s)
        if why:
            print("[experiments] run %s: %s; left out of the curves" % (r["dir"], why))
            continue
        by_mode[r["mode"]].append(run_data)
    setup.append("wall time of the campaign: %.0f s" % (time.time() - t0))
    by_mode = {m: r for m, r in by_mode.items() if r}
    if not by_mode:
        print("[experiments] no run succeeded")
        return 1
    res = experiments.write_outputs(out, by_mode, setup=setup)
    for r in res["rows"]:
        print("[experiments] %s: %d runs, found %.0f%% (median), explored %.1f m3 (median)" % (
            r["mode"], r["runs"], r["found_percent_median"], r["explored_m3_median"]))
    print("[experiments] report: %s" % os.path.join(out, "report.md"))
    return 0


if __name__ == "__main__":
    sys.exit(main())

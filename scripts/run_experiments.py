#!/usr/bin/env python3
"""Runs N seeds x {classic, semantic} x scenes in lockstep simulation and
writes median / 10th-90th percentile curves (PNG), curves.csv and report.md
(the paper's Section V-B evaluation).

Example (what `make experiments` runs):
  run_experiments.py --scenes 0 1 2 --runs 3 --size 8 6 3 --sim-limit-s 200 --out results/experiments
(18 runs of about 2.5 min each on a 2-core machine)

Both modes run with config/sim.yaml's simulator settings (its detector misses
masks under 1200 px, so a whole chair is detected from about 4 m, the range
the paper's d_bg assumes), plus --sim-overrides if given, e.g.
config/detector_long_range.yaml (50 px: chairs from 10 m). The report names
the detector the runs used.
"""
import argparse
import os
import subprocess
import sys
import time


def main(argv=None):
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", type=int, nargs="+", default=[0, 1, 2], help="generator seeds of the scenes")
    ap.add_argument("--runs", type=int, default=3, help="runs per scene and mode (planner seeds)")
    ap.add_argument("--modes", nargs="+", default=["classic", "semantic"])
    ap.add_argument("--size", type=float, nargs=3, default=[8.0, 6.0, 3.0], metavar=("X", "Y", "H"))
    ap.add_argument("--classes", nargs="+", default=["chair"])
    ap.add_argument("--sim-limit-s", type=float, default=200.0)
    ap.add_argument("--wall-limit-s", type=float, default=900.0)
    ap.add_argument("--out", default=os.path.join("results", "experiments"))
    ap.add_argument("--sim-overrides", default="",
                    help="YAML for the simulator loaded after config/sim.yaml in every run, e.g. "
                    "config/detector_long_range.yaml")
    args = ap.parse_args(argv)
    sys.path.insert(0, os.path.join(here, "..", "src"))
    from semantic_exploration.eval import experiments

    out = os.path.abspath(args.out)
    sim_overrides = os.path.abspath(args.sim_overrides) if args.sim_overrides else ""
    setup = ["scenes %s (generator seeds), %d planner seeds, house %g x %g x %g m, classes %s, %g s sim per run" % (
        " ".join(str(s) for s in args.scenes), args.runs, args.size[0], args.size[1], args.size[2],
        " ".join(args.classes), args.sim_limit_s),
        "simulator overrides: %s" % (experiments.describe_yaml(sim_overrides) if sim_overrides else "none")]
    by_mode = {m: [] for m in args.modes}
    total = len(args.scenes) * args.runs * len(args.modes)
    k = 0
    t0 = time.time()
    for scene in args.scenes:
        for run in range(args.runs):
            for mode in args.modes:
                k += 1
                run_dir = os.path.join(out, "runs", "scene%d_run%d_%s" % (scene, run, mode))
                print("[experiments] run %d/%d: scene %d, seed %d, %s (%.0f s so far)" % (
                    k, total, scene, run, mode, time.time() - t0), flush=True)
                overrides = os.path.join(out, "runs", "planner_seed%d.yaml" % run)
                os.makedirs(os.path.dirname(overrides), exist_ok=True)
                with open(overrides, "w") as f:
                    f.write("planner:\n  seed: %d\n" % (run + 1))
                cmd = [sys.executable, os.path.join(here, "run_mission.py"), "--mode", mode, "--seed", str(scene),
                       "--size"] + [str(v) for v in args.size] + ["--classes"] + args.classes + [
                       "--out", run_dir, "--sim-limit-s", str(args.sim_limit_s),
                       "--wall-limit-s", str(args.wall_limit_s), "--extra-overrides", overrides]
                if sim_overrides:
                    cmd += ["--sim-overrides", sim_overrides]
                rc = subprocess.call(cmd)
                if rc != 0 or not os.path.exists(os.path.join(run_dir, "timeseries.csv")):
                    print("[experiments] run %s failed (exit %d); left out of the curves" % (run_dir, rc))
                    continue
                run_data = experiments.read_run(run_dir)
                why = experiments.implausible(run_data, args.sim_limit_s)
                if why:
                    print("[experiments] run %s: %s; left out of the curves" % (run_dir, why))
                    continue
                by_mode[mode].append(run_data)
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

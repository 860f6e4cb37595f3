#!/usr/bin/env python3
"""Evaluates a recorded run: reads a bag (launch/record.launch) and the
simulator's ground truth, and writes the same timeseries.csv, report.md and
summary.json as run_mission.py writes for a live run, as far as the bag holds
the data (planner status, map statistics, objects, poses, collisions, drop
counts). Saved maps (the nodes' ~save output) are scored against ground truth
when given.

Example:
  evaluate_run.py --bag run.bag --gt-dir results/run/ground_truth --out results/run_from_bag \\
      [--map results/run/map] [--objects results/run/objects]
"""
import argparse
import csv
import glob
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bag", required=True, help="bag recorded with record.launch")
    ap.add_argument("--gt-dir", required=True, help="ground truth exported by the simulator (objects.json ...)")
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--mode", default="semantic", help="mode of the recorded run (for the report)")
    ap.add_argument("--seed", type=int, default=None, help="scene seed of the recorded run (for the report)")
    ap.add_argument("--classes", nargs="+", default=["chair"], help="classes of interest")
    ap.add_argument("--map", default="", help="saved background map directory (with occupied.ply)")
    ap.add_argument("--objects", default="", help="saved object map directory (with objects.json)")
    ap.add_argument("--period-s", type=float, default=1.0, help="time-series row period, s of bag time")
    ap.add_argument("--no-eval", action="store_true", help="skip scoring saved maps against ground truth")
    ap.add_argument("--start", type=float, nargs=4, default=None, metavar=("X", "Y", "Z", "YAW"),
                    help="the run's start pose (m, rad) where the ground truth has none (its observable surface "
                    "depends on it)")
    args = ap.parse_args(argv)

    sys.path.insert(0, HERE)
    import run_mission as mission
    mission._import_package()
    from semantic_exploration.eval.bag import read_bag
    from semantic_exploration.eval.report import write_report

    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(args.gt_dir, "objects.json")) as f:
        gt = json.load(f)
    gt["gt_dir"] = os.path.abspath(args.gt_dir)
    if args.start:
        gt["start"] = list(args.start)
    gt_objs = [o for o in gt["objects"] if o["class"] in args.classes]
    log, rows, info = read_bag(args.bag, gt_objs, args.period_s)
    if not rows:
        print("[evaluate] %s holds none of the evaluation topics" % args.bag, file=sys.stderr)
        return 1
    if args.objects and os.path.exists(os.path.join(args.objects, "objects.json")):
        # The bag holds no meshes: objects found is known (as the report matches) for the saved map only,
        # at the last row; the rows before it carry the centroid proxy alone.
        from semantic_exploration.eval import metrics
        from semantic_exploration.eval.truth import GroundTruthIndex
        index = GroundTruthIndex(metrics.load_ground_truth(args.gt_dir), args.classes)
        rows[-1]["ground_truth_found"] = len(index.found(metrics.load_reconstruction(os.path.abspath(args.objects))))
        rows[-1]["found_at_s"] = rows[-1]["sim_s"]
    with open(os.path.join(out, "timeseries.csv"), "w") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    saved = {}
    if args.map:
        files = sorted(glob.glob(os.path.join(os.path.abspath(args.map), "*")))
        saved["background_map"] = {"success": bool(files), "message": "saved map %s" % args.map, "files": files}
    if args.objects:
        d = os.path.abspath(args.objects)
        ok = os.path.exists(os.path.join(d, "objects.json"))
        saved["object_map"] = {"success": ok, "message": "saved objects %s" % args.objects, "dir": d,
                               "files": sorted(glob.glob(os.path.join(d, "*")))}
    if log.finished():
        reason = log.status.termination_reason or "finished"
    else:
        reason = "end of bag (planner not finished)" if log.status else "end of bag (no planner status)"
    run = argparse.Namespace(mode=args.mode, seed=args.seed, classes=args.classes, no_eval=args.no_eval)
    sim_s = info["end_s"] - info["start_s"] if info["end_s"] is not None else 0.0
    summary = write_report(out, run, gt, log, saved, info["end_s"], None, reason)
    summary["bag"] = {"path": os.path.abspath(args.bag), "duration_s": sim_s, **info}
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    if info["missing_topics"]:
        with open(os.path.join(out, "report.md"), "a") as f:
            f.write("\nThe bag lacks %s: the figures from those topics are missing above.\n"
                    % ", ".join(info["missing_topics"]))
    print("[evaluate] %s: %d rows over %.1f s of bag time; report %s" % (
        args.bag, len(rows), sim_s, os.path.join(out, "report.md")))
    print("[evaluate] " + log.drop_report_lines()[0])
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Scores saved object maps against a run's ground truth, as the mission
report does (semantic_exploration.eval.final): for each objects directory,
the map objects matched to ground-truth objects with their accuracy RMSE and
completeness, the spurious and the duplicated. Used to compare meshes of one
flight extracted again under other gates (remesh_objects) without flying
again. Prints one JSON document per directory.

Example:
  score_objects.py --gt-dir results/run/ground_truth results/run/objects results/run/objects_fg06
"""
import argparse
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gt-dir", required=True, help="ground truth exported by the simulator (the run's ground_truth)")
    ap.add_argument("--classes", nargs="+", default=["chair"], help="classes of interest")
    ap.add_argument("objects", nargs="+", help="saved object map directories (with objects.json)")
    args = ap.parse_args(argv)
    sys.path.insert(0, HERE)
    import run_mission as mission
    mission._import_package()
    from semantic_exploration.eval import metrics
    from semantic_exploration.eval.final import object_figures
    from semantic_exploration.eval.truth import GroundTruthIndex

    rc = 0
    # One ground-truth index (surface samples, observability) for every directory.
    try:
        index = GroundTruthIndex(metrics.load_ground_truth(os.path.abspath(args.gt_dir)), args.classes)
    except Exception as e:  # a ground truth that cannot be read scores nothing: say why, once
        print("[score_objects] ground truth %s: %s: %s" % (args.gt_dir, type(e).__name__, e), file=sys.stderr)
        return 1
    try:
        index.start_observability()
        for d in args.objects:
            if not os.path.exists(os.path.join(d, "objects.json")):
                print("[score_objects] %s holds no objects.json" % d, file=sys.stderr)
                rc = 1
                continue
            try:
                res = {"objects_dir": os.path.abspath(d), "evaluation": object_figures(index, d)}
            except Exception as e:  # one unreadable map must not lose the others' figures
                res = {"objects_dir": os.path.abspath(d), "error": "%s: %s" % (type(e).__name__, e)}
                print("[score_objects] %s: %s" % (d, res["error"]), file=sys.stderr)
                rc = 1
            print(json.dumps(res), flush=True)
    finally:
        index.close()
    return rc


if __name__ == "__main__":
    sys.exit(main())

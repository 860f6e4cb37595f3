#!/usr/bin/env python3
"""Times the scoring of one run against ground truth, as run_mission.py scores
it (objects, then background), and prints one JSON line with the wall and CPU
seconds and the scores.

Without --run it first writes a stand-in run of the default house (generator
seed 0, 10 x 8 x 3 m) into --work: its ground truth, each chair's true mesh
subdivided to 2 cm edges with 1 cm noise (an object map's mesh), and the
centres of the 4 cm voxels every surface passes through (a background map).

--src scores with another checkout's Python package, e.g. the code before a change:
  git archive <commit> src | tar -x -C /tmp/before
  bench_scoring.py --src /tmp/before/src; bench_scoring.py
"""
import argparse
import inspect
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def make_run(work, seed=0, size=(10.0, 8.0, 3.0), voxel_m=0.04):
    import numpy as np
    import trimesh
    from semantic_exploration.sim.classes import DEFAULT_CLASS_NAMES
    from semantic_exploration.sim.generator import generate
    from semantic_exploration.sim.scene import export_ground_truth
    scene = generate(seed, size)
    gt = export_ground_truth(scene, os.path.join(work, "ground_truth"), DEFAULT_CLASS_NAMES)
    rec = os.path.join(work, "objects")
    os.makedirs(rec, exist_ok=True)
    rng = np.random.default_rng(seed)
    objs = []
    for o in gt["objects"]:
        if o["class"] != "chair":
            continue
        m = trimesh.load(os.path.join(work, "ground_truth", o["mesh"]), process=False, force="mesh")
        m = m.subdivide_to_size(0.02)
        m.vertices += rng.normal(0.0, 0.01, m.vertices.shape)
        m.export(os.path.join(rec, "%d.ply" % o["id"]))
        objs.append({"id": o["id"], "class_name": "chair", "mesh": "%d.ply" % o["id"]})
    with open(os.path.join(rec, "objects.json"), "w") as f:
        json.dump({"objects": objs}, f)
    whole = trimesh.Trimesh(scene.vertices, scene.faces, process=False)
    pts, _ = trimesh.sample.sample_surface(whole, int(whole.area / 0.005 ** 2), seed=seed)
    centres = (np.unique(np.floor(pts / voxel_m).astype(np.int64), axis=0) + 0.5) * voxel_m
    os.makedirs(os.path.join(work, "map"), exist_ok=True)
    trimesh.PointCloud(centres).export(os.path.join(work, "map", "occupied.ply"))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", default="", help="a run directory (ground_truth/, objects/, map/occupied.ply)")
    ap.add_argument("--work", default="/tmp/semexp_bench_scoring", help="where the stand-in run is written")
    ap.add_argument("--src", default=os.path.join(HERE, "..", "src"), help="Python package source to score with")
    ap.add_argument("--classes", nargs="+", default=["chair"])
    ap.add_argument("--out", default="", help="also append the figures as make bench's JSON lines to this file")
    args = ap.parse_args(argv)
    sys.path.insert(0, os.path.abspath(args.src))
    from semantic_exploration.eval import metrics
    run = args.run
    if not run:
        run = args.work
        if not os.path.exists(os.path.join(run, "map", "occupied.ply")):
            make_run(run)
    import resource

    def cpu():  # this process and its finished children (the observability workers), s
        return time.process_time() + resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime

    t0, c0 = time.time(), cpu()
    gt = metrics.load_ground_truth(os.path.join(run, "ground_truth"))
    rec = metrics.load_reconstruction(os.path.join(run, "objects"))
    pts = metrics.read_ply_vertices(os.path.join(run, "map", "occupied.ply"))
    try:  # as run_mission.py scores: one index, observability started first
        from semantic_exploration.eval.truth import GroundTruthIndex
    except ImportError:  # the code before GroundTruthIndex
        ev = metrics.evaluate_objects(gt, rec, args.classes)
        t1, c1 = time.time(), cpu()
        extra = [args.classes] if "classes" in inspect.signature(metrics.evaluate_background).parameters else []
        b = metrics.evaluate_background(gt, pts, *extra)
    else:
        index = GroundTruthIndex(gt, args.classes)
        if hasattr(index, "start_observability"):
            index.start_observability()
            index.background.tree
        ev = index.evaluate_objects(rec)
        t1, c1 = time.time(), cpu()
        b = index.evaluate_background(pts)
    t2, c2 = time.time(), cpu()
    summary = {
        "src": os.path.abspath(args.src), "run": run, "wall_s": round(t2 - t0, 1), "cpu_s": round(c2 - c0, 1),
        "objects_wall_s": round(t1 - t0, 1), "background_wall_s": round(t2 - t1, 1),
        "found": len(ev.found_gt_ids), "ground_truth": ev.n_ground_truth,
        "object_rmse_m": [round(m.score.rmse_m, 5) for m in ev.matches if m.score],
        "object_completeness": [round(m.score.completeness, 4) for m in ev.matches if m.score],
        "background": {"rmse_m": round(b.rmse_m, 5), "completeness": round(b.completeness, 4),
                       "n_reconstructed": b.n_reconstructed, "observable_fraction": round(b.observable_fraction, 4)},
        "load_average": os.getloadavg()[0]}
    print(json.dumps(summary))
    if args.out:
        with open(args.out, "a") as f:
            for key, unit in (("wall_s", "s"), ("cpu_s", "s"), ("objects_wall_s", "s"), ("background_wall_s", "s")):
                f.write(json.dumps({"name": "scoring.default_house.%s" % key, "value": summary[key], "unit": unit,
                                    "peer": None, "peer_value": None}) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

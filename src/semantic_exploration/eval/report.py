"""A run's report.md and summary.json: how and when it ended, what it found
and how well it reconstructed it (against the ground truth), its CPU budget,
dropped input and files. run_mission.py writes them at the end of a mission,
evaluate_run.py for a recorded bag."""
import json
import os

from semantic_exploration.eval import cpu_budget, experiments, final


def detector_of(sim_overrides, min_mask_pixels):
    """The detector a run used: {"min_mask_pixels": px or None (unknown), "source": the file that set it}."""
    source = "config/sim.yaml"
    if sim_overrides:
        import yaml
        with open(sim_overrides) as f:
            if "min_mask_pixels" in ((yaml.safe_load(f) or {}).get("detector") or {}):
                source = os.path.basename(sim_overrides)
    return {"min_mask_pixels": min_mask_pixels, "source": source}


def write_report(out, args, gt, mon, saved, sim_s, wall_s, reason, detector=None):
    """report.md and summary.json of a run; args needs mode, seed and classes,
    mon is a RunLog (live or read from a bag), wall_s may be None (a bag),
    detector as detector_of() gives it (None: not known)."""
    objects = mon.objects.objects if mon.objects else []
    gt_objs = [o for o in gt["objects"] if o["class"] in set(args.classes)]
    stats = mon.stats
    summary = {
        "mode": args.mode, "scene": gt.get("scene"), "seed": args.seed,
        "termination_reason": reason, "sim_time_s": sim_s, "wall_time_s": wall_s,
        "iterations": mon.status.iteration if mon.status else 0,
        "explored_volume_m3": stats.explored_volume_m3 if stats else 0.0,
        "frontier_count": stats.frontier_count if stats else None,
        "end_conditions": mon.open_conditions(),  # what still held the run open when it ended
        "map_objects": len(objects), "ground_truth_objects": len(gt_objs),
        "path_length_m": mon.path_length_m, "collisions": mon.collisions,
        "dropped_input": mon.drop_summary(),
        "invalid_depth_pixels": stats.invalid_depth_pixels if stats else 0,
        "saved": saved, "detector": detector, "planner_timing": getattr(args, "timing", None),
        "snapshots": getattr(args, "snapshot_summary", None),
        "background_snapshots": getattr(args, "background_snapshot_summary", None),
        "cpu_budget": mon.cpu.summary(getattr(args, "camera_rate_hz", None)),  # None: the rate of the frames
        # Objects the planner retired by evidence at its last status (object_retirement.hpp).
        "retired_objects": list(getattr(mon, "retired_objects", [])),
    }
    free = os.path.join(gt["gt_dir"], "free_space.json")
    if os.path.exists(free):
        with open(free) as f:
            summary["explorable_free_volume_m3"] = json.load(f)["explorable_free_volume_m3"]
    summary["evaluation"] = (final.evaluate(out, gt, args.classes, saved) if not getattr(args, "no_eval", False)
                             else {"skipped": "--no-eval"})
    # Ground-truth objects some map object lies on (None without an evaluation).
    summary["ground_truth_found"] = summary["evaluation"].get("found")
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    lines = [
        "# Exploration report", "", "| | |", "|---|---|", "| mode | %s |" % args.mode,
        "| scene | %s |" % summary["scene"],
        "| detector | %s |" % experiments.describe_detector(detector),
        "| planner timing | %s |" % (getattr(args, "timing", None) or "unknown"),
        "| termination | %s |" % reason,
        "| sim time | %.1f s |" % sim_s,
        "| wall time | %s |" % ("%.1f s" % wall_s if wall_s is not None else "- (from a bag)"),
        "| planning iterations | %d |" % summary["iterations"],
        "| explored volume | %.1f m3 |" % summary["explored_volume_m3"],
    ]
    if "explorable_free_volume_m3" in summary:
        lines.append("| explorable free volume (ground truth) | %.1f m3 |" % summary["explorable_free_volume_m3"])
    lines += [
        "| ground-truth objects found (%s) | %s / %d |" % (
            ", ".join(args.classes), "-" if summary["ground_truth_found"] is None else summary["ground_truth_found"],
            len(gt_objs)),
        *final.map_object_rows(len(objects), summary["evaluation"]),
        "| path length | %.1f m |" % mon.path_length_m,
        "| collisions | %d |" % mon.collisions,
        "", "## Objects found", "",
        "Retired: below planner/object_observed_fraction after object_retirement/max_failed_views flights aimed "
        "at it that did not move its share seen from <= d_obj; it no longer holds `explored` open.", "",
        "| id | class | centroid (m) | voxels | observed from <= d_obj | retired |", "|---|---|---|---|---|---|",
    ]
    for o in objects:
        lines.append("| %d | %s | (%.2f, %.2f, %.2f) | %d | %.0f%% | %s |" % (
            o.id, o.class_name, o.centroid.x, o.centroid.y, o.centroid.z, o.voxel_count,
            100.0 * o.observed_fraction, "yes" if o.id in summary["retired_objects"] else "no"))
    ev = summary["evaluation"]
    if ev.get("objects"):
        lines += ["", "## Object reconstruction (against ground truth, 5 cm)", "",
                  "found %d of %d ground-truth objects" % (ev["found"], ev["ground_truth"]), "",
                  "A map object is matched to the ground-truth object most of its surface lies on (within 5 cm). "
                  "Completeness is the share of the *observable* ground-truth surface with a reconstructed point "
                  "within 5 cm: surface some camera pose the MAV can take sees (camera centre at least R from every "
                  "surface and connected to the start, unoccluded, within the depth range and the vertical field "
                  "of view, at most 75 deg off the surface normal; see eval/observable.py). The last column gives "
                  "that share of each object's surface.", "",
                  "| map id | class | ground-truth id | on its surface | accuracy RMSE | completeness | observable |",
                  "|---|---|---|---|---|---|---|"]
        for m in ev["objects"]:
            lines.append("| %d | %s | %s | %.0f%% | %s | %s | %s |" % (
                m["map_id"], m["class"], m["gt_id"] if m["gt_id"] is not None else "-",
                100 * m["on_surface_fraction"],
                "%.1f cm" % (100 * m["rmse_m"]) if m.get("rmse_m") is not None else "-",
                "%.0f%%" % (100 * m["completeness"]) if m.get("completeness") is not None else "-",
                "%.0f%%" % (100 * m["observable_fraction"]) if m.get("observable_fraction") is not None else "-"))
    if ev.get("background"):
        b = ev["background"]
        lines += ["", "background: accuracy RMSE %.1f cm, completeness %.0f%% of the observable surface (%.0f%% of "
                  "it; %d occupied voxels)" % (100 * b["rmse_m"], 100 * b["completeness"],
                                               100 * b.get("observable_fraction", 1.0), b["n_reconstructed"])]
    if ev.get("error"):
        lines += ["", "evaluation: %s" % ev["error"]]
    sn, sb, ts = summary.get("snapshots"), summary.get("background_snapshots"), ev.get("timeseries")
    if sn or sb:
        share = sum(x["share_of_wall"] or 0.0 for x in (sn, sb) if x)
        lines += ["", "time series: %s%s took %.1f s of wall time during the run (%.1f%%)%s" % (
            "%d object-map snapshots (every %g s of sim time; objects found matched as above)" % (
                sn["count"], sn["period_s"]) if sn else "",
            "%s%d background-map snapshots (every %g s)" % (", " if sn else "", sb["count"], sb["period_s"])
            if sb else "", sum(x["wall_s"] for x in (sn, sb) if x), 100 * share,
            "; scoring them afterwards %.1f s" % ts["scoring_wall_s"] if ts else "")]
    lines += (["", "## Onboard CPU budget", ""] + cpu_budget.report_lines(summary["cpu_budget"]) +
              ["", "## Dropped input", ""] + mon.drop_report_lines())
    lines += ["", "## Files", ""]
    for name, s in saved.items():
        lines.append("- %s: %s" % (name, s["message"]))
        lines += ["  - %s" % p for p in s["files"]]
    lines.append("- ground truth: %s" % gt["gt_dir"])
    with open(os.path.join(out, "report.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    return summary

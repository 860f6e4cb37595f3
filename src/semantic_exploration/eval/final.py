"""A mission's final figures from its saved maps (run_mission.py and the bag evaluation use it)."""
import os


def evaluate(out, gt, classes, saved):
    """Final figures from the saved meshes and map (empty where a map was not saved).
    gt["start"] stands in for a ground truth exported without one."""
    from semantic_exploration.eval import metrics
    from semantic_exploration.eval.truth import GroundTruthIndex
    res = {}
    index = None
    try:
        doc = metrics.load_ground_truth(gt["gt_dir"])
        if not doc.get("start") and gt.get("start"):
            doc["start"] = list(gt["start"])
        index = GroundTruthIndex(doc, classes)
        # Observability in other processes while this one samples the scene and builds its trees.
        index.start_observability()
        index.background.tree
        rec_dir = saved.get("object_map", {}).get("dir") or os.path.join(out, "objects")
        if saved.get("object_map", {}).get("success") and os.path.exists(os.path.join(rec_dir, "objects.json")):
            res.update(object_figures(index, rec_dir))
        occ = [f for f in saved.get("background_map", {}).get("files", []) if f.endswith("occupied.ply")]
        b = index.evaluate_background(metrics.read_ply_vertices(occ[0])) if occ else None
        if b is not None:
            res["background"] = {"rmse_m": b.rmse_m, "completeness": b.completeness,
                                 "n_reconstructed": b.n_reconstructed, "observable_fraction": b.observable_fraction}
        series = os.path.join(out, "snapshot", "series")
        if os.path.isdir(series):  # the time series' accuracy and completeness, from the run's snapshots
            from semantic_exploration.eval.snapshots import finish_series
            rec = metrics.load_reconstruction(rec_dir) if "found" in res else None
            res["timeseries"] = finish_series(index, series, os.path.join(out, "timeseries.csv"), rec, b)
    except Exception as e:  # a failed evaluation must not lose the rest of the report
        res["error"] = "%s: %s" % (type(e).__name__, e)
    finally:
        if index is not None:  # nothing saved (a node died at start-up) used no mask: collect the process
            index.close()
    return res


def object_figures(index, rec_dir):
    """The figures on a saved object map (rec_dir, with objects.json) against the ground truth `index`
    (a GroundTruthIndex with its observability started): found, the spurious and the duplicated, and per map
    object its match, RMSE and completeness."""
    from semantic_exploration.eval import metrics
    ev = index.evaluate_objects(metrics.load_reconstruction(rec_dir))
    # Map objects on no ground-truth object, and ground-truth objects more than one map object lies on.
    return {"found": len(ev.found_gt_ids), "ground_truth": ev.n_ground_truth, "spurious": ev.spurious_map_ids,
            "without_surface": ev.without_surface_map_ids,  # empty meshes: neither matched nor spurious
            "duplicates": [{"gt_id": g, "map_ids": ids} for g, ids in ev.duplicates.items()],
            "objects": [{"map_id": m.map_id, "class": m.map_class, "gt_id": m.gt_id,
                         "on_surface_fraction": m.on_surface_fraction,
                         "rmse_m": m.score.rmse_m if m.score else None,
                         "completeness": m.score.completeness if m.score else None,
                         "observable_fraction": ev.observable_fraction.get(m.gt_id)} for m in ev.matches]}


def map_object_rows(n_objects, ev):
    """The report's rows on map objects: their number, the spurious ones (on no ground-truth object) and the
    ground-truth objects more than one map object lies on, from evaluate()'s result ev ('-' without one)."""
    spurious, dups, empty = ev.get("spurious"), ev.get("duplicates"), ev.get("without_surface")
    rows = ["| map objects | %d |" % n_objects,
            "| spurious map objects (on no ground-truth object) | %s |" % (
                "-" if spurious is None else "%d%s" % (len(spurious), " (map ids %s)" % ", ".join(
                    str(i) for i in spurious) if spurious else "")),
            "| duplicated ground-truth objects (more than one map object on them) | %s |" % (
                "-" if dups is None else "%d%s" % (len(dups), " (%s)" % "; ".join(
                    "ground truth %d: map ids %s" % (d["gt_id"], ", ".join(str(i) for i in d["map_ids"]))
                    for d in dups) if dups else ""))]
    if empty:  # only named when there are some (an object tracked under the foreground prior, no mesh yet)
        rows.append("| map objects without a mesh yet (neither matched nor spurious) | %d (map ids %s) |" % (
            len(empty), ", ".join(str(i) for i in empty)))
    return rows

"""One definition of "found": the time series counts a ground-truth object as
found when a map object's mesh lies on it (eval.metrics' matching, the final
report's), at object-map snapshots (eval.snapshots), not when a map object's
centroid falls in its box (RunLog.found_proxy, kept under that name)."""
import json
import os
from types import SimpleNamespace as NS

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from semantic_exploration.eval import experiments, metrics  # noqa: E402
from semantic_exploration.eval.runlog import RunLog  # noqa: E402
from semantic_exploration.eval.snapshots import ObjectSnapshots  # noqa: E402
from semantic_exploration.eval.truth import GroundTruthIndex  # noqa: E402
from semantic_exploration.sim.scene import export_ground_truth  # noqa: E402

from test_eval_background import _scene  # noqa: E402

CHAIR_LO, CHAIR_HI = np.array([1.6, 1.2, 0.0]), np.array([2.05, 1.65, 0.9])  # test_eval_background's chair box


@pytest.fixture(scope="module")
def gt(tmp_path_factory):
    d = str(tmp_path_factory.mktemp("gt"))
    export_ground_truth(_scene(), d, ["chair", "table", "cabinet"])
    return metrics.load_ground_truth(d)


def write_objects(directory, meshes):
    """An object map as object_map/save writes it: objects.json and one mesh per object (id -> Trimesh)."""
    os.makedirs(directory, exist_ok=True)
    objs = []
    for oid, mesh in meshes.items():
        mesh.export(os.path.join(directory, "object_%d_chair.ply" % oid))
        objs.append({"id": oid, "class_name": "chair", "mesh": "object_%d_chair.ply" % oid})
    with open(os.path.join(directory, "objects.json"), "w") as f:
        json.dump({"objects": objs}, f)


def bled_mask_mesh():
    """A "chair" that is mostly floor: a 1.2 x 1.2 m floor patch under the chair plus
    its seat; its centroid lies in the chair's box, its surface mostly on the floor."""
    floor = trimesh.creation.box(extents=[1.2, 1.2, 0.002])
    floor.apply_translation([1.825, 1.425, 0.001])
    seat = trimesh.creation.box(extents=[0.45, 0.45, 0.02])
    seat.apply_translation([1.825, 1.425, 0.9])
    return trimesh.util.concatenate([floor.subdivide_to_size(0.05), seat]).subdivide_to_size(0.05)


def chair_mesh(gt):
    chair = next(o for o in gt["objects"] if o["class"] == "chair")
    return trimesh.load(os.path.join(gt["dir"], chair["mesh"]), force="mesh").subdivide_to_size(0.02)


def map_objects(*centroids, voxels=100, observed=0.5):
    """What object_map/objects holds: class, centroid, surface voxels and their share observed from <= d_obj."""
    return NS(objects=[NS(class_name="chair", centroid=NS(x=c[0], y=c[1], z=c[2]), voxel_count=voxels,
                          observed_fraction=observed) for c in centroids])


def test_object_observed_share_weighs_objects_by_their_voxels():
    log = RunLog()
    assert log.row(0.0, 0.0, [])["object_observed_share"] == ""
    a, b = map_objects((0, 0, 0), voxels=100, observed=0.5), map_objects((1, 1, 1), voxels=300, observed=0.9)
    log.objects = NS(objects=a.objects + b.objects)
    assert log.row(1.0, 1.0, [])["object_observed_share"] == pytest.approx((50 + 270) / 400)


def test_time_series_counts_what_the_report_counts(gt, tmp_path):
    chair_id = next(o["id"] for o in gt["objects"] if o["class"] == "chair")
    index = GroundTruthIndex(gt, ["chair"])
    maps = iter([{1: bled_mask_mesh()}, {1: bled_mask_mesh(), 2: chair_mesh(gt)}])
    snap_dir = str(tmp_path / "snapshot")

    def save(directory):
        write_objects(directory, next(maps))
        return {"success": True}

    log = RunLog()
    snaps = ObjectSnapshots(index, save, snap_dir, period_s=5.0)
    gt_objs = [o for o in gt["objects"] if o["class"] == "chair"]
    assert snaps.due(0.3)
    log.objects = map_objects(bled_mask_mesh().vertices.mean(0))
    assert np.all((bled_mask_mesh().vertices.mean(0) >= CHAIR_LO) & (bled_mask_mesh().vertices.mean(0) <= CHAIR_HI))
    assert snaps.take(0.3, log) == []
    row = log.row(1.0, 0.5, gt_objs)
    # The bled object's centroid is in the chair's box: the proxy counts it; its mesh lies on the floor.
    assert row["ground_truth_found_proxy"] == 1
    assert row["ground_truth_found"] == 0 and row["found_at_s"] == 0.3
    report = index.evaluate_objects(metrics.load_reconstruction(snap_dir), score=False)
    assert report.found_gt_ids == [] and report.matches[0].gt_id is None
    assert not snaps.due(4.9) and snaps.due(5.0)
    assert snaps.take(5.2, log) == [chair_id]
    row = log.row(6.0, 3.0, gt_objs)
    assert row["ground_truth_found"] == 1 and row["found_at_s"] == 5.2
    assert index.evaluate_objects(metrics.load_reconstruction(snap_dir), score=False).found_gt_ids == [chair_id]
    assert not snaps.due(9.9) and snaps.due(10.0)
    s = snaps.summary(run_wall_s=100.0)
    assert s["count"] == 2 and s["failed"] == 0 and 0 < s["share_of_wall"] < 1


def test_failed_snapshot_keeps_the_last_count(gt, tmp_path):
    log = RunLog()
    snaps = ObjectSnapshots(GroundTruthIndex(gt, ["chair"]), lambda d: {"success": False, "message": "down"},
                            str(tmp_path / "s"), period_s=5.0)
    assert snaps.take(1.0, log) is None
    assert log.row(1.0, 1.0, [])["ground_truth_found"] == ""
    assert snaps.summary(10.0)["failed"] == 1 and snaps.summary(10.0)["last_error"] == "down"


def test_campaign_curves_use_the_matched_count(tmp_path):
    # ground_truth_found (matched) and the proxy disagree; the curve follows the matched count,
    # an empty field (before the first snapshot) holds the value before it.
    d = tmp_path / "run"
    d.mkdir()
    (d / "timeseries.csv").write_text("sim_s,explored_volume_m3,ground_truth_found,found_at_s,"
                                      "ground_truth_found_proxy,path_length_m\n"
                                      "0,0,,,0,0\n1,1,0,0.5,1,1\n2,2,,0.5,2,2\n3,3,2,2.5,2,3\n")
    (d / "summary.json").write_text(json.dumps({"ground_truth_objects": 2}))
    run = experiments.read_run(str(d))
    assert run["series"]["found_percent"].tolist() == [0.0, 0.0, 0.0, 100.0]

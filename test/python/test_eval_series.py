"""The time series' accuracy and completeness (eval.snapshots): map snapshots
taken during a run, scored after it against the ground truth, added to
timeseries.csv; on the furnished room of test_eval_background."""
import csv
import os

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")
pytest.importorskip("embreex")

from semantic_exploration.eval import metrics, snapshots  # noqa: E402
from semantic_exploration.eval.truth import GroundTruthIndex  # noqa: E402
from semantic_exploration.sim.scene import export_ground_truth  # noqa: E402

from test_eval_background import GRID_ORIGIN, R_M, _scene, _scene_mesh, _voxel_centres  # noqa: E402


@pytest.fixture(scope="module")
def gt(tmp_path_factory):
    d = str(tmp_path_factory.mktemp("gt"))
    export_ground_truth(_scene(), d, ["chair", "table", "cabinet"])
    return metrics.load_ground_truth(d)


@pytest.fixture(scope="module")
def index(gt):
    return GroundTruthIndex(gt, ["chair"])


def chair_offset(gt, offset_m):
    """The chair's surface, sampled 5 mm apart and moved offset_m along its outward normals."""
    chair = next(o for o in gt["objects"] if o["class"] == "chair")
    mesh = trimesh.load(os.path.join(gt["dir"], chair["mesh"]), force="mesh")
    pts, fi = trimesh.sample.sample_surface_even(mesh, int(mesh.area / 0.005 ** 2), seed=5)
    return chair["id"], pts + offset_m * mesh.face_normals[fi]


def test_object_summary(gt, index):
    gid, pts = chair_offset(gt, 0.01)
    s = index.object_summary([(gid, pts)])
    assert s["object_rmse_m"] == pytest.approx(0.01, abs=0.001)  # 1 cm off the surface
    assert s["object_completeness"] == 1.0                       # within 5 cm everywhere
    # Only the chair's top half: its observable surface is the top, the sides; the sides' lower half is missing.
    top = pts[pts[:, 2] > 0.45]
    half = index.object_summary([(gid, top)])["object_completeness"]
    # Sides 4 x 0.45 x 0.9 m^2, top 0.45^2: covered the top, the upper half of the sides and 5 cm below it.
    assert half == pytest.approx((0.45 ** 2 + 4 * 0.45 * 0.5) / (0.45 ** 2 + 4 * 0.45 * 0.9), abs=0.02)
    none = index.object_summary([])
    assert np.isnan(none["object_rmse_m"]) and none["object_completeness"] == 0.0


def test_snapshots_scored_and_added_to_the_time_series(gt, index, tmp_path):
    d = tmp_path / "series"
    d.mkdir()
    gid, pts = chair_offset(gt, 0.01)
    np.savez(str(d / "objects_000005.00.npz"), sim_s=5.0, gt_ids=np.zeros(0, np.int64))
    np.savez(str(d / "objects_000010.00.npz"), sim_s=10.0, gt_ids=np.array([gid]), v0=pts.astype(np.float32))
    centres = _voxel_centres(_scene_mesh(gt), R_M, GRID_ORIGIN)
    np.save(str(d / "occupied_000010.00.npy"), centres.astype(np.float32))
    scores = snapshots.score_series(index, str(d))
    assert sorted(scores) == [5.0, 10.0]
    assert scores[5.0]["object_completeness"] == 0.0 and np.isnan(scores[5.0]["object_rmse_m"])
    assert scores[10.0]["object_rmse_m"] == pytest.approx(0.01, abs=0.001)
    # The perfect voxel map: as evaluate_background scores it (completeness on every 8th observable sample).
    exact = index.evaluate_background(centres.astype(np.float32).astype(np.float64))
    assert scores[10.0]["background_rmse_m"] == pytest.approx(exact.rmse_m, rel=1e-9)
    assert scores[10.0]["background_completeness"] == 1.0 == exact.completeness
    ts = tmp_path / "timeseries.csv"
    ts.write_text("sim_s,explored_volume_m3\n0,0\n5,1\n7,2\n10,3\n12,4\n")
    snapshots.add_series_columns(str(ts), scores, final={"object_rmse_m": 0.02, "background_rmse_m": 0.03})
    rows = list(csv.DictReader(open(str(ts))))
    assert [r["object_completeness"] for r in rows] == ["", "0.00000", "0.00000", "1.00000", "1.00000"]
    assert [r["object_rmse_m"] for r in rows][:3] == ["", "", ""] and rows[4]["object_rmse_m"] == "0.02000"
    assert float(rows[3]["object_rmse_m"]) == pytest.approx(0.01, abs=0.001)
    assert [r["background_rmse_m"] for r in rows][:3] == ["", "", ""] and rows[4]["background_rmse_m"] == "0.03000"
    assert rows[4]["explored_volume_m3"] == "4"


def test_point_cloud_is_read():
    from types import SimpleNamespace as NS
    xyz = np.array([[1.0, 2.0, 3.0], [-4.5, 0.25, 7.0]], np.float32)
    rgb = np.array([[1, 2, 3, 0], [4, 5, 6, 0]], np.uint8)
    data = np.hstack([xyz.view(np.uint8).reshape(2, 12), rgb]).tobytes()  # x y z r g b (pad): 16 bytes a point
    msg = NS(fields=[NS(name="x", offset=0), NS(name="y", offset=4), NS(name="z", offset=8), NS(name="rgb", offset=12)],
             point_step=16, data=data)
    assert np.array_equal(snapshots.cloud_xyz(msg), xyz)

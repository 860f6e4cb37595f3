"""Evaluation metrics against hand-computed answers on analytic surfaces."""
import json
import os

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from semantic_exploration.eval import metrics  # noqa: E402


def square_mesh(path, size=1.0):
    """A size x size square in the z = 0 plane."""
    v = np.array([[0, 0, 0], [size, 0, 0], [size, size, 0], [0, size, 0]], float)
    trimesh.Trimesh(v, [[0, 1, 2], [0, 2, 3]], process=False).export(path)


def box_mesh(path, centre, extent):
    trimesh.creation.box(extents=extent, transform=trimesh.transformations.translation_matrix(centre)).export(path)


def grid(x0, x1, y0, y1, z, step):
    xs, ys = np.meshgrid(np.arange(x0, x1 + 1e-9, step), np.arange(y0, y1 + 1e-9, step))
    return np.stack([xs.ravel(), ys.ravel(), np.full(xs.size, z)], 1)


def test_offset_plane_has_rmse_equal_to_the_offset(tmp_path):
    square_mesh(str(tmp_path / "gt.ply"))
    truth = metrics.sample_surface(str(tmp_path / "gt.ply"), 0.002, seed=1)
    s = metrics.score_surface(grid(0, 1, 0, 1, 0.02, 0.01), truth)
    assert s.rmse_m == pytest.approx(0.02, abs=1e-3)
    assert s.completeness == pytest.approx(1.0, abs=1e-3)


def test_half_covered_plane_completeness(tmp_path):
    # Points over x in [0, 0.5] at height 2 cm: true samples are covered up to
    # x = 0.5 + sqrt(0.05^2 - 0.02^2) = 0.5458, so completeness is 0.5458.
    square_mesh(str(tmp_path / "gt.ply"))
    truth = metrics.sample_surface(str(tmp_path / "gt.ply"), 0.002, seed=1)
    s = metrics.score_surface(grid(0, 0.5, 0, 1, 0.02, 0.002), truth)
    assert s.completeness == pytest.approx(0.5 + np.sqrt(0.05 ** 2 - 0.02 ** 2), abs=0.01)
    assert s.rmse_m == pytest.approx(0.02, abs=1e-3)


def test_empty_reconstruction_is_incomplete(tmp_path):
    square_mesh(str(tmp_path / "gt.ply"))
    truth = metrics.sample_surface(str(tmp_path / "gt.ply"), 0.01)
    s = metrics.score_surface(np.zeros((0, 3)), truth)
    assert s.completeness == 0.0 and np.isnan(s.rmse_m)


def test_objects_are_matched_to_the_surface_they_lie_on(tmp_path):
    gt_dir, rec_dir = tmp_path / "gt", tmp_path / "rec"
    (gt_dir / "objects").mkdir(parents=True)
    rec_dir.mkdir()
    box_mesh(str(gt_dir / "objects" / "1.ply"), [0, 0, 0.5], [0.5, 0.5, 1.0])
    box_mesh(str(gt_dir / "objects" / "2.ply"), [3, 0, 0.5], [0.5, 0.5, 1.0])
    box_mesh(str(gt_dir / "objects" / "3.ply"), [0, 3, 0.4], [1.0, 0.6, 0.8])
    json.dump({"background_mesh": "background.ply", "objects": [
        {"id": 1, "class": "chair", "mesh": "objects/1.ply"},
        {"id": 2, "class": "chair", "mesh": "objects/2.ply"},
        {"id": 3, "class": "table", "mesh": "objects/3.ply"}]}, open(gt_dir / "objects.json", "w"))
    # Map object 7: chair 1's surface, 1 cm too large. Map object 8: a chair
    # floating where nothing is. Map object 9: a "chair" lying on the table.
    box_mesh(str(rec_dir / "7.ply"), [0, 0, 0.5], [0.52, 0.52, 1.02])
    box_mesh(str(rec_dir / "8.ply"), [6, 6, 0.5], [0.5, 0.5, 1.0])
    box_mesh(str(rec_dir / "9.ply"), [0, 3, 0.4], [1.0, 0.6, 0.8])
    json.dump({"objects": [{"id": 7, "class_name": "chair", "mesh": "7.ply"},
                           {"id": 8, "class_name": "chair", "mesh": "8.ply"},
                           {"id": 9, "class_name": "chair", "mesh": "9.ply"}]}, open(rec_dir / "objects.json", "w"))
    # No room and no start here, so completeness counts the whole surface (test_eval_observable covers the rest).
    ev = metrics.evaluate_objects(metrics.load_ground_truth(str(gt_dir)), metrics.load_reconstruction(str(rec_dir)),
                                  ["chair"], spacing_m=0.005, observable_only=False)
    by_id = {m.map_id: m for m in ev.matches}
    assert by_id[7].gt_id == 1 and by_id[7].on_surface_fraction == 1.0
    assert by_id[8].gt_id is None and by_id[8].on_surface_fraction == 0.0
    assert by_id[9].gt_id is None  # a table is not a chair
    assert ev.n_ground_truth == 2 and ev.found_gt_ids == [1]
    assert ev.found_fraction == 0.5
    # Box vertices 1 cm outside each face: distance to the surface sqrt(3) cm at
    # the corners (the only vertices of a trimesh box).
    assert by_id[7].score.rmse_m == pytest.approx(0.01 * np.sqrt(3), abs=2e-3)


def test_point_cloud_ply_is_read(tmp_path):
    pts = grid(0, 1, 0, 1, 0.0, 0.25)
    trimesh.PointCloud(pts).export(str(tmp_path / "cloud.ply"))
    got = metrics.read_ply_vertices(str(tmp_path / "cloud.ply"))
    assert got.shape == (25, 3)
    assert np.allclose(np.sort(got, 0), np.sort(pts, 0))


def test_empty_mesh_reads_as_no_vertices(tmp_path):
    # What object_map/save writes for an object whose TSDF has no surface yet.
    with open(str(tmp_path / "empty.ply"), "wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                b"property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                b"element face 0\nproperty list uchar uint vertex_indices\nend_header\n")
    assert metrics.read_ply_vertices(str(tmp_path / "empty.ply")).shape == (0, 3)

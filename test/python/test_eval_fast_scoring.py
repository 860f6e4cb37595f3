"""The faster scoring algorithms give the same answers, value for value, as
the straightforward ones they replaced (written out here as references), on
a small furnished room: observability with the first surface along each ray
found before the camera search and the incidence rule applied before rays
are built, probe masks carried per face, the capped clearance transform,
k-d tree queries in spatial order, and surface sampling."""
import os
import types

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")
pytest.importorskip("embreex")

from scipy import ndimage  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

from semantic_exploration.eval import metrics, observable  # noqa: E402
from semantic_exploration.eval.truth import GroundTruthIndex  # noqa: E402
from semantic_exploration.sim.scene import export_ground_truth  # noqa: E402

from test_eval_background import _scene, _voxel_centres, _scene_mesh  # noqa: E402


def reference_sees(self, p, u, n=None):
    """Observability._sees before: the camera search to the depth limit, then one occlusion test."""
    eps = 1e-3
    if n is not None:
        steep = np.abs(np.einsum("ij,ij->i", n, u)) >= np.cos(self.view.max_incidence_rad) - 1e-9
        out = np.zeros(len(p), bool)
        if np.any(steep):
            out[steep] = self._sees(p[steep], u[steep])
        return out
    cos_axis = np.cos(np.arcsin(np.clip(u[:, 2], -1, 1)) - self.view.pitch_rad)
    t_cam = self._first_camera_position(p, u, self.view.d_min_m / cos_axis, self.view.d_max_m / cos_axis)
    ok = np.isfinite(t_cam)
    if np.any(ok):
        o = (p[ok] + eps * u[ok]).astype(np.float32)
        free = self._embree.run(o, u[ok].astype(np.float32), dists=(t_cam[ok] - eps).astype(np.float32),
                                query="OCCLUDED") == -1
        ok[np.flatnonzero(ok)[~free]] = False
    return ok


def reference_first_camera_position(self, p, u, t0, t1, max_steps=200):
    """Observability._first_camera_position before: three-index reads of the grid."""
    res, shape = self._res, np.array(self._to_camera.shape)
    t = t0.copy()
    out = np.full(len(p), np.inf)
    act = np.flatnonzero(t <= t1)
    for _ in range(max_steps):
        if len(act) == 0:
            break
        x = p[act] + t[act, None] * u[act]
        idx = np.floor((x - self._origin) / res).astype(np.int64)
        inside = np.all((idx >= 0) & (idx < shape), axis=1)
        act, idx = act[inside], idx[inside]
        g = self._to_camera[idx[:, 0], idx[:, 1], idx[:, 2]]
        hit = g == 0
        out[act[hit]] = t[act[hit]]
        act, g = act[~hit], g[~hit]
        t[act] += np.maximum(g - 0.87 * res, 0.5 * res)
        act = act[t[act] <= t1[act]]
    self.unresolved_rays += len(act)
    return out


def reference_mask(self, points, normals=None, chunk=16384, round_rays=8):
    """Observability.mask before: every ray of a round built, the incidence rule applied in _sees."""
    points = np.asarray(points, np.float64).reshape(-1, 3)
    if normals is not None:
        normals = np.asarray(normals, np.float64).reshape(-1, 3)
        normals = normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    rng = np.random.default_rng(self.view.seed)
    k = self.view.directions
    out = np.zeros(len(points), bool)
    order = np.random.default_rng(self.view.seed + 1).permutation(k)
    for a in range(0, len(points), chunk):
        p = points[a:a + chunk]
        dirs = self._directions(len(p), rng)[:, order]
        seen = np.zeros(len(p), bool)
        for r in range(0, k, round_rays):
            todo = np.flatnonzero(~seen)
            if len(todo) == 0:
                break
            u = dirs[todo, r:r + round_rays].reshape(-1, 3)
            owner = np.repeat(todo, min(round_rays, k - r))
            nn = None if normals is None else normals[a:a + chunk][owner]
            seen[np.unique(owner[self._sees(p[owner], u, nn)])] = True
        out[a:a + chunk] = seen
    return out


def reference_mask_by_probes(obs, points, point_faces, probes, probe_faces, probe_normals):
    """mask_by_probes before: one 4-d tree, faces 1 km apart along the fourth axis."""
    seen = obs.mask(probes, probe_normals)
    tree = cKDTree(np.hstack([probes, 1e3 * probe_faces[:, None].astype(np.float64)]))
    _, i = tree.query(np.hstack([points, 1e3 * point_faces[:, None].astype(np.float64)]))
    return seen[i]


def reference_score(reconstructed, truth, threshold_m, observable_mask):
    """score_surface before: plain trees, queries in the given order."""
    counted = truth[observable_mask]
    d_rec, _ = cKDTree(truth).query(reconstructed)
    d_gt, _ = cKDTree(reconstructed).query(counted, distance_upper_bound=threshold_m)
    return float(np.sqrt(np.mean(d_rec ** 2))), float(np.mean(np.isfinite(d_gt)))


@pytest.fixture(scope="module")
def gt(tmp_path_factory):
    d = str(tmp_path_factory.mktemp("gt"))
    export_ground_truth(_scene(), d, ["chair", "table", "cabinet"])
    return metrics.load_ground_truth(d)


@pytest.fixture(scope="module")
def obs_pair(gt):
    fast = observable.for_ground_truth(gt)
    ref = observable.for_ground_truth(gt)
    ref._sees = types.MethodType(reference_sees, ref)
    ref.mask = types.MethodType(reference_mask, ref)
    ref._first_camera_position = types.MethodType(reference_first_camera_position, ref)
    return fast, ref


def test_clearance_equals_the_euclidean_distance_transform(gt):
    v, f = observable.scene_of_ground_truth(gt)
    free, _ = observable._free_cells(v, f, 0.025)
    expected = ndimage.distance_transform_edt(free) * 0.025 - 0.5 * 0.025 >= 0.125
    assert np.array_equal(observable._clear_cells(free, 0.025, 0.125), expected)
    rng = np.random.default_rng(0)
    for _ in range(10):  # random grids, radii and cell sizes
        fr = rng.random((24, 20, 16)) > rng.uniform(0.002, 0.05)
        res, r = rng.uniform(0.01, 0.05), rng.uniform(0.02, 0.3)
        assert np.array_equal(observable._clear_cells(fr, res, r),
                              ndimage.distance_transform_edt(fr) * res - 0.5 * res >= r)


def test_object_masks_are_the_same(gt, obs_pair):
    fast, ref = obs_pair
    seen = []
    for o in gt["objects"]:
        path = os.path.join(gt["dir"], o["mesh"])
        pts, faces = metrics.sample_surface_faces(path, 0.01, 0)
        normals = metrics.face_normals(path, faces)
        a, b = fast.mask(pts, normals), ref.mask(pts, normals)
        assert np.array_equal(a, b), o["mesh"]
        seen.append(a)
    seen = np.concatenate(seen)
    assert 0.1 < seen.mean() < 0.95  # some seen, some hidden (bottoms): the comparison means something


def test_probe_masks_are_the_same(gt, obs_pair):
    fast, _ = obs_pair
    for m in [gt["background_mesh"]] + [o["mesh"] for o in gt["objects"]]:
        path = os.path.join(gt["dir"], m)
        pts, faces = metrics.sample_surface_faces(path, 0.02, 0)
        probes, pf = metrics.sample_surface_faces(path, 0.1, 0, face_centres=True)
        normals = metrics.face_normals(path, pf)
        assert np.array_equal(fast.mask_by_probes(pts, faces, probes, pf, normals),
                              reference_mask_by_probes(fast, pts, faces, probes, pf, normals)), m


def test_background_scores_are_the_same(gt):
    centres = _voxel_centres(_scene_mesh(gt), 0.04, np.array([0.013, 0.029, 0.007]))
    rng = np.random.default_rng(1)
    # Noise and a few far-off points, so that the two-step nearest search takes its second step.
    # Half the room left out, so that completeness is well below 1.
    centres = centres[centres[:, 0] > 1.5]
    rec = np.vstack([centres + rng.normal(0, 0.01, centres.shape), rng.uniform(-2, 5, (50, 3))])
    s = metrics.evaluate_background(gt, rec)
    bg = GroundTruthIndex(gt, []).background
    rmse, completeness = reference_score(rec, bg.samples, metrics.COMPLETENESS_THRESHOLD_M, bg.visible)
    assert s.rmse_m == rmse and s.completeness == completeness
    assert 0.5 < completeness < 1.0


def test_surface_samples_are_trimeshs(gt):
    # metrics' sampler draws the same random numbers and does the same arithmetic as trimesh's.
    for m in [gt["background_mesh"]] + [o["mesh"] for o in gt["objects"]]:
        mesh = trimesh.load(os.path.join(gt["dir"], m), process=False, force="mesh")
        for count, seed in ((1, 0), (5000, 0), (123457, 3)):
            a, fa = trimesh.sample.sample_surface(mesh, count, seed=seed)
            b, fb = metrics._sample_triangles(mesh, count, seed, chunk=4096)
            assert np.array_equal(a, b) and np.array_equal(fa, fb), (m, count)

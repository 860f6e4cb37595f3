"""Background accuracy and completeness (eval.metrics.evaluate_background)
against a perfect synthetic voxel map of a small furnished room: the ground
truth's surfaces voxelised at r, as the background map would hold them."""
import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")
pytest.importorskip("embreex")

from semantic_exploration.eval import metrics  # noqa: E402
from semantic_exploration.sim.scene import Scene, export_ground_truth  # noqa: E402

R_M = 0.04          # voxel size of the synthetic map, m (config/semantic.yaml background_map/resolution_m)
SPACING_M = 0.01    # evaluate_background's ground-truth sample spacing, m
ROOM = (3.0, 2.5, 2.2)
START = (0.6, 0.6, 1.2, 0.0)
# The map's grid origin: generic, so that no wall lies exactly on a voxel boundary.
GRID_ORIGIN = np.array([0.013, 0.029, 0.007])


def _box(lo, hi, rotation=None):
    m = trimesh.creation.box(extents=np.subtract(hi, lo))
    if rotation is not None:
        m.apply_transform(rotation)
    m.apply_translation(np.add(lo, hi) / 2.0)
    return np.asarray(m.vertices), np.asarray(m.faces)


def _scene():
    """Floor, ceiling, four 5 cm walls; a chair (of interest) on the floor,
    a table (not of interest), and a plank tilted about a skew axis (faces
    in no axis plane)."""
    x, y, h = ROOM
    t = 0.05
    tilt = trimesh.transformations.rotation_matrix(0.6, [1.0, 0.7, 0.3])
    parts = [((-t, -t, -t), (x + t, y + t, 0.0), 1, None), ((-t, -t, h), (x + t, y + t, h + t), 2, None),
             ((-t, -t, 0.0), (0.0, y + t, h), 3, None), ((x, -t, 0.0), (x + t, y + t, h), 3, None),
             ((0.0, -t, 0.0), (x, 0.0, h), 3, None), ((0.0, y, 0.0), (x, y + t, h), 3, None),
             ((1.6, 1.2, 0.0), (2.05, 1.65, 0.9), 4, None),       # chair
             ((0.4, 1.5, 0.0), (1.2, 2.1, 0.75), 5, None),        # table
             ((1.8, 0.3, 1.0), (2.6, 0.7, 1.06), 6, tilt)]        # plank
    verts, faces, ids, n = [], [], [], 0
    for lo, hi, oid, rot in parts:
        v, f = _box(lo, hi, rot)
        verts.append(v)
        faces.append(f + n)
        ids.append(np.full(len(f), oid))
        n += len(v)
    return Scene(np.vstack(verts), np.vstack(faces), np.concatenate(ids), name="room", start=START,
                 objects={1: "floor", 2: "ceiling", 3: "wall", 4: "chair", 5: "table", 6: "cabinet"})


def _scene_mesh(gt):
    import os
    parts = [trimesh.load(os.path.join(gt["dir"], m), process=False, force="mesh")
             for m in [gt["background_mesh"]] + [o["mesh"] for o in gt["objects"]]]
    return trimesh.util.concatenate(parts)


def _voxel_centres(mesh, r, origin):
    """Centres of the voxels (edge r, grid through origin) the mesh's surface
    passes through: every face covered by a barycentric lattice r / 8 apart."""
    tri = np.asarray(mesh.triangles)
    pts = []
    for a, b, c in tri:
        k = max(1, int(np.ceil(max(np.linalg.norm(b - a), np.linalg.norm(c - a), np.linalg.norm(c - b)) / (r / 8))))
        i, j = np.meshgrid(np.arange(k + 1), np.arange(k + 1), indexing="ij")
        keep = i + j <= k
        u, w = i[keep] / k, j[keep] / k
        pts.append(a + u[:, None] * (b - a) + w[:, None] * (c - a))
    cells = np.floor((np.vstack(pts) - origin) / r).astype(np.int64)
    # One integer key per cell, in the cells' lexicographic order: np.unique on it sorts millions of lattice
    # points many times faster than np.unique(axis=0) on the rows, with the same result.
    lo = cells.min(axis=0)
    span = cells.max(axis=0) - lo + 1
    key = np.unique(((cells[:, 0] - lo[0]) * span[1] + (cells[:, 1] - lo[1])) * span[2] + (cells[:, 2] - lo[2]))
    cells = np.stack([key // (span[1] * span[2]), key // span[2] % span[1], key % span[2]], axis=1) + lo
    return origin + (cells + 0.5) * r


@pytest.fixture(scope="module")
def gt(tmp_path_factory):
    d = str(tmp_path_factory.mktemp("gt"))
    export_ground_truth(_scene(), d, ["chair", "table", "cabinet"])
    return metrics.load_ground_truth(d)


def test_bound_of_a_perfect_voxel_map():
    # r / 2 for a plane along a space diagonal, plus the sampling term s^2 / pi.
    assert metrics.voxel_map_rmse_bound(0.04, 0.01) == pytest.approx(np.sqrt(0.02 ** 2 + 0.01 ** 2 / np.pi))
    assert metrics.voxel_map_rmse_bound(0.04, 0.0) == pytest.approx(0.02)


def test_perfect_voxel_map_is_within_the_bound_and_complete(gt):
    centres = _voxel_centres(_scene_mesh(gt), R_M, GRID_ORIGIN)
    s = metrics.evaluate_background(gt, centres)
    bound = metrics.voxel_map_rmse_bound(R_M, SPACING_M)
    # The chair's voxels are scored against the chair: against the floor
    # below it (the scene without the objects of interest) the RMSE would be
    # about 7 cm here.
    assert s.rmse_m <= bound, (s.rmse_m, bound)
    assert s.rmse_m >= R_M / np.sqrt(12.0)  # no better than an axis-aligned plane can be
    assert s.completeness == 1.0
    assert s.n_reconstructed == len(centres)


def test_reconstruction_offset_by_3_cm(gt):
    # Every surface sampled at one point per cm^2 (uniform random: a gap that
    # leaves a truth sample 5 cm from every moved point, no point within 4 cm in the face,
    # has probability exp(-50)) and moved 3 cm along its outward normal (into
    # the room for the walls' inner faces): RMSE 3 cm, less only within 3 cm
    # of concave edges, where a moved point comes nearer the other face.
    # trimesh's even sampling would cost three times the scoring here.
    mesh = _scene_mesh(gt)
    pts, fi = trimesh.sample.sample_surface(mesh, int(mesh.area / 0.01 ** 2), seed=3)
    moved = pts + 0.03 * mesh.face_normals[fi]
    s = metrics.evaluate_background(gt, moved)
    assert s.rmse_m == pytest.approx(0.03, abs=0.003)
    assert s.completeness == 1.0

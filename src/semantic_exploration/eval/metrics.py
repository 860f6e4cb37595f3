"""Reconstruction metrics of the paper's Section V-B, against ground truth.

Ground truth is what the simulator exports (`objects.json`, one PLY per
object, `background.ply`); a reconstruction is what `object_map/save` writes
(`objects.json` index + one PLY mesh per object) and the background map's
occupied voxel centres.

Distances to a ground-truth surface are measured to a dense, seeded sample of
that surface (spacing `sample_spacing_m`, default 5 mm) through a k-d tree,
so a distance is over-estimated by at most about half the spacing.

Completeness counts only the *observable* ground-truth samples (see
`observable`): those some camera pose the MAV can take sees, so the bottom
of a chair standing on the floor or a face pressed against a wall, which no
exploration can reconstruct, do not count as missing. Accuracy and the
matching of map objects to ground-truth objects use the whole surface.
"""
import json
import os
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np
from scipy.spatial import cKDTree

COMPLETENESS_THRESHOLD_M = 0.05  # "within 5 cm" (paper Section V-B)


def read_ply_vertices(path: str) -> np.ndarray:
    """Vertex positions (N x 3, float64) of a PLY mesh or point cloud (ASCII or binary)."""
    import trimesh
    geom = trimesh.load(path, process=False)  # a PLY without faces loads as a PointCloud
    if not hasattr(geom, "vertices"):  # an empty PLY loads as an empty Scene
        return np.zeros((0, 3))
    return np.asarray(geom.vertices, dtype=np.float64).reshape(-1, 3)


def sample_surface(path: str, spacing_m: float, seed: int = 0) -> np.ndarray:
    """Seeded uniform samples of a mesh surface, about one per spacing_m^2,
    plus the mesh's vertices (so thin parts are never missed)."""
    return sample_surface_faces(path, spacing_m, seed)[0]


def sample_surface_faces(path: str, spacing_m: float, seed: int = 0, face_centres: bool = False):
    """sample_surface's points and the face each lies on (a vertex: one of its
    faces; -1 for a mesh without faces). face_centres adds every face's centroid
    (so each face holds at least one sample)."""
    import trimesh
    mesh = trimesh.load(path, process=False, force="mesh")
    verts = np.asarray(mesh.vertices, dtype=np.float64).reshape(-1, 3)
    if len(mesh.faces) == 0:
        return verts, np.full(len(verts), -1, np.int64)
    faces = np.asarray(mesh.faces, np.int64)
    count = max(1, int(np.ceil(mesh.area / (spacing_m * spacing_m))))
    pts, fi = _sample_triangles(mesh, count, seed)
    vface = np.full(len(verts), -1, np.int64)
    vface[faces.ravel()] = np.repeat(np.arange(len(faces)), 3)
    parts = [np.asarray(pts, np.float64), verts]
    fparts = [np.asarray(fi, np.int64), vface]
    if face_centres:
        parts.append(verts[faces].mean(1))
        fparts.append(np.arange(len(faces)))
    keep = np.concatenate(fparts) >= 0  # vertices no face uses are no surface
    return np.vstack(parts)[keep], np.concatenate(fparts)[keep]


def _sample_triangles(mesh, count: int, seed: int, chunk: int = 1 << 20):
    """trimesh.sample.sample_surface(mesh, count, seed=seed), the same points
    (the same random draws and the same arithmetic, element by element)
    without its (count, 2, 3) temporaries."""
    w = np.cumsum(mesh.area_faces)
    rng = np.random.default_rng(seed)
    fi = np.searchsorted(w, rng.random(count) * w[-1])
    lengths = rng.random((count, 2, 1))[:, :, 0]
    flip = lengths.sum(axis=1) > 1.0
    lengths[flip] -= 1.0
    lengths = np.abs(lengths)
    v = np.asarray(mesh.vertices, np.float64)
    f = np.asarray(mesh.faces, np.int64)
    o = v[f[:, 0]]
    e1, e2 = v[f[:, 1]] - o, v[f[:, 2]] - o
    out = np.empty((count, 3))
    for a in range(0, count, chunk):
        i, l = fi[a:a + chunk], lengths[a:a + chunk]
        out[a:a + chunk] = (e1[i] * l[:, :1] + e2[i] * l[:, 1:]) + o[i]
    return out, fi


def face_normals(path: str, faces: np.ndarray) -> np.ndarray:
    """Unit normals (N x 3) of the given faces of a mesh (zero for a degenerate face)."""
    import trimesh
    mesh = trimesh.load(path, process=False, force="mesh")
    tri = np.asarray(mesh.vertices, np.float64)[np.asarray(mesh.faces, np.int64)[faces]]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)


@dataclass
class SurfaceScore:
    """Accuracy (RMSE of reconstructed points to the true surface, m) and
    completeness (fraction of the counted true surface samples -- the
    observable ones, see the module doc -- with a reconstructed point within
    the threshold; nan if none is observable)."""
    rmse_m: float
    completeness: float
    n_reconstructed: int
    n_ground_truth: int             # true surface samples
    observable_fraction: float = 1.0  # fraction of them counted in completeness


def spatial_order(points: np.ndarray, cell_m: float = 0.1) -> np.ndarray:
    """A permutation that brings points of the same cell_m cell together:
    k-d tree queries in this order reuse the tree's nodes in cache (3-4x faster)."""
    if len(points) == 0:
        return np.zeros(0, np.int64)
    c = np.floor((points - points.min(0)) / cell_m).astype(np.int64)
    n = c.max(0) + 1
    return np.argsort((c[:, 0] * n[1] + c[:, 1]) * n[2] + c[:, 2], kind="stable")


def kd_tree(points: np.ndarray) -> cKDTree:
    """A k-d tree for exact nearest-neighbour distances; sliding-midpoint
    splits build 3x faster than median splits and answer the same."""
    return cKDTree(points, balanced_tree=False, compact_nodes=False)


def nearest_distance(tree: cKDTree, queries: np.ndarray, first_bound_m: float = 0.25) -> np.ndarray:
    """Distance (m) of each query to its nearest tree point, in the queries'
    order. Searched within first_bound_m first, then without bound for the
    queries that found nothing: far queries are what make a search slow."""
    order = spatial_order(queries)
    d, _ = tree.query(queries[order], distance_upper_bound=first_bound_m, workers=-1)
    far = np.flatnonzero(~np.isfinite(d))
    if len(far):
        d[far], _ = tree.query(queries[order[far]], workers=-1)
    out = np.empty(len(queries))
    out[order] = d
    return out


def within(tree: cKDTree, queries: np.ndarray, threshold_m: float) -> np.ndarray:
    """(N,) bool: a tree point lies within threshold_m of each query (queries' order)."""
    order = spatial_order(queries)
    d, _ = tree.query(queries[order], distance_upper_bound=threshold_m, workers=-1)
    out = np.empty(len(queries), bool)
    out[order] = np.isfinite(d)
    return out


def score_surface(reconstructed: np.ndarray, truth_samples: np.ndarray,
                  threshold_m: float = COMPLETENESS_THRESHOLD_M,
                  truth_tree: Optional[cKDTree] = None,
                  observable: Optional[np.ndarray] = None) -> SurfaceScore:
    """observable: (N,) bool over truth_samples, the samples completeness counts (default all)."""
    if len(truth_samples) == 0:
        raise ValueError("empty ground-truth surface")
    counted = truth_samples if observable is None else truth_samples[observable]
    frac = len(counted) / len(truth_samples)
    if len(reconstructed) == 0:
        return SurfaceScore(float("nan"), 0.0 if len(counted) else float("nan"), 0, len(truth_samples), frac)
    tree = truth_tree if truth_tree is not None else kd_tree(truth_samples)
    d_rec = nearest_distance(tree, reconstructed)
    if len(counted):
        completeness = float(np.mean(within(kd_tree(reconstructed), counted, threshold_m)))
    else:
        completeness = float("nan")
    return SurfaceScore(float(np.sqrt(np.mean(d_rec ** 2))), completeness, len(reconstructed), len(truth_samples),
                        frac)


@dataclass
class ObjectMatch:
    map_id: int
    map_class: str
    gt_id: Optional[int]        # None: lies on no ground-truth object of its class
    on_surface_fraction: float  # fraction of its vertices within the threshold of gt_id's surface
    score: Optional[SurfaceScore] = None
    empty: bool = False         # its mesh has no vertex yet (a surface tracked under the foreground prior only)


@dataclass
class ObjectEvaluation:
    matches: List[ObjectMatch] = field(default_factory=list)
    n_ground_truth: int = 0
    found_gt_ids: List[int] = field(default_factory=list)
    observable_fraction: Dict[int, float] = field(default_factory=dict)  # per ground-truth id, of its samples

    @property
    def found_fraction(self) -> float:
        return len(self.found_gt_ids) / self.n_ground_truth if self.n_ground_truth else float("nan")

    @property
    def spurious_map_ids(self) -> List[int]:
        """Map objects matched to no ground-truth object (they lie on none of their class), ascending. An
        object whose mesh is still empty lies on nothing and is not one: see without_surface_map_ids."""
        return sorted(m.map_id for m in self.matches if m.gt_id is None and not m.empty)

    @property
    def without_surface_map_ids(self) -> List[int]:
        """Map objects saved with an empty mesh, ascending: under the foreground prior an object made from
        one detection near its mask's border has a surface that matching tracks but no mesh yet. They can
        be neither matched nor judged spurious."""
        return sorted(m.map_id for m in self.matches if m.empty)

    @property
    def duplicates(self) -> Dict[int, List[int]]:
        """Ground-truth objects matched by more than one map object: ground-truth id -> the map ids, ascending."""
        by_gt: Dict[int, List[int]] = {}
        for m in self.matches:
            if m.gt_id is not None:
                by_gt.setdefault(m.gt_id, []).append(m.map_id)
        return {g: sorted(ids) for g, ids in sorted(by_gt.items()) if len(ids) > 1}


def load_ground_truth(gt_dir: str) -> Dict:
    with open(os.path.join(gt_dir, "objects.json")) as f:
        doc = json.load(f)
    doc["dir"] = gt_dir
    return doc


def load_reconstruction(obj_dir: str) -> Dict:
    with open(os.path.join(obj_dir, "objects.json")) as f:
        doc = json.load(f)
    doc["dir"] = obj_dir
    return doc


_OBSERVABILITY_CACHE: Dict = {}


def _observability(gt: Dict, observable_only: bool, view):
    """One Observability per ground truth and view model (objects and background share it)."""
    if not observable_only:
        return None
    from . import observable
    key = (os.path.realpath(gt["dir"]), repr(view), repr(gt.get("start")))
    if key not in _OBSERVABILITY_CACHE:
        _OBSERVABILITY_CACHE.clear()  # a grid per scene is large; keep the last one only
        _OBSERVABILITY_CACHE[key] = observable.for_ground_truth(gt, view)
    return _OBSERVABILITY_CACHE[key]


def evaluate_objects(gt: Dict, rec: Dict, classes: List[str], spacing_m: float = 0.005,
                     threshold_m: float = COMPLETENESS_THRESHOLD_M, seed: int = 0,
                     observable_only: bool = True, view=None) -> ObjectEvaluation:
    """Matches each reconstructed object to the ground-truth object of its
    class that most of its vertices lie on (within threshold_m; more than half
    of them), then scores accuracy and completeness of each match. A
    ground-truth object counts as found once any map object matches it.
    Completeness counts the observable samples only (observable.ViewModel
    `view`, default config/sim.yaml's camera and MAV; the ground truth needs
    its background and start), or all with observable_only=False."""
    from .truth import GroundTruthIndex
    return GroundTruthIndex(gt, classes, observable_only, view, object_spacing_m=spacing_m, threshold_m=threshold_m,
                            seed=seed).evaluate_objects(rec)


def evaluate_background(gt: Dict, occupied_points: np.ndarray, spacing_m: float = 0.01,
                        threshold_m: float = COMPLETENESS_THRESHOLD_M, seed: int = 0,
                        observable_only: bool = True, view=None, probe_spacing_m: float = 0.1) -> SurfaceScore:
    """Accuracy and completeness of the background map's occupied voxel
    centres against every surface of the scene, the objects of interest
    included: the background map integrates every depth pixel, so its voxels
    model the chairs too. Scoring them against the scene without the chairs
    would measure each chair voxel's distance to the floor or a wall behind it;
    taking the chairs' voxels out instead (by the object maps) would make the
    score depend on what the object maps found. Both sides cover the same
    surfaces this way. A perfect voxel map of resolution r (the centres of the
    voxels the surfaces pass through) scores an RMSE of at most
    sqrt(r^2 / 4 + s^2 / pi) on planar surfaces (s = spacing_m; see
    voxel_map_rmse_bound) and completeness 1 (every sample lies in a voxel
    whose centre is within r sqrt(3) / 2 < threshold_m for r <= 5 cm).
    Completeness counts the observable samples (as in evaluate_objects); over
    these large surfaces observability is computed at probes probe_spacing_m
    apart and carried to the samples of the same face."""
    from .truth import GroundTruthIndex
    return GroundTruthIndex(gt, [], observable_only, view, background_spacing_m=spacing_m,
                            probe_spacing_m=probe_spacing_m, threshold_m=threshold_m,
                            seed=seed).evaluate_background(occupied_points)


def voxel_map_rmse_bound(resolution_m: float, spacing_m: float = 0.01) -> float:
    """Largest background accuracy RMSE (m) of a perfect voxel map of planar
    surfaces at resolution_m, measured against samples spacing_m apart.

    A plane with unit normal n passes through the voxels whose centre c has
    |n . (c - p)| <= h = (r / 2) |n|_1 (p on the plane), and over a large plane
    these centres' signed distances are spread evenly over [-h, h]: RMSE
    h / sqrt(3), largest for n along a space diagonal (|n|_1 = sqrt(3)): r / 2
    (for an axis-aligned plane r / sqrt(12)). Measuring to the nearest of
    uniform random samples of density 1 / s^2 adds, at right angles, the
    distance from the foot point to that sample, whose mean square is s^2 / pi
    (nearest point of a planar Poisson process). Edges and corners of convex
    parts may put a centre up to r sqrt(3) / 2 from the surface; large planes
    dominate a room."""
    return float(np.sqrt(resolution_m ** 2 / 4.0 + spacing_m ** 2 / np.pi))

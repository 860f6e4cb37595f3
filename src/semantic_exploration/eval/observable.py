"""Which ground-truth surface points the MAV's camera can observe at all.

Completeness counts the fraction of ground-truth surface samples with a
reconstructed point nearby. Samples on surfaces no camera pose can see (the
bottom of a box standing on the floor, a face pressed against a wall, the
faces hidden inside overlapping parts of one piece of furniture) can never be
reconstructed, so completeness is measured against the *observable* samples:

A surface point p is observable if some camera pose the MAV can take sees it:
the camera centre c lies in the explorable free space (at least the collision
radius R from every surface and connected to the start position, on a grid of
``grid_m``), the segment from c to p hits no surface (within a 1 mm
tolerance at p), the depth of p lies in [d_min, d_max], and p lies within the
camera's vertical field of view for some yaw (the MAV only yaws; the camera is
mounted with a fixed pitch), i.e. the elevation of the direction p -> c lies in
[pitch - atan(cy / fy), pitch + atan((H - 1 - cy) / fy)], and, where the
surface normal at p is given, the view is at most ``max_incidence_rad``
(75 deg) off the normal (either side). Without that last rule, the back of an
armchair standing 15 cm from a wall counted as observable: a camera centre R
from the wall fits 2.5 cm behind the back's plane and sees it at 10 deg
grazing, where a depth camera returns next to nothing.

The existence of c is tested along ``directions`` rays per point (stratified
in azimuth and in the sine of the elevation over that band, jittered with a
fixed seed): along each ray, the first camera position in the free-space grid
is found by sphere tracing its distance field (a step never passes over a
free-space cell), and the segment from p to it is tested for occlusion with
Embree. A later position on the same ray cannot be visible if the first is
not, so one occlusion query per ray decides it. Points seen only through a
solid angle finer than the ray spacing may be missed (counted unobservable).
"""
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np


@dataclass
class ViewModel:
    """Where the camera can be and what it sees. Defaults are config/sim.yaml's
    camera and MAV (the paper's Table I)."""
    radius_m: float = 0.125    # camera centre at least this far from every surface (collision sphere R), m
    d_min_m: float = 0.1       # nearest valid depth, m
    d_max_m: float = 10.0      # farthest valid depth, m
    fy_px: float = 262.5       # vertical focal length, px
    cy_px: float = 119.5       # principal point row, px
    height_px: int = 240       # image height, px
    pitch_rad: float = 0.0     # camera mount pitch, + = down, rad
    grid_m: float = 0.025      # cell size of the free-space grid of camera positions, m
    max_incidence_rad: float = 1.309  # views farther than this from the surface normal do not count (75 deg), rad
    directions: int = 96       # rays per surface point
    seed: int = 0              # direction jitter seed

    def validate(self) -> None:
        if not (self.radius_m >= 0 and 0 <= self.d_min_m < self.d_max_m and self.fy_px > 0 and self.height_px > 0
                and 0 <= self.cy_px <= self.height_px - 1 and self.grid_m > 0 and self.directions >= 1
                and 0 < self.max_incidence_rad <= np.pi / 2):
            raise ValueError("invalid ViewModel %s" % (self,))

    def elevation_band_rad(self):
        """Elevation range (rad, + = up) of the direction from a seen point to the camera."""
        up = np.arctan(self.cy_px / self.fy_px)                        # image rows above the centre see upwards
        down = np.arctan((self.height_px - 1 - self.cy_px) / self.fy_px)
        return self.pitch_rad - up, self.pitch_rad + down

    @classmethod
    def from_sim_config(cls, doc: dict, **overrides) -> "ViewModel":
        """From a mav_sim parameter dict (config/sim.yaml layout: camera, mav sections)."""
        cam, mav = doc.get("camera", {}), doc.get("mav", {})
        d = cls()
        kw = dict(radius_m=mav.get("radius_m", d.radius_m), d_min_m=cam.get("d_min_m", d.d_min_m),
                  d_max_m=cam.get("d_max_m", d.d_max_m), fy_px=cam.get("fy", d.fy_px),
                  cy_px=cam.get("cy", d.cy_px), height_px=cam.get("height", d.height_px),
                  pitch_rad=cam.get("mount_rpy_rad", [0.0, d.pitch_rad, 0.0])[1])
        kw.update(overrides)
        return cls(**kw)


def _free_cells(vertices: np.ndarray, faces: np.ndarray, res: float, margin_cells: int = 2):
    """Cells (edge res, m) no triangle touches, over the scene's box plus a
    margin, and the grid's lower corner. Triangles are rasterised through a
    barycentric lattice about res / 2 apart along their two first edges."""
    lo = vertices.min(0) - margin_cells * res
    shape = np.maximum(np.ceil((vertices.max(0) + margin_cells * res - lo) / res).astype(int), 1)
    occ = np.zeros(shape, bool)
    tri = vertices[faces]
    a, ab, ac = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    n = np.maximum(np.ceil(np.maximum(np.linalg.norm(ab, axis=1), np.linalg.norm(ac, axis=1)) / (0.5 * res)), 1)
    for k in np.unique(n).astype(int):
        sel = np.flatnonzero(n == k)
        i, j = np.meshgrid(np.arange(k + 1), np.arange(k + 1), indexing="ij")
        keep = i + j <= k
        u, w = i[keep] / k, j[keep] / k
        for c in range(0, len(sel), max(1, 2000000 // len(u))):  # bounded memory per batch
            s = sel[c:c + max(1, 2000000 // len(u))]
            pts = a[s, None] + u[None, :, None] * ab[s, None] + w[None, :, None] * ac[s, None]
            idx = np.clip(np.floor((pts.reshape(-1, 3) - lo) / res).astype(np.int64), 0, shape - 1)
            occ[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    return ~occ, lo


def _clear_cells(free: np.ndarray, res: float, radius_m: float) -> np.ndarray:
    """Cells whose centre's distance to the nearest non-free cell centre, less
    half a cell, is at least radius_m: the same answer, float for float, as
    ndimage.distance_transform_edt(free) * res - 0.5 * res >= radius_m, from
    squared distances computed one axis after the other over offsets up to K
    cells only. Where the nearest non-free cell lies within K cells the
    squared distance is exact; otherwise it, and the true one, exceed K^2,
    and K is chosen so that any such cell is clear."""
    k_max = int(np.ceil((radius_m + 0.5 * res) / res)) + 1
    big = np.int32(3 * (k_max + 1) ** 2)
    d2 = np.where(free, big, np.int32(0)).astype(np.int32)
    for axis in range(3):
        out = d2.copy()
        n = d2.shape[axis]
        for k in range(1, min(k_max, n - 1) + 1):
            src = [slice(None)] * 3
            dst = [slice(None)] * 3
            for a, b in ((slice(k, None), slice(None, -k)), (slice(None, -k), slice(k, None))):
                src[axis], dst[axis] = a, b
                np.minimum(out[tuple(dst)], d2[tuple(src)] + np.int32(k * k), out=out[tuple(dst)])
        d2 = np.minimum(out, big)
    return np.sqrt(d2.astype(np.float64)) * res - 0.5 * res >= radius_m


class Observability:
    """Observability test of surface points in one scene (triangle soup in the world frame)."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, start_xyz: Sequence[float],
                 view: Optional[ViewModel] = None):
        import embreex.rtcore_scene as rtcs
        from embreex.mesh_construction import TriangleMesh
        from scipy import ndimage
        from ..sim.scene import SceneError
        self.view = view if view is not None else ViewModel()
        self.view.validate()
        vertices = np.asarray(vertices, np.float64).reshape(-1, 3)
        faces = np.asarray(faces, np.int64).reshape(-1, 3)
        self._embree = rtcs.EmbreeScene()
        TriangleMesh(self._embree, vertices.astype(np.float32), faces.astype(np.int32))
        res = self.view.grid_m
        # Cells touched by a surface, then each cell centre's distance to the
        # nearest touched cell; a surface lies within about half a cell of that one's centre.
        free, origin = _free_cells(vertices, faces, res)
        clear = _clear_cells(free, res, self.view.radius_m)
        s = np.floor((np.asarray(start_xyz[:3], np.float64) - origin) / res).astype(int)
        if np.any(s < 0) or np.any(s >= clear.shape) or not clear[tuple(s)]:
            raise SceneError("start %s is not at least %.3f m from every surface"
                             % (list(start_xyz[:3]), self.view.radius_m))
        labels, _ = ndimage.label(clear)
        self.camera_cells = labels == labels[tuple(s)]  # where the camera centre can be
        # Distance (m) from each cell centre to the nearest camera cell centre.
        self._to_camera = (ndimage.distance_transform_edt(~self.camera_cells) * res).astype(np.float32)
        self._origin, self._res = origin, res
        self.unresolved_rays = 0  # rays whose sphere tracing hit the iteration cap (counted unobservable)

    def _directions(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """(n, K, 3) unit directions from the point towards the camera, stratified over the band."""
        return self._unit(*self._angles(n, rng))

    @staticmethod
    def _unit(sz: np.ndarray, az: np.ndarray) -> np.ndarray:
        """Unit vectors of elevation sines sz and azimuths az (rad), shape (..., 3)."""
        r = np.sqrt(np.clip(1 - sz * sz, 0, 1))
        return np.stack([r * np.cos(az), r * np.sin(az), sz], -1)

    def _angles(self, n: int, rng: np.random.Generator):
        """_directions' elevation sines and azimuths, (n, K) each."""
        k = self.view.directions
        n_el = max(1, int(round(np.sqrt(k / 6.0))))
        n_az = int(np.ceil(k / n_el))
        lo, hi = self.view.elevation_band_rad()
        s_lo, s_hi = np.sin(max(lo, -np.pi / 2)), np.sin(min(hi, np.pi / 2))
        i_el = np.repeat(np.arange(n_el), n_az)[:k]
        i_az = np.tile(np.arange(n_az), n_el)[:k]
        sz = s_lo + (s_hi - s_lo) * (i_el[None] + rng.random((n, k))) / n_el
        az = 2 * np.pi * (i_az[None] + rng.random((n, k))) / n_az + rng.random((n, 1)) * 2 * np.pi
        return sz, az

    def _first_camera_position(self, p: np.ndarray, u: np.ndarray, t0: np.ndarray, t1: np.ndarray,
                               max_steps: int = 200) -> np.ndarray:
        """Ray parameter (m) of the first camera cell along p + t u, t in [t0, t1]; inf if none."""
        res, shape = self._res, np.array(self._to_camera.shape)
        flat = self._to_camera.reshape(-1)
        t = t0.copy()
        out = np.full(len(p), np.inf)
        act = np.flatnonzero(t <= t1)
        for _ in range(max_steps):
            if len(act) == 0:
                break
            x = p[act] + t[act, None] * u[act]
            idx = np.floor((x - self._origin) / res).astype(np.int64)
            inside = ((idx >= 0) & (idx < shape)).all(1)
            if not inside.all():
                act, idx = act[inside], idx[inside]  # the grid holds every camera cell: outside is a miss
            g = flat[(idx[:, 0] * shape[1] + idx[:, 1]) * shape[2] + idx[:, 2]]
            hit = g == 0
            out[act[hit]] = t[act[hit]]
            act, g = act[~hit], g[~hit]
            # A point in this cell is at least g - half a cell diagonal from any camera cell centre.
            t[act] += np.maximum(g - 0.87 * res, 0.5 * res)
            act = act[t[act] <= t1[act]]
        self.unresolved_rays += len(act)
        return out

    def _sees(self, p: np.ndarray, u: np.ndarray, n: Optional[np.ndarray] = None) -> np.ndarray:
        """(M,) bool: a camera position along p + t u sees p (n: unit normals at p, or None)."""
        eps = 1e-3  # rays start 1 mm off the point, so they do not hit its own face
        if n is not None:
            steep = np.abs(np.einsum("ij,ij->i", n, u)) >= np.cos(self.view.max_incidence_rad) - 1e-9
            out = np.zeros(len(p), bool)
            if np.any(steep):
                out[steep] = self._sees(p[steep], u[steep])
            return out
        # Depth is along the optical axis: the ray makes angle |elev - pitch| with it (yaw centred on p).
        cos_axis = np.cos(np.arcsin(np.clip(u[:, 2], -1, 1)) - self.view.pitch_rad)
        t0, t1 = self.view.d_min_m / cos_axis, self.view.d_max_m / cos_axis
        # The first surface along the ray (from 1 mm off p) first: a camera
        # position beyond it cannot see p, so the search stops there. p is seen
        # iff the first camera position comes before that surface, which is
        # what an occlusion test of the segment to it would answer; most rays
        # from a surface point hit another surface within centimetres.
        o = (p + eps * u).astype(np.float32)
        t_hit = self._embree.run(o, u.astype(np.float32), dists=(t1 - eps).astype(np.float32), query="DISTANCE")
        blocked = t_hit < (t1 - eps).astype(np.float32)
        t_cam = self._first_camera_position(p, u, t0, np.where(blocked, np.minimum(t1, eps + t_hit), t1))
        ok = np.isfinite(t_cam)
        ok[ok] = ~blocked[ok] | (t_hit[ok] > (t_cam[ok] - eps).astype(np.float32))
        return ok

    def mask(self, points: np.ndarray, normals: Optional[np.ndarray] = None, chunk: int = 16384,
             round_rays: int = 8) -> np.ndarray:
        """(N,) bool: which points (N x 3, m, on the scene's surfaces) are
        observable; normals (N x 3, either orientation) enable the incidence rule."""
        points = np.asarray(points, np.float64).reshape(-1, 3)
        if normals is not None:
            normals = np.asarray(normals, np.float64).reshape(-1, 3)
            normals = normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
        rng = np.random.default_rng(self.view.seed)
        k = self.view.directions
        out = np.zeros(len(points), bool)
        # Rays go out in rounds over a fixed shuffle of the strata; a point stops once one ray sees it.
        order = np.random.default_rng(self.view.seed + 1).permutation(k)
        cos_max = np.cos(self.view.max_incidence_rad) - 1e-9
        for a in range(0, len(points), chunk):
            p = points[a:a + chunk]
            sz, az = self._angles(len(p), rng)
            sz, az = sz[:, order], az[:, order]
            seen = np.zeros(len(p), bool)
            for r in range(0, k, round_rays):
                todo = np.flatnonzero(~seen)
                if len(todo) == 0:
                    break
                # This round's directions of the points not seen yet, those within the incidence limit.
                dirs = self._unit(sz[todo, r:r + round_rays], az[todo, r:r + round_rays])
                sel = (np.abs(np.einsum("ijk,ik->ij", dirs, normals[a:a + chunk][todo])) >= cos_max
                       if normals is not None else np.ones(dirs.shape[:2], bool))
                owner = np.repeat(todo, sel.sum(1))
                seen[owner[self._sees(p[owner], dirs[sel])]] = True
            out[a:a + chunk] = seen
        return out

    def mask_by_probes(self, points: np.ndarray, point_faces: np.ndarray, probes: np.ndarray,
                       probe_faces: np.ndarray, probe_normals: Optional[np.ndarray] = None,
                       seen: Optional[np.ndarray] = None) -> np.ndarray:
        """Cheaper mask for large surfaces: the observability of a coarser probe
        sample, carried to each point from the nearest probe on the same face
        (face indices of one mesh; every face needs a probe). seen: the
        probes' mask(probes, probe_normals) if already known."""
        if seen is None:
            seen = self.mask(probes, probe_normals)
        return carry_probe_masks(points, point_faces, probes, probe_faces, seen)


def carry_probe_masks(points: np.ndarray, point_faces: np.ndarray, probes: np.ndarray, probe_faces: np.ndarray,
                      seen: np.ndarray) -> np.ndarray:
    """Observability.mask_by_probes once the probes' mask `seen` is known."""
    from scipy.spatial import cKDTree
    from .metrics import spatial_order
    if len(points) == 0:
        return np.zeros(0, bool)
    # Per face: how many probes, how many seen. A face whose probes agree
    # passes their answer on (most faces, such as a wall's outside); on the
    # others each point takes its nearest probe's.
    n_faces = int(max(point_faces.max(), probe_faces.max())) + 1
    q_count = np.bincount(probe_faces, minlength=n_faces)
    q_seen = np.bincount(probe_faces, weights=seen.astype(np.float64), minlength=n_faces).astype(np.int64)
    if np.any(q_count[point_faces] == 0):
        raise ValueError("mask_by_probes: faces %s have points but no probe"
                         % np.unique(point_faces[q_count[point_faces] == 0])[:5].tolist())
    out = (q_seen == q_count)[point_faces]
    mixed = (q_seen > 0) & (q_seen < q_count)
    on_mixed = np.flatnonzero(mixed[point_faces])
    if len(on_mixed) == 0:
        return out
    p_order = on_mixed[np.argsort(point_faces[on_mixed], kind="stable")]
    faces, p_start, p_count = np.unique(point_faces[p_order], return_index=True, return_counts=True)
    q_order = np.argsort(probe_faces, kind="stable")
    q_start = np.searchsorted(probe_faces[q_order], faces, "left")
    for f, a, n, b in zip(faces, p_start, p_count, q_start):
        pi = p_order[a:a + n]
        if n > 20000:  # large faces: queries in spatial order
            pi = pi[spatial_order(points[pi])]
        qi = q_order[b:b + q_count[f]]
        out[pi] = seen[qi[cKDTree(probes[qi]).query(points[pi])[1]]]
    return out


_POOL_STATE = {}  # what forked workers of masks() read: the Observability and the jobs


def _pool_mask(i: int):
    obs, jobs = _POOL_STATE["obs"], _POOL_STATE["jobs"]
    return i, obs.mask(*jobs[i])


def masks(obs: "Observability", jobs, processes: int = 2):
    """[obs.mask(points, normals) for (points, normals) in jobs], the jobs
    spread over forked processes (largest first), which share obs's grids
    and Embree scene with this one. Each job's answer does not depend on
    where it runs: mask() seeds its directions per call."""
    import multiprocessing as mp
    if processes <= 1 or len(jobs) < 2 or "fork" not in mp.get_all_start_methods():
        return [obs.mask(*j) for j in jobs]
    order = sorted(range(len(jobs)), key=lambda i: -len(jobs[i][0]))
    out = [None] * len(jobs)
    _POOL_STATE.update(obs=obs, jobs=jobs)
    try:
        with mp.get_context("fork").Pool(min(processes, len(jobs))) as pool:
            for i, m in pool.imap_unordered(_pool_mask, order):
                out[i] = m
    finally:
        _POOL_STATE.clear()
    return out


def scene_of_ground_truth(gt: dict):
    """Vertices and faces of the whole scene from an exported ground truth
    (background.ply plus every exported object mesh)."""
    import os
    import trimesh
    verts, faces, n = [], [], 0
    for rel in [gt["background_mesh"]] + [o["mesh"] for o in gt["objects"]]:
        m = trimesh.load(os.path.join(gt["dir"], rel), process=False, force="mesh")
        verts.append(np.asarray(m.vertices, np.float64))
        faces.append(np.asarray(m.faces, np.int64) + n)
        n += len(m.vertices)
    return np.vstack(verts), np.vstack(faces)


def for_ground_truth(gt: dict, view: Optional[ViewModel] = None) -> Observability:
    """Observability in an exported ground truth (objects.json with its start)."""
    if not gt.get("start"):
        raise ValueError("ground truth in %s has no start position, so its observable surface is undefined"
                         % gt.get("dir"))
    v, f = scene_of_ground_truth(gt)
    return Observability(v, f, gt["start"], view)

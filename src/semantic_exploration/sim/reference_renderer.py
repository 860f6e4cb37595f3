"""Reference renderer: the simulator's camera as of commit 9440b49, kept unchanged.

:class:`renderer.Renderer` must give the same images where noise is off
(test/python/test_sim_render_fast.py compares them pixel for pixel) and
``scripts/bench_sim.py`` times both in one run. Do not optimise this file.

Ray-traced RGB-D camera with ground-truth instance and class images (Embree via embreex).

Depth is the optical-axis distance (z in the camera frame), as RGB-D cameras
report it. Rays are cast with direction (x, y, 1) in the camera frame, so the
hit parameter is the depth itself; it is recomputed in float64 from the hit
triangle's plane, which keeps it exact to well below a millimetre.
"""

from typing import Dict, Iterable, Optional

import numpy as np

from .classes import ClassTable
from .config import CameraConfig, NoiseConfig
from .renderer import sigma_of_depth
from .scene import Scene


class ReferenceRenderer:
    """Renders depth (32FC1 m), colour (rgb8), instance (16UC1) and class (16UC1) images of a scene."""

    def __init__(self, scene: Scene, camera: CameraConfig, classes: ClassTable,
                 non_returning: Iterable[str] = ("window", "mirror"), noise: Optional[NoiseConfig] = None):
        import embreex.rtcore_scene as rtcs
        from embreex.mesh_construction import TriangleMesh
        camera.validate()
        self.camera = camera
        self.scene = scene
        self.classes = classes
        self.noise = noise if noise is not None else NoiseConfig(enabled=False)
        self.noise.validate()
        self.rng = np.random.default_rng(self.noise.seed)
        self._embree = rtcs.EmbreeScene()
        TriangleMesh(self._embree, scene.vertices.astype(np.float32), scene.faces.astype(np.int32))
        tri = scene.triangles()
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        norm = np.linalg.norm(n, axis=1)
        self._valid_face = norm > 1e-12
        n[self._valid_face] /= norm[self._valid_face, None]
        self._normal = n
        self._offset = np.einsum("ij,ij->i", n, tri[:, 0])
        # Per-face lookups (index M = "no hit").
        m = len(scene.faces)
        # Object id -> (instance, class) tables, then per face by one gather.
        things = scene.thing_ids(classes.names)
        top = int(max(scene.face_object.max(), max(things, default=0))) + 1
        id_inst = np.zeros(top, np.uint16)
        id_cls = np.zeros(top, np.uint16)
        for oid in things:
            id_inst[oid] = oid
            id_cls[oid] = classes.id(scene.objects[oid])
        fo = np.clip(scene.face_object, 0, top - 1)
        self._face_instance = np.append(id_inst[fo], np.uint16(0))
        self._face_class = np.append(id_cls[fo], np.uint16(0))
        nr = np.zeros(m + 1, bool)
        nr[:m] = scene.non_returning_faces(non_returning)
        nr[m] = True
        self._face_nonreturning = nr
        self._face_color = np.vstack([scene.face_colors, [[0, 0, 0]]]).astype(np.float32)
        u, v = np.meshgrid(np.arange(camera.width, dtype=np.float64), np.arange(camera.height, dtype=np.float64))
        self._dirs_C = np.stack([(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy,
                                 np.ones_like(u)], -1).reshape(-1, 3)
        self._inv_ray_len = 1.0 / np.linalg.norm(self._dirs_C, axis=1)  # rotation-invariant
        self._origins = np.empty((camera.width * camera.height, 3), np.float32)

    def camera_info(self) -> Dict:
        """Intrinsics as sensor_msgs/CameraInfo fields (plumb_bob, zero distortion)."""
        c = self.camera
        return {"width": c.width, "height": c.height, "distortion_model": "plumb_bob", "D": [0.0] * 5,
                "K": [c.fx, 0.0, c.cx, 0.0, c.fy, c.cy, 0.0, 0.0, 1.0],
                "R": [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
                "P": [c.fx, 0.0, c.cx, 0.0, 0.0, c.fy, c.cy, 0.0, 0.0, 0.0, 1.0, 0.0]}

    def cast(self, T_WC: np.ndarray):
        """Hit face per pixel (M = no hit) and optical-axis depth (inf where no hit)."""
        R, t = T_WC[:3, :3], T_WC[:3, 3]
        dirs_W = self._dirs_C @ R.T
        self._origins[:] = t
        prim = self._embree.run(self._origins, dirs_W.astype(np.float32))
        m = len(self.scene.faces)
        face = np.where(prim >= 0, prim, m)
        hit = np.flatnonzero(prim >= 0)
        depth = np.full(len(face), np.inf)
        if len(hit):
            f = prim[hit]
            n = self._normal[f]
            den = np.einsum("ij,ij->i", n, dirs_W[hit])
            num = self._offset[f] - n @ t
            with np.errstate(divide="ignore", invalid="ignore"):
                d = num / den
            ok = np.isfinite(d) & (d > 0) & (np.abs(den) > 1e-12)
            depth[hit[ok]] = d[ok]
            face[hit[~ok]] = m
            depth[hit[~ok]] = np.inf
        return face, depth, dirs_W

    def render(self, T_WC: np.ndarray, noise: Optional[bool] = None) -> Dict[str, np.ndarray]:
        """Renders all images from camera pose T_WC (4x4, camera optical frame to world).

        Returns depth (H, W) float32 m (0 = invalid), rgb (H, W, 3) uint8,
        instance (H, W) uint16 (thing object id, 0 = none), class (H, W) uint16
        (class id, 0 = none), true_depth (H, W) float64 (inf = no hit).
        """
        c = self.camera
        face, depth_true, dirs_W = self.cast(T_WC)
        depth = depth_true.copy()
        valid = np.isfinite(depth) & ~self._face_nonreturning[face] & (depth >= c.d_min_m) & (depth <= c.d_max_m)
        if noise if noise is not None else self.noise.enabled:
            nz = self.noise
            sig = sigma_of_depth(depth[valid], nz.sigma_min_m, nz.sigma_max_m, nz.s_per_m)
            depth[valid] += self.rng.standard_normal(len(sig)) * sig
            valid[valid] &= depth[valid] > 0
        depth[~valid] = 0.0
        # Headlight shading: surfaces facing the camera are brightest.
        cosang = np.abs(np.einsum("ij,ij->i", self._normal[np.minimum(face, len(self._normal) - 1)], dirs_W))
        cosang *= self._inv_ray_len
        shade = (0.35 + 0.65 * cosang).astype(np.float32)
        rgb = self._face_color[face] * shade[:, None]
        hw = (c.height, c.width)
        return {"depth": depth.astype(np.float32).reshape(hw),
                "rgb": np.clip(rgb, 0, 255).astype(np.uint8).reshape(hw + (3,)),
                "instance": self._face_instance[face].reshape(hw),
                "class": self._face_class[face].reshape(hw),
                "true_depth": depth_true.reshape(hw),
                "face": face.reshape(hw)}

"""Ray-traced RGB-D camera with ground-truth instance and class images (Embree via embreex).

Depth is the optical-axis distance (z in the camera frame), as RGB-D cameras
report it. Rays are cast with direction (x, y, 1) in the camera frame, so the
hit parameter is the depth itself; it is recomputed in float64 from the hit
triangle's plane, which keeps it exact to well below a millimetre.

One Embree pass per frame gives the hit triangle of every pixel; depth,
colour, instance and class images are then whole-image gathers from per-face
tables. Every table has one extra entry at the end for "no hit", so Embree's
-1 indexes it directly.

The pass goes through Embree 3's stream call (:mod:`embree3`, Debian's
libembree3) when it is installed, else through embreex one ray at a time.
With embreex the images equal those of
:class:`reference_renderer.ReferenceRenderer` (the renderer this one replaced)
pixel for pixel where noise is off; Embree 3 builds another BVH and breaks
ties between triangles that share an edge differently, which changes about
1 pixel in 10^4, all on triangle edges (test/python/test_sim_render_fast.py).
"""

from typing import Dict, Iterable, Optional

import numpy as np

from .classes import ClassTable
from .config import CameraConfig, NoiseConfig
from .scene import Scene


def sigma_of_depth(d, sigma_min, sigma_max, s):
    """Depth noise std (m) at depth d (m): max(sigma_min, min(s d^2, sigma_max)) (paper Table I)."""
    return np.maximum(sigma_min, np.minimum(s * np.square(d), sigma_max))


class _Embreex:
    """First hits through embreex (Embree 2), one ray per call."""
    name = "embreex"

    def __init__(self, scene: Scene, n_rays: int):
        import embreex.rtcore_scene as rtcs
        from embreex.mesh_construction import TriangleMesh
        self._embree = rtcs.EmbreeScene()
        TriangleMesh(self._embree, scene.vertices.astype(np.float32), scene.faces.astype(np.int32))
        self._origins = np.empty((n_rays, 3), np.float32)
        self._dirs = np.empty((n_rays, 3), np.float32)

    def first_hit(self, t_W: np.ndarray, dirs_W: np.ndarray) -> np.ndarray:
        self._origins[:] = t_W
        self._dirs[:] = dirs_W
        return self._embree.run(self._origins, self._dirs)


class _Embree3:
    """First hits through Embree 3's stream call, the whole image at once."""
    name = "embree3"

    def __init__(self, scene: Scene, n_rays: int):
        from .embree3 import TriangleScene
        self._scene = TriangleScene(scene.vertices, scene.faces)
        self.device_config = self._scene.device_config
        self._scene.first_hit(np.zeros(3), np.ones((n_rays, 3)))  # allocates the ray buffers once

    def first_hit(self, t_W: np.ndarray, dirs_W: np.ndarray) -> np.ndarray:
        s = self._scene
        s.org[:] = t_W[:, None]
        s.dir[:] = dirs_W.T
        return s.trace()


def _backend(scene: Scene, n_rays: int, backend: str):
    if backend not in ("auto", "embree3", "embreex"):
        raise ValueError("unknown ray casting backend %r (auto, embree3 or embreex)" % backend)
    if backend != "embreex":
        from .embree3 import EmbreeError, library
        if library() is not None or backend == "embree3":
            try:
                return _Embree3(scene, n_rays)
            except EmbreeError:
                if backend == "embree3":
                    raise
    return _Embreex(scene, n_rays)  # slower, same images (but for ties between coplanar faces)


class Renderer:
    """Renders depth (32FC1 m), colour (rgb8), instance (16UC1) and class (16UC1) images of a scene.

    ``backend``: "auto" (Embree 3 if libembree3 is installed, else embreex), "embree3" or "embreex";
    ``self.backend`` names the one in use."""

    def __init__(self, scene: Scene, camera: CameraConfig, classes: ClassTable,
                 non_returning: Iterable[str] = ("window", "mirror"), noise: Optional[NoiseConfig] = None,
                 backend: str = "auto"):
        camera.validate()
        self.camera = camera
        self.scene = scene
        self.classes = classes
        self.noise = noise if noise is not None else NoiseConfig(enabled=False)
        self.noise.validate()
        self.rng = np.random.default_rng(self.noise.seed)
        m = len(scene.faces)
        self._m = m
        # Per-face tables of m + 1 entries; entry m (= index -1) is "no hit".
        tri = scene.triangles()
        n = np.zeros((m + 1, 3))
        n[:m] = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        norm = np.linalg.norm(n[:m], axis=1)
        ok = norm > 1e-12
        n[:m][ok] /= norm[ok, None]
        self._normal = n  # unit normal (degenerate faces keep their tiny one and are rejected per hit)
        self._offset = np.zeros(m + 1)
        self._offset[:m] = np.einsum("ij,ij->i", n[:m], tri[:, 0])
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
        nr = np.ones(m + 1, bool)
        nr[:m] = scene.non_returning_faces(non_returning)
        self._face_nonreturning = nr
        self._face_color = np.vstack([scene.face_colors, [[0, 0, 0]]]).astype(np.float32)
        u, v = np.meshgrid(np.arange(camera.width, dtype=np.float64), np.arange(camera.height, dtype=np.float64))
        self._dirs_C = np.stack([(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy,
                                 np.ones_like(u)], -1).reshape(-1, 3)
        self._inv_ray_len = 1.0 / np.linalg.norm(self._dirs_C, axis=1)  # rotation-invariant
        npx = camera.width * camera.height
        self._dirs_W = np.empty((npx, 3))  # reused every frame; the returned images are fresh arrays
        self._rays = _backend(scene, npx, backend)
        self.backend = self._rays.name
        #: Embree 3's device configuration (embree3.DEVICE_CONFIG), "" for embreex (its default kernels)
        self.device_config = getattr(self._rays, "device_config", "")

    def camera_info(self) -> Dict:
        """Intrinsics as sensor_msgs/CameraInfo fields (plumb_bob, zero distortion)."""
        c = self.camera
        return {"width": c.width, "height": c.height, "distortion_model": "plumb_bob", "D": [0.0] * 5,
                "K": [c.fx, 0.0, c.cx, 0.0, c.fy, c.cy, 0.0, 0.0, 1.0],
                "R": [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
                "P": [c.fx, 0.0, c.cx, 0.0, 0.0, c.fy, c.cy, 0.0, 0.0, 0.0, 1.0, 0.0]}

    def cast(self, T_WC: np.ndarray):
        """Hit face per pixel (M = no hit), optical-axis depth (inf where no hit), ray directions in
        world (N, 3) and the cosine of each hit's incidence (0 where no hit)."""
        R, t = T_WC[:3, :3], T_WC[:3, 3]
        dirs_W = np.matmul(self._dirs_C, R.T, out=self._dirs_W)
        prim = self._rays.first_hit(t, dirs_W)  # -1 = no hit = the tables' last entry
        n = self._normal.take(prim, axis=0)
        den = np.einsum("ij,ij->i", n, dirs_W)  # ray . normal; the depth is where the ray meets the plane
        num = self._offset.take(prim) - n @ t
        with np.errstate(divide="ignore", invalid="ignore"):
            depth = num / den
        ok = (np.abs(den) > 1e-12) & (depth > 0) & (depth < np.inf)  # misses have den = 0
        face = np.where(ok, prim, self._m)
        depth[~ok] = np.inf
        return face, depth, dirs_W, np.abs(den, out=den)

    def render(self, T_WC: np.ndarray, noise: Optional[bool] = None) -> Dict[str, np.ndarray]:
        """Renders all images from camera pose T_WC (4x4, camera optical frame to world).

        Returns depth (H, W) float32 m (0 = invalid), rgb (H, W, 3) uint8,
        instance (H, W) uint16 (thing object id, 0 = none), class (H, W) uint16
        (class id, 0 = none), true_depth (H, W) float64 (inf = no hit).
        """
        c = self.camera
        face, depth_true, _, absden = self.cast(T_WC)
        valid = ~self._face_nonreturning.take(face)
        valid &= depth_true >= c.d_min_m
        valid &= depth_true <= c.d_max_m
        if noise if noise is not None else self.noise.enabled:
            nz = self.noise
            idx = np.flatnonzero(valid)
            d = depth_true.take(idx)
            d += self.rng.standard_normal(len(idx)) * sigma_of_depth(d, nz.sigma_min_m, nz.sigma_max_m, nz.s_per_m)
            depth = np.zeros(len(face), np.float32)
            depth[idx] = np.where(d > 0, d, 0.0)
        else:
            depth = np.where(valid, depth_true, 0.0).astype(np.float32)
        # Headlight shading: surfaces facing the camera are brightest.
        absden *= self._inv_ray_len
        shade = (0.35 + 0.65 * absden).astype(np.float32)
        np.minimum(shade, 1.0, out=shade)  # |cos| may exceed 1 by rounding; keeps rgb <= 255
        rgb = self._face_color.take(face, axis=0)
        rgb *= shade[:, None]
        hw = (c.height, c.width)
        return {"depth": depth.reshape(hw),
                "rgb": rgb.astype(np.uint8).reshape(hw + (3,)),
                "instance": self._face_instance.take(face).reshape(hw),
                "class": self._face_class.take(face).reshape(hw),
                "true_depth": depth_true.reshape(hw),
                "face": face.reshape(hw)}

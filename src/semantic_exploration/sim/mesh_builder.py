"""Building scenes from parts: unit box, cylinder and sphere meshes placed, coloured and tagged with
an object id, accumulated into one :class:`Scene` (used by the furniture and the house generator)."""

import math
from typing import Dict, List

import numpy as np

from .scene_model import Scene


def _box_mesh():
    v = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)], float)
    # Outward-facing triangles of the unit cube (vertex index = 4x + 2y + z).
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], np.int64)
    return v, f


def _cylinder_mesh(sections=12):
    a = np.linspace(0, 2 * math.pi, sections, endpoint=False)
    ring = np.stack([np.cos(a), np.sin(a)], 1)
    v = np.concatenate([np.c_[ring, np.zeros(sections)], np.c_[ring, np.ones(sections)], [[0, 0, 0], [0, 0, 1]]])
    f = []
    for i in range(sections):
        j = (i + 1) % sections
        f += [[i, j, sections + j], [i, sections + j, sections + i],
              [2 * sections, j, i], [2 * sections + 1, sections + i, sections + j]]
    return v, np.array(f, np.int64)


def _sphere_mesh():
    # Icosahedron subdivided once (80 faces), unit radius.
    t = (1 + 5 ** 0.5) / 2
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
                  [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6],
         [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10],
         [8, 6, 7], [9, 8, 1]]
    verts = list(v / np.linalg.norm(v, axis=1, keepdims=True))
    mid = {}
    out = []

    def m(a, b):
        key = (min(a, b), max(a, b))
        if key not in mid:
            p = verts[a] + verts[b]
            verts.append(p / np.linalg.norm(p))
            mid[key] = len(verts) - 1
        return mid[key]
    for a, b, c in f:
        ab, bc, ca = m(a, b), m(b, c), m(c, a)
        out += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
    return np.array(verts), np.array(out, np.int64)


_BOX = _box_mesh()
_CYL = _cylinder_mesh()
_SPH = _sphere_mesh()


class MeshBuilder:
    """Accumulates parts (each tagged with an object id and a colour) into one scene."""

    def __init__(self, rng: np.random.Generator):
        self.rng = rng
        self.v: List[np.ndarray] = []
        self.f: List[np.ndarray] = []
        self.ids: List[np.ndarray] = []
        self.cols: List[np.ndarray] = []
        self.n = 0
        self.objects: Dict[int, str] = {}
        self.next_id = 1

    def new_object(self, label: str) -> int:
        oid = self.next_id
        self.next_id += 1
        self.objects[oid] = label
        return oid

    def _add(self, verts, faces, oid, color):
        self.v.append(verts)
        self.f.append(faces + self.n)
        self.ids.append(np.full(len(faces), oid, np.int32))
        self.cols.append(np.tile(np.clip(np.asarray(color), 0, 255).astype(np.uint8), (len(faces), 1)))
        self.n += len(verts)

    def box(self, oid, color, center, size, pose=None):
        v = _BOX[0] * np.asarray(size, float) + np.asarray(center, float)
        self._add(apply_pose(pose, v), _BOX[1], oid, color)

    def box_minmax(self, oid, color, lo, hi, pose=None):
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        self.box(oid, color, (lo + hi) / 2, hi - lo, pose)

    def cylinder(self, oid, color, base, radius, height, pose=None):
        v = _CYL[0] * np.array([radius, radius, height]) + np.asarray(base, float)
        self._add(apply_pose(pose, v), _CYL[1], oid, color)

    def sphere(self, oid, color, center, radii, pose=None):
        v = _SPH[0] * np.asarray(radii, float) + np.asarray(center, float)
        self._add(apply_pose(pose, v), _SPH[1], oid, color)

    def scene(self, name, start) -> Scene:
        return Scene(np.concatenate(self.v), np.concatenate(self.f), np.concatenate(self.ids),
                     np.concatenate(self.cols), self.objects, name=name, start=start)


def apply_pose(pose, v):
    """Applies pose (x, y, yaw) about z to local points."""
    if pose is None:
        return v
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    out = v.copy()
    out[:, 0] = c * v[:, 0] - s * v[:, 1] + x
    out[:, 1] = s * v[:, 0] + c * v[:, 1] + y
    return out


def vary_colour(rng, color, amount=18):
    """``color`` with each channel moved by up to +-``amount`` (uniform integers)."""
    return np.asarray(color, float) + rng.integers(-amount, amount + 1, 3)

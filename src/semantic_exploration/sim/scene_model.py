"""The semantic scene model: one labelled triangle soup (see :mod:`scene` for the file formats).

A scene is one triangle soup in the world frame (z up, metres) whose faces
carry an object id; ``objects`` maps each id to a label (mpcat40-style name
such as ``chair``, ``wall``). Faces with id 0 (or an id without a label) are
unlabelled structure. Objects whose label is in the class table are the
"things" the exploration looks for; everything else is background.
"""

from typing import Dict, Iterable, List, Optional, Tuple

import numpy as np


class SceneError(Exception):
    """A scene file is missing, unreadable or inconsistent; the message says which and why."""


class Scene:
    """A labelled triangle mesh.

    Attributes:
        vertices: (N, 3) float64 vertex positions in the world frame, m.
        faces: (M, 3) int64 vertex indices.
        face_object: (M,) int32 object id of each face (0 = unlabelled).
        face_colors: (M, 3) uint8 RGB colour of each face.
        objects: object id -> label (class name).
        non_returning_ids: object ids whose surfaces return no depth
            (besides those whose label is non-returning).
        start: suggested start pose (x, y, z, yaw) in free space, or None.
        name: scene name (file stem).
    """

    def __init__(self, vertices, faces, face_object, face_colors=None,
                 objects: Optional[Dict[int, str]] = None, name: str = "scene",
                 start: Optional[Tuple[float, float, float, float]] = None,
                 non_returning_ids: Iterable[int] = ()):
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
        self.faces = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
        self.face_object = np.ascontiguousarray(face_object, dtype=np.int32).reshape(-1)
        if face_colors is None:
            face_colors = np.full((len(self.faces), 3), 180, np.uint8)
        self.face_colors = np.ascontiguousarray(face_colors, dtype=np.uint8).reshape(-1, 3)
        self.objects: Dict[int, str] = dict(objects or {})
        self.name = name
        self.start = None if start is None else tuple(float(x) for x in start)
        self.non_returning_ids = set(int(i) for i in non_returning_ids)
        self.check()

    # ------------------------------------------------------------------ checks
    def check(self) -> None:
        """Raises SceneError if the arrays are inconsistent or not finite."""
        m = len(self.faces)
        if len(self.vertices) == 0 or m == 0:
            raise SceneError("scene '%s' has no triangles" % self.name)
        if not np.all(np.isfinite(self.vertices)):
            raise SceneError("scene '%s' has non-finite vertex coordinates" % self.name)
        if self.faces.min() < 0 or self.faces.max() >= len(self.vertices):
            raise SceneError("scene '%s': face vertex index out of range [0, %d)"
                             % (self.name, len(self.vertices)))
        if len(self.face_object) != m or len(self.face_colors) != m:
            raise SceneError("scene '%s': %d faces but %d object ids / %d colours"
                             % (self.name, m, len(self.face_object), len(self.face_colors)))
        for k, v in self.objects.items():
            if not isinstance(k, (int, np.integer)) or k <= 0 or k > 65535:
                raise SceneError("scene '%s': object id %r must be an integer in [1, 65535]" % (self.name, k))
            if not isinstance(v, str) or not v:
                raise SceneError("scene '%s': object %d has no class name" % (self.name, k))

    # ------------------------------------------------------------- properties
    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) axis-aligned bounding box [min, max] of all vertices, m."""
        return np.stack([self.vertices.min(0), self.vertices.max(0)])

    def triangles(self) -> np.ndarray:
        """(M, 3, 3) triangle corner positions."""
        return self.vertices[self.faces]

    def label_of_faces(self) -> List[str]:
        return [self.objects.get(int(i), "") for i in self.face_object]

    def non_returning_faces(self, non_returning_labels: Iterable[str]) -> np.ndarray:
        """(M,) bool: faces of objects flagged non-returning or labelled with one of the labels."""
        labels = set(non_returning_labels)
        bad_ids = {i for i, c in self.objects.items() if c in labels} | self.non_returning_ids
        if not bad_ids:
            return np.zeros(len(self.faces), bool)
        return np.isin(self.face_object, np.fromiter(bad_ids, np.int64))

    def thing_ids(self, class_names: Iterable[str]) -> List[int]:
        """Ids of the objects whose label is a known class and that own at least one face."""
        names = set(class_names)
        present = set(np.unique(self.face_object).tolist())
        return sorted(i for i, c in self.objects.items() if c in names and i in present)

    def object_mesh(self, object_ids) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vertices, faces and face colours of the faces of ``object_ids`` (compacted)."""
        sel = np.isin(self.face_object, np.asarray(list(object_ids), np.int64))
        return compact_mesh(self.vertices, self.faces[sel], self.face_colors[sel])

    def background_mesh(self, class_names: Iterable[str]):
        """Vertices, faces and face colours of every face that is not a thing of ``class_names``."""
        things = self.thing_ids(class_names)
        sel = ~np.isin(self.face_object, np.asarray(things, np.int64))
        return compact_mesh(self.vertices, self.faces[sel], self.face_colors[sel])


def compact_mesh(vertices, faces, face_colors):
    """The vertices that ``faces`` use, the faces renumbered onto them, and the face colours."""
    used, inverse = np.unique(faces.reshape(-1), return_inverse=True)
    return vertices[used], inverse.reshape(-1, 3), face_colors


def to_z_up(v: np.ndarray, up_axis: str) -> np.ndarray:
    """Vertices (N, 3) of a mesh whose up axis is ``up_axis`` ("z" or "y") in the z-up world frame."""
    if up_axis == "z":
        return v
    if up_axis == "y":  # glTF/Habitat y-up, -z forward -> z-up: (x, y, z) -> (x, -z, y)
        return np.stack([v[:, 0], -v[:, 2], v[:, 1]], 1)
    raise SceneError("up_axis must be 'z' or 'y' (got %r)" % up_axis)

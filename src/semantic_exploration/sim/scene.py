"""Semantic triangle-mesh scenes: data model, loaders, writers and ground-truth export.

A scene is one triangle soup in the world frame (z up, metres) whose faces
carry an object id; ``objects`` maps each id to a label (mpcat40-style name
such as ``chair``, ``wall``). Faces with id 0 (or an id without a label) are
unlabelled structure. Objects whose label is in the class table are the
"things" the exploration looks for; everything else is background.

Formats:
- Habitat/Matterport3D: ``<scene>_semantic.ply`` (PLY, faces with an integer
  ``object_id``) + ``<scene>.house`` (``ASCII 1.1``; ``C`` records give the
  category of each index, ``O`` records the category of each object).
- Hand-made: any mesh trimesh reads (OBJ/PLY/GLB...) + a JSON label table
  (see :func:`load_mesh_with_labels`).
"""

import json
import os
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
        return _compact(self.vertices, self.faces[sel], self.face_colors[sel])

    def background_mesh(self, class_names: Iterable[str]):
        """Vertices, faces and face colours of every face that is not a thing of ``class_names``."""
        things = self.thing_ids(class_names)
        sel = ~np.isin(self.face_object, np.asarray(things, np.int64))
        return _compact(self.vertices, self.faces[sel], self.face_colors[sel])


def _compact(vertices, faces, face_colors):
    used, inverse = np.unique(faces.reshape(-1), return_inverse=True)
    return vertices[used], inverse.reshape(-1, 3), face_colors


# ---------------------------------------------------------------------------
# PLY (binary little/big endian and ASCII), only what semantic meshes need.
# ---------------------------------------------------------------------------
_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def read_ply(path: str) -> Dict[str, Dict[str, np.ndarray]]:
    """Reads a PLY file into {element: {property: array}}; list properties become (n, k) arrays.

    Only faces with a constant list length (triangles) are supported for list
    properties, which is what Habitat's semantic meshes use; polygon faces are
    fan-triangulated in the ASCII path.
    """
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise SceneError("cannot read PLY '%s': %s" % (path, e.strerror or e))
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise SceneError("'%s' is not a PLY file (no 'ply' magic or no end_header)" % path)
    nl = data.find(b"\n", end)
    header = data[:end].decode("ascii", "replace").splitlines()
    body = data[nl + 1:]
    fmt = None
    elements: List[Tuple[str, int, List[Tuple]]] = []
    for ln, line in enumerate(header, 1):
        tok = line.split()
        if not tok or tok[0] in ("ply", "comment", "obj_info"):
            continue
        if tok[0] == "format":
            fmt = tok[1]
        elif tok[0] == "element":
            if len(tok) != 3 or not tok[2].isdigit():
                raise SceneError("%s: header line %d: malformed element line '%s'" % (path, ln, line))
            elements.append((tok[1], int(tok[2]), []))
        elif tok[0] == "property":
            if not elements:
                raise SceneError("%s: header line %d: property before any element" % (path, ln))
            if tok[1] == "list":
                if len(tok) != 5 or tok[2] not in _PLY_TYPES or tok[3] not in _PLY_TYPES:
                    raise SceneError("%s: header line %d: malformed list property '%s'" % (path, ln, line))
                elements[-1][2].append((tok[4], _PLY_TYPES[tok[2]], _PLY_TYPES[tok[3]]))
            else:
                if len(tok) != 3 or tok[1] not in _PLY_TYPES:
                    raise SceneError("%s: header line %d: malformed property '%s'" % (path, ln, line))
                elements[-1][2].append((tok[2], _PLY_TYPES[tok[1]]))
    if fmt not in ("binary_little_endian", "binary_big_endian", "ascii"):
        raise SceneError("%s: unsupported PLY format %r" % (path, fmt))
    if fmt == "ascii":
        return _read_ply_ascii(path, body, elements)
    endian = "<" if fmt == "binary_little_endian" else ">"
    out: Dict[str, Dict[str, np.ndarray]] = {}
    pos = 0
    for name, count, props in elements:
        lists = [p for p in props if len(p) == 3]
        if not lists:
            dt = np.dtype([(p[0], endian + p[1]) for p in props])
            need = dt.itemsize * count
            if pos + need > len(body):
                raise SceneError("%s: file truncated in element '%s'" % (path, name))
            arr = np.frombuffer(body, dt, count, pos)
            pos += need
        else:
            # Fixed-length lists: read the first count to build a structured dtype, then check all.
            fields = []
            off = pos
            for p in props:
                if len(p) == 3:
                    if off + np.dtype(p[1]).itemsize > len(body):
                        raise SceneError("%s: file truncated in element '%s'" % (path, name))
                    k = int(np.frombuffer(body, endian + p[1], 1, off)[0])
                    fields.append((p[0] + "__n", endian + p[1]))
                    fields.append((p[0], endian + p[2], (k,)))
                    off += np.dtype(p[1]).itemsize + k * np.dtype(p[2]).itemsize
                else:
                    fields.append((p[0], endian + p[1]))
                    off += np.dtype(p[1]).itemsize
            dt = np.dtype(fields)
            need = dt.itemsize * count
            if pos + need > len(body):
                raise SceneError("%s: file truncated in element '%s' (or faces are not all triangles)"
                                 % (path, name))
            arr = np.frombuffer(body, dt, count, pos)
            for p in lists:
                if count and not np.all(arr[p[0] + "__n"] == arr[p[0]].shape[1]):
                    raise SceneError("%s: element '%s' has lists of varying length; only triangle "
                                     "meshes are supported" % (path, name))
            pos += need
        out[name] = {p[0]: np.array(arr[p[0]]) for p in props}
    return out


def _read_ply_ascii(path, body, elements):
    lines = body.decode("ascii", "replace").split("\n")
    li = 0
    out = {}
    for name, count, props in elements:
        cols: Dict[str, list] = {p[0]: [] for p in props}
        for _ in range(count):
            while li < len(lines) and not lines[li].strip():
                li += 1
            if li >= len(lines):
                raise SceneError("%s: file truncated in element '%s'" % (path, name))
            tok = lines[li].split()
            li += 1
            i = 0
            try:
                for p in props:
                    if len(p) == 3:
                        k = int(tok[i])
                        vals = [float(t) for t in tok[i + 1:i + 1 + k]]
                        i += 1 + k
                        cols[p[0]].append(vals)
                    else:
                        cols[p[0]].append(float(tok[i]))
                        i += 1
            except (ValueError, IndexError):
                raise SceneError("%s: malformed ASCII line %d in element '%s'" % (path, li, name))
        res = {}
        for p in props:
            if len(p) == 3:
                lst = cols[p[0]]
                if lst and any(len(v) != 3 for v in lst):
                    raise SceneError("%s: only triangle faces are supported" % path)
                res[p[0]] = np.array(lst, dtype=p[2]).reshape(-1, 3)
            else:
                res[p[0]] = np.array(cols[p[0]], dtype=p[1])
        out[name] = res
    return out


def write_semantic_ply(path: str, scene: Scene, matterport_ids: bool = True) -> None:
    """Writes a binary little-endian PLY with vertex colours and a per-face ``object_id``.

    The layout is byte-for-byte Habitat's semantic PLY. With ``matterport_ids``
    the face ids are Matterport object indices (our id - 1; -1 = no object),
    as in Habitat's files; otherwise our ids are written as they are.

    Vertices are duplicated per face colour so that the vertex colours carry
    the face colours exactly (as Habitat's semantic PLYs do for their id colours).
    """
    v = scene.vertices[scene.faces].reshape(-1, 3).astype("<f4")
    c = np.repeat(scene.face_colors, 3, axis=0)
    vd = np.empty(len(v), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                 ("red", "u1"), ("green", "u1"), ("blue", "u1")])
    vd["x"], vd["y"], vd["z"] = v[:, 0], v[:, 1], v[:, 2]
    vd["red"], vd["green"], vd["blue"] = c[:, 0], c[:, 1], c[:, 2]
    m = len(scene.faces)
    fd = np.empty(m, dtype=[("n", "u1"), ("idx", "<i4", (3,)), ("object_id", "<i4")])
    fd["n"] = 3
    fd["idx"] = np.arange(3 * m, dtype=np.int32).reshape(-1, 3)
    fd["object_id"] = scene.face_object - 1 if matterport_ids else scene.face_object
    header = ("ply\nformat binary_little_endian 1.0\ncomment semantic_exploration scene %s\n"
              "element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\n"
              "element face %d\nproperty list uchar int vertex_indices\nproperty int object_id\n"
              "end_header\n" % (scene.name, len(v), m))
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(vd.tobytes())
        f.write(fd.tobytes())


def write_mesh_ply(path: str, vertices, faces, face_colors=None) -> None:
    """Writes a plain binary PLY mesh (vertex colours from face colours if given)."""
    vertices = np.asarray(vertices, np.float64)
    faces = np.asarray(faces, np.int64)
    if face_colors is not None:
        # Average the colours of the faces around each vertex.
        acc = np.zeros((len(vertices), 3))
        cnt = np.zeros(len(vertices))
        for k in range(3):
            np.add.at(acc, faces[:, k], np.asarray(face_colors, float))
            np.add.at(cnt, faces[:, k], 1)
        col = (acc / np.maximum(cnt, 1)[:, None]).round().astype(np.uint8)
    vd_fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    if face_colors is not None:
        vd_fields += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    vd = np.empty(len(vertices), dtype=vd_fields)
    vd["x"], vd["y"], vd["z"] = vertices[:, 0], vertices[:, 1], vertices[:, 2]
    if face_colors is not None:
        vd["red"], vd["green"], vd["blue"] = col[:, 0], col[:, 1], col[:, 2]
    fd = np.empty(len(faces), dtype=[("n", "u1"), ("idx", "<i4", (3,))])
    fd["n"] = 3
    fd["idx"] = faces
    header = "ply\nformat binary_little_endian 1.0\nelement vertex %d\n" % len(vertices)
    header += "property float x\nproperty float y\nproperty float z\n"
    if face_colors is not None:
        header += "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    header += "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % len(faces)
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(vd.tobytes())
        f.write(fd.tobytes())


# ---------------------------------------------------------------------------
# Matterport .house (ASCII 1.1): C and O records.
# ---------------------------------------------------------------------------
def read_house(path: str) -> Dict[int, str]:
    """Object id -> mpcat40 class name from a Matterport ``.house`` file.

    Matterport object indices start at 0 and the faces of Habitat's semantic
    PLY carry them (-1 = no object); in memory ids are index + 1 so that 0 can
    mean "no object" in the 16-bit instance images.
    """
    try:
        with open(path, "r", encoding="utf-8", errors="replace") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise SceneError("cannot read house file '%s': %s" % (path, e.strerror or e))
    if not lines or lines[0].strip() != "ASCII 1.1":
        raise SceneError("%s: first line must be 'ASCII 1.1' (got %r)" % (path, lines[0] if lines else ""))
    categories: Dict[int, str] = {}
    obj_cat: Dict[int, Tuple[int, int]] = {}
    for ln, line in enumerate(lines[1:], 2):
        tok = line.split()
        if not tok:
            continue
        try:
            if tok[0] == "C":
                # C category_index mapping_index mapping_name mpcat40_index mpcat40_name ...
                if len(tok) < 6:
                    raise ValueError("C record needs >= 6 fields")
                categories[int(tok[1])] = tok[5].replace("#", " ")
            elif tok[0] == "O":
                # O object_index region_index category_index px py pz ...
                if len(tok) < 4:
                    raise ValueError("O record needs >= 4 fields")
                obj_cat[int(tok[1])] = (int(tok[3]), ln)
        except ValueError as e:
            raise SceneError("%s:%d: malformed record '%s' (%s)" % (path, ln, line.strip(), e))
    objects = {}
    for oid, (cat, ln) in obj_cat.items():
        if cat < 0:
            continue  # Matterport marks unassigned objects with category -1
        if cat not in categories:
            raise SceneError("%s:%d: object %d refers to unknown category %d" % (path, ln, oid, cat))
        if oid < 0 or oid >= 65535:
            # Ids above 16 bits do not fit the instance images.
            raise SceneError("%s:%d: object index %d outside [0, 65534]" % (path, ln, oid))
        objects[oid + 1] = categories[cat]  # file indices are 0-based; ours start at 1 (0 = none)
    return objects


def write_house(path: str, scene: Scene) -> None:
    """Writes a minimal Matterport ``.house`` (H, C and O records) for ``scene.objects``."""
    from .classes import MPCAT40_INDEX
    labels = sorted(set(scene.objects.values()))
    cat_index = {c: i for i, c in enumerate(labels)}
    lo, hi = scene.bounds
    lines = ["ASCII 1.1",
             "H %s semantic_exploration 0 0 0 0 0 %d %d 0 0 0 0 0 0 0 0 %s 0 0 0 0 0"
             % (scene.name, len(scene.objects), len(labels), " ".join("%.4f" % x for x in (*lo, *hi)))]
    for c in labels:
        lines.append("C %d %d %s %d %s 0 0 0 0 0" % (cat_index[c], cat_index[c] + 1, c.replace(" ", "#"),
                                                    MPCAT40_INDEX.get(c, 39), c.replace(" ", "#")))
    for oid in sorted(scene.objects):
        sel = scene.face_object == oid
        if np.any(sel):
            v = scene.vertices[scene.faces[sel].reshape(-1)]
            c, r = (v.min(0) + v.max(0)) / 2, (v.max(0) - v.min(0)) / 2
        else:
            c, r = np.zeros(3), np.zeros(3)
        lines.append("O %d 0 %d %.4f %.4f %.4f 1 0 0 0 1 0 %.4f %.4f %.4f 0 0 0 0 0 0 0 0"
                     % (oid - 1, cat_index[scene.objects[oid]], *c, *r))
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


# ---------------------------------------------------------------------------
# Loaders
# ---------------------------------------------------------------------------
def _to_z_up(v: np.ndarray, up_axis: str) -> np.ndarray:
    if up_axis == "z":
        return v
    if up_axis == "y":  # glTF/Habitat y-up, -z forward -> z-up: (x, y, z) -> (x, -z, y)
        return np.stack([v[:, 0], -v[:, 2], v[:, 1]], 1)
    raise SceneError("up_axis must be 'z' or 'y' (got %r)" % up_axis)


def load_habitat(ply_path: str, house_path: Optional[str] = None, up_axis: str = "z") -> Scene:
    """Loads ``<scene>_semantic.ply`` and its ``<scene>.house`` (found next to it if not given)."""
    if house_path is None:
        base = ply_path[:-len("_semantic.ply")] if ply_path.endswith("_semantic.ply") else ply_path[:-4]
        house_path = base + ".house"
    if not os.path.isfile(ply_path):
        raise SceneError("scene mesh '%s' does not exist" % ply_path)
    if not os.path.isfile(house_path):
        raise SceneError("category table '%s' does not exist (needed for %s)" % (house_path, ply_path))
    ply = read_ply(ply_path)
    if "vertex" not in ply or "face" not in ply:
        raise SceneError("%s: needs 'vertex' and 'face' elements" % ply_path)
    vx = ply["vertex"]
    fc = ply["face"]
    if not all(k in vx for k in "xyz"):
        raise SceneError("%s: vertex element lacks x/y/z" % ply_path)
    idx_name = "vertex_indices" if "vertex_indices" in fc else ("vertex_index" if "vertex_index" in fc else None)
    if idx_name is None:
        raise SceneError("%s: face element lacks vertex_indices" % ply_path)
    if "object_id" not in fc:
        raise SceneError("%s: faces carry no 'object_id' property; not a semantic mesh" % ply_path)
    v = np.stack([vx["x"], vx["y"], vx["z"]], 1).astype(np.float64)
    v = _to_z_up(v, up_axis)
    faces = fc[idx_name].astype(np.int64).reshape(-1, 3)
    if len(faces) and (faces.min() < 0 or faces.max() >= len(v)):
        raise SceneError("%s: face vertex index out of range" % ply_path)
    obj = fc["object_id"].astype(np.int64)
    colors = None
    if all(k in vx for k in ("red", "green", "blue")):
        vc = np.stack([vx["red"], vx["green"], vx["blue"]], 1).astype(np.float64)
        colors = vc[faces].mean(1).round().astype(np.uint8)
    objects = read_house(house_path)
    obj = obj + 1  # Matterport/Habitat 0-based object index (-1 = none) -> our 1-based id (0 = none)
    unknown = set(np.unique(obj).tolist()) - set(objects) - {0}
    obj = np.where(np.isin(obj, list(objects)), obj, 0).astype(np.int32)
    name = os.path.basename(ply_path)
    name = name[:-len("_semantic.ply")] if name.endswith("_semantic.ply") else os.path.splitext(name)[0]
    scene = Scene(v, faces, obj, colors, objects, name=name)
    scene.unlabelled_ids = sorted(unknown)  # reported by callers; their faces became background
    return scene


def load_mesh_with_labels(mesh_path: str, labels_path: str, up_axis: str = "z") -> Scene:
    """Loads any mesh trimesh reads plus a JSON label table.

    The JSON is either a flat ``{"<object id>": "<class>", ...}`` (faces take
    their id from a PLY ``object_id`` face property) or::

        {"objects": [{"id": 3, "class": "chair", "geometry": "chair_3",
                      "non_returning": false}, ...],
         "start": [x, y, z, yaw]}

    where ``geometry`` names a node/group of a multi-part file (OBJ groups,
    GLB nodes) whose faces belong to the object; unnamed geometry is
    unlabelled background.
    """
    if not os.path.isfile(mesh_path):
        raise SceneError("scene mesh '%s' does not exist" % mesh_path)
    try:
        with open(labels_path) as f:
            table = json.load(f)
    except OSError as e:
        raise SceneError("cannot read label table '%s': %s" % (labels_path, e.strerror or e))
    except ValueError as e:
        raise SceneError("label table '%s' is not valid JSON: %s" % (labels_path, e))
    entries, start = _parse_label_table(labels_path, table)
    objects = {e["id"]: e["class"] for e in entries}
    non_ret = [e["id"] for e in entries if e.get("non_returning")]
    by_geom = {e["geometry"]: e["id"] for e in entries if e.get("geometry")}
    name = os.path.splitext(os.path.basename(mesh_path))[0]

    if mesh_path.lower().endswith(".ply") and not by_geom:
        ply = read_ply(mesh_path)
        fc, vx = ply.get("face", {}), ply.get("vertex", {})
        if "object_id" in fc:
            if not all(k in vx for k in ("x", "y", "z")):
                raise SceneError("%s: vertex element lacks x/y/z" % mesh_path)
            if "vertex_indices" not in fc and "vertex_index" not in fc:
                raise SceneError("%s: face element lacks vertex_indices" % mesh_path)
            v = _to_z_up(np.stack([vx["x"], vx["y"], vx["z"]], 1).astype(np.float64), up_axis)
            faces = fc.get("vertex_indices", fc.get("vertex_index")).astype(np.int64).reshape(-1, 3)
            obj = fc["object_id"].astype(np.int64)
            obj = np.where(np.isin(obj, list(objects)), obj, 0).astype(np.int32)
            colors = None
            if all(k in vx for k in ("red", "green", "blue")):
                vc = np.stack([vx["red"], vx["green"], vx["blue"]], 1).astype(np.float64)
                colors = vc[faces].mean(1).round().astype(np.uint8)
            return Scene(v, faces, obj, colors, objects, name=name, start=start, non_returning_ids=non_ret)

    vs, fs, ids, cols = [], [], [], []
    off = 0
    unknown_geom = set(by_geom)
    for names, v, f, fcol in _read_parts(mesh_path):
        oid = 0
        for n in names:
            if n in by_geom:
                oid = by_geom[n]
            unknown_geom.discard(n)
        vs.append(v)
        fs.append(f + off)
        ids.append(np.full(len(f), oid, np.int32))
        cols.append(fcol)
        off += len(v)
    if not vs:
        raise SceneError("'%s' contains no triangles" % mesh_path)
    if unknown_geom:
        raise SceneError("label table '%s' names geometry not in '%s': %s"
                         % (labels_path, mesh_path, ", ".join(sorted(unknown_geom))))
    v = _to_z_up(np.concatenate(vs), up_axis)
    return Scene(v, np.concatenate(fs), np.concatenate(ids), np.concatenate(cols), objects,
                 name=name, start=start, non_returning_ids=non_ret)


def _read_parts(mesh_path):
    """Yields (names, vertices, faces, face colours) per named part of a mesh file.

    OBJ is read here (trimesh merges OBJ objects that share a material);
    everything else goes through trimesh's scene graph (node and geometry names).
    """
    if mesh_path.lower().endswith(".obj"):
        yield from _read_obj_parts(mesh_path)
        return
    import trimesh
    try:
        loaded = trimesh.load(mesh_path, force="scene")
    except Exception as e:  # trimesh raises many types for bad files
        raise SceneError("trimesh cannot read '%s': %s" % (mesh_path, e))
    for node in loaded.graph.nodes_geometry:
        transform, geom_name = loaded.graph[node]
        geom = loaded.geometry[geom_name]
        if not hasattr(geom, "faces") or len(geom.faces) == 0:
            continue
        v = trimesh.transformations.transform_points(geom.vertices, transform)
        try:
            fcol = np.asarray(geom.visual.to_color().face_colors)[:, :3].astype(np.uint8)
        except Exception:  # textured or odd visuals: fall back to grey
            fcol = np.full((len(geom.faces), 3), 180, np.uint8)
        yield (node, geom_name), v, np.asarray(geom.faces, np.int64), fcol


def _read_obj_parts(path):
    try:
        with open(path, "r", errors="replace") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise SceneError("cannot read '%s': %s" % (path, e.strerror or e))
    verts = []
    parts = []  # (name, [faces])
    name = ""
    cur = None
    for ln, line in enumerate(lines, 1):
        tok = line.split()
        if not tok:
            continue
        try:
            if tok[0] == "v":
                verts.append([float(t) for t in tok[1:4]])
            elif tok[0] in ("o", "g"):
                name = " ".join(tok[1:])
                cur = None
            elif tok[0] == "f":
                idx = []
                for t in tok[1:]:
                    i = int(t.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(verts) + i)
                if cur is None:
                    cur = (name, [])
                    parts.append(cur)
                for k in range(1, len(idx) - 1):  # fan-triangulate polygons
                    cur[1].append([idx[0], idx[k], idx[k + 1]])
        except (ValueError, IndexError):
            raise SceneError("%s:%d: malformed OBJ line '%s'" % (path, ln, line.strip()))
    v = np.array(verts, np.float64).reshape(-1, 3)
    for name, faces in parts:
        f = np.array(faces, np.int64).reshape(-1, 3)
        if len(f) and (f.min() < 0 or f.max() >= len(v)):
            raise SceneError("%s: face index out of range in part '%s'" % (path, name))
        used, inv = np.unique(f.reshape(-1), return_inverse=True)
        yield (name,), v[used], inv.reshape(-1, 3), np.full((len(f), 3), 180, np.uint8)


def _parse_label_table(path, table):
    start = None
    if isinstance(table, dict) and "objects" in table:
        raw = table["objects"]
        start = table.get("start")
        if start is not None and (not isinstance(start, list) or len(start) != 4
                                  or not all(isinstance(x, (int, float)) and np.isfinite(x) for x in start)):
            raise SceneError("%s: 'start' must be [x, y, z, yaw] of finite numbers" % path)
        if not isinstance(raw, list):
            raise SceneError("%s: 'objects' must be a list of {id, class} entries" % path)
        entries = []
        for k, e in enumerate(raw):
            if not isinstance(e, dict) or "id" not in e or "class" not in e:
                raise SceneError("%s: objects[%d] must be an object with 'id' and 'class'" % (path, k))
            entries.append(e)
    elif isinstance(table, dict):
        entries = [{"id": k, "class": v} for k, v in table.items()]
    else:
        raise SceneError("%s: label table must be a JSON object" % path)
    seen = set()
    for e in entries:
        try:
            oid = int(e["id"])
        except (TypeError, ValueError):
            raise SceneError("%s: object id %r is not an integer" % (path, e["id"]))
        if oid != float(e["id"]) or oid <= 0 or oid > 65535:
            raise SceneError("%s: object id %r must be an integer in [1, 65535]" % (path, e["id"]))
        if oid in seen:
            raise SceneError("%s: object id %d listed twice" % (path, oid))
        seen.add(oid)
        if not isinstance(e["class"], str) or not e["class"].strip():
            raise SceneError("%s: object %d needs a non-empty class name" % (path, oid))
        e["id"] = oid
    return entries, start


def load_scene(path: str, labels: Optional[str] = None, up_axis: str = "z") -> Scene:
    """Loads a scene file by its form: ``*_semantic.ply`` (+ .house), else mesh + JSON labels.

    ``labels`` is the .house or .json table; if omitted, ``<stem>.house`` and
    then ``<stem>.json`` next to the mesh are tried.
    """
    if not path:
        raise SceneError("no scene file given")
    if not os.path.isfile(path):
        raise SceneError("scene file '%s' does not exist" % path)
    base = path[:-len("_semantic.ply")] if path.endswith("_semantic.ply") else os.path.splitext(path)[0]
    if labels is None:
        for cand in (base + ".house", base + ".json"):
            if os.path.isfile(cand):
                labels = cand
                break
        else:
            raise SceneError("no label table for '%s' (looked for %s.house and %s.json)" % (path, base, base))
    if labels.endswith(".house"):
        scene = load_habitat(path, labels, up_axis)
    else:
        scene = load_mesh_with_labels(path, labels, up_axis)
    meta = base + ".start.json"
    if scene.start is None and os.path.isfile(meta):
        try:
            with open(meta) as f:
                st = json.load(f)
            scene.start = tuple(float(x) for x in st["start"])
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise SceneError("%s: malformed start pose file: %s" % (meta, e))
    return scene


def save_habitat(scene: Scene, directory: str) -> str:
    """Writes ``<name>_semantic.ply``, ``<name>.house`` (and the start pose) into ``directory``.

    Returns the PLY path.
    """
    os.makedirs(directory, exist_ok=True)
    ply = os.path.join(directory, scene.name + "_semantic.ply")
    write_semantic_ply(ply, scene)
    write_house(os.path.join(directory, scene.name + ".house"), scene)
    if scene.start is not None:
        with open(os.path.join(directory, scene.name + ".start.json"), "w") as f:
            json.dump({"start": list(scene.start)}, f)
    return ply


# ---------------------------------------------------------------------------
# Ground-truth export
# ---------------------------------------------------------------------------
def free_space_grid(scene: Scene, resolution_m: float = 0.1, start=None, margin_m: float = 0.0):
    """Explorable free space: voxels not touched by any surface and 6-connected to the start.

    Surfaces are rasterised by dense sampling (spacing resolution/4), so thin
    walls close the volume. Returns (free bool grid (nx, ny, nz), origin (3,)
    lower corner of voxel (0,0,0), resolution).
    """
    from scipy import ndimage
    lo, hi = scene.bounds
    lo = lo - margin_m
    hi = hi + margin_m
    shape = np.maximum(np.ceil((hi - lo) / resolution_m).astype(int), 1)
    occ = np.zeros(shape, bool)
    step = resolution_m / 4.0
    tri = scene.triangles()
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    lab = np.linalg.norm(b - a, axis=1)
    lac = np.linalg.norm(c - a, axis=1)
    n = np.maximum(np.ceil(np.maximum(lab, lac) / step).astype(int), 1)
    for k in np.unique(n):
        sel = n == k
        # Barycentric lattice with k steps along each edge.
        i, j = np.meshgrid(np.arange(k + 1), np.arange(k + 1), indexing="ij")
        keep = i + j <= k
        u = (i[keep] / k)[None, :, None]
        w = (j[keep] / k)[None, :, None]
        pts = a[sel][:, None] + u * (b[sel] - a[sel])[:, None] + w * (c[sel] - a[sel])[:, None]
        idx = np.floor((pts.reshape(-1, 3) - lo) / resolution_m).astype(int)
        idx = np.clip(idx, 0, shape - 1)
        occ[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    free = ~occ
    if start is None:
        start = scene.start
    if start is None:
        return free, lo, resolution_m
    s = np.floor((np.asarray(start[:3]) - lo) / resolution_m).astype(int)
    if np.any(s < 0) or np.any(s >= shape) or not free[tuple(s)]:
        raise SceneError("start position %s is not in free space" % (list(start[:3]),))
    labels, _ = ndimage.label(free)
    return labels == labels[tuple(s)], lo, resolution_m


def export_ground_truth(scene: Scene, directory: str, class_names: Iterable[str],
                        free_resolution_m: float = 0.1, start=None) -> Dict:
    """Writes per-object PLYs, background.ply, objects.json and free_space.{json,npz}.

    The explorable free space is the free volume connected to ``start`` (x, y,
    z[, yaw]; default the scene's start pose); without a start it is skipped.
    Returns the objects.json content.
    """
    class_names = list(class_names)
    start = scene.start if start is None else tuple(float(v) for v in start)
    os.makedirs(os.path.join(directory, "objects"), exist_ok=True)
    objs = []
    order = np.argsort(scene.face_object, kind="stable")  # faces grouped by object, once
    sorted_ids = scene.face_object[order]
    for oid in scene.thing_ids(class_names):
        sel = order[np.searchsorted(sorted_ids, oid, "left"):np.searchsorted(sorted_ids, oid, "right")]
        v, f, c = _compact(scene.vertices, scene.faces[sel], scene.face_colors[sel])
        cls = scene.objects[oid]
        fn = "objects/%d_%s.ply" % (oid, cls)
        write_mesh_ply(os.path.join(directory, fn), v, f, c)
        objs.append({"id": oid, "class": cls, "class_id": class_names.index(cls) + 1,
                     "bbox_min": v.min(0).round(4).tolist(), "bbox_max": v.max(0).round(4).tolist(),
                     "centroid": v.mean(0).round(4).tolist(), "mesh": fn, "faces": int(len(f))})
    v, f, c = scene.background_mesh(class_names)
    write_mesh_ply(os.path.join(directory, "background.ply"), v, f, c)
    lo, hi = scene.bounds
    doc = {"scene": scene.name, "bounds_min": lo.round(4).tolist(), "bounds_max": hi.round(4).tolist(),
           "start": list(start) if start else None, "class_names": class_names,
           "background_mesh": "background.ply", "objects": objs}
    with open(os.path.join(directory, "objects.json"), "w") as fh:
        json.dump(doc, fh, indent=1)
    if start is not None:
        free, origin, res = free_space_grid(scene, free_resolution_m, start)
        np.savez_compressed(os.path.join(directory, "free_space.npz"), free=free, origin=origin,
                            resolution=res)
        with open(os.path.join(directory, "free_space.json"), "w") as fh:
            json.dump({"explorable_free_volume_m3": float(free.sum() * res ** 3), "resolution_m": res,
                       "origin": origin.round(4).tolist(), "shape": list(free.shape),
                       "grid": "free_space.npz"}, fh, indent=1)
    return doc

"""PLY reading (binary little/big endian and ASCII) and writing, only what semantic meshes need."""

from typing import Dict, List, Tuple

import numpy as np

from .scene_model import Scene, SceneError

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

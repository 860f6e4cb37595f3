"""Hand-made scenes: any mesh trimesh reads (OBJ/PLY/GLB...) plus a JSON label table."""

import json
import os

import numpy as np

from .ply import read_ply
from .scene_model import Scene, SceneError, to_z_up


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
            v = to_z_up(np.stack([vx["x"], vx["y"], vx["z"]], 1).astype(np.float64), up_axis)
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
    v = to_z_up(np.concatenate(vs), up_axis)
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

"""Habitat/Matterport3D scenes: ``<scene>_semantic.ply`` (faces with an integer ``object_id``)
plus ``<scene>.house`` (``ASCII 1.1``; ``C`` records give the category of each index, ``O``
records the category of each object)."""

import json
import os
from typing import Dict, Optional, Tuple

import numpy as np

from .ply import read_ply, write_semantic_ply
from .scene_model import Scene, SceneError, to_z_up


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
    v = to_z_up(v, up_axis)
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

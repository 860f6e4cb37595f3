"""Ground-truth export of a scene: per-object meshes, the background mesh, objects.json and the
explorable free space."""

import json
import os
from typing import Dict, Iterable

import numpy as np

from .free_space import free_space_grid
from .ply import write_mesh_ply
from .scene_model import Scene, compact_mesh


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
        v, f, c = compact_mesh(scene.vertices, scene.faces[sel], scene.face_colors[sel])
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

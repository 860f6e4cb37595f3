"""Semantic triangle-mesh scenes: the public face of the modules that hold them.

- :mod:`scene_model`: the data model (:class:`Scene`, :class:`SceneError`).
- :mod:`ply`: PLY reading and writing.
- :mod:`habitat`: Habitat/Matterport3D ``<scene>_semantic.ply`` (PLY, faces
  with an integer ``object_id``) + ``<scene>.house`` (``ASCII 1.1``; ``C``
  records give the category of each index, ``O`` records the category of
  each object).
- :mod:`labelled_mesh`: any mesh trimesh reads (OBJ/PLY/GLB...) + a JSON
  label table (see :func:`load_mesh_with_labels`).
- :mod:`free_space`: the explorable free space, rasterised.
- :mod:`ground_truth`: per-object meshes, background and free space for scoring.

Everything is imported from here as before (``from semantic_exploration.sim.scene import ...``);
:func:`load_scene` picks the loader by the file's form.
"""

import json
import os
from typing import Optional

from .free_space import free_space_grid
from .ground_truth import export_ground_truth
from .habitat import load_habitat, read_house, save_habitat, write_house
from .labelled_mesh import load_mesh_with_labels
from .ply import read_ply, write_mesh_ply, write_semantic_ply
from .scene_model import Scene, SceneError, compact_mesh, to_z_up

__all__ = ["Scene", "SceneError", "compact_mesh", "to_z_up", "read_ply", "write_semantic_ply", "write_mesh_ply",
           "read_house", "write_house", "load_habitat", "save_habitat", "load_mesh_with_labels",
           "load_scene", "free_space_grid", "export_ground_truth"]


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

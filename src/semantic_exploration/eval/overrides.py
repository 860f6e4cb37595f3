"""Parameter override files of a mission, combined section by section.

rosparam loads a YAML file as one mapping, so two `planner:` sections in one
file leave only the last; run_mission.py's layers (the scene's bounds and
classes, its own settings, --extra-overrides, config/deterministic.yaml) are
merged here instead, each later layer's settings winning key by key.
"""
import copy
from typing import Dict, Iterable

import yaml


def merge(into: Dict, top: Dict) -> Dict:
    """`top`'s settings over `into`'s, recursing into sections both have; returns `into`.
    What it takes from `top` is copied: a later merge into `into` leaves `top` as it was."""
    for k, v in top.items():
        if isinstance(v, dict) and isinstance(into.get(k), dict):
            merge(into[k], v)
        else:
            into[k] = copy.deepcopy(v)
    return into


def load(path: str) -> Dict:
    """A YAML override file as a mapping ({} when empty); anything else is refused by name."""
    with open(path) as f:
        doc = yaml.safe_load(f)
    if doc is None:
        return {}
    if not isinstance(doc, dict):
        raise ValueError("%s: an override file must hold a YAML mapping, not %s" % (path, type(doc).__name__))
    return doc


def write_merged(path: str, layers: Iterable[Dict], header: str) -> Dict:
    """`path`'s own settings with `layers` merged over them in order, written back to `path`."""
    doc = load(path)
    for layer in layers:
        merge(doc, layer)
    with open(path, "w") as f:
        f.write("# %s\n" % header)
        yaml.safe_dump(doc, f)
    return doc

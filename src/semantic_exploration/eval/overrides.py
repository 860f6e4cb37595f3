"""Parameter override files of a mission, combined section by section.

rosparam loads a YAML file as one mapping, so two `planner:` sections in one
file leave only the last; run_mission.py's layers (the scene's bounds and
classes, its own settings, --extra-overrides, config/deterministic.yaml) are
merged here instead, each later layer's settings winning key by key.
"""
import copy
from typing import Dict, Iterable

import yaml

#: run_mission.py's own settings for the C++ nodes, under --extra-overrides. It stops the run at
#: --sim-limit-s itself, so the planner's own limit (config/semantic.yaml: 600 s) must not end a
#: longer run first; --extra-overrides may set one again.
MISSION_OVERRIDES = {"planner": {"time_limit_s": 0.0}}


class _Tagged(str):
    """A value under one of rosparam's angle tags (`!degrees 90`, `!radians pi/2`), kept as written:
    rosparam evaluates it when it loads the merged file."""
    tag = ""


class _Loader(yaml.SafeLoader):
    """safe_load that keeps rosparam's angle tags."""


class _Dumper(yaml.SafeDumper):
    """safe_dump that writes the angle tags back."""


def _keep(tag):
    def construct(loader, node):
        value = _Tagged(loader.construct_scalar(node))
        value.tag = tag
        return value
    return construct


for _tag in ("!degrees", "!radians"):
    _Loader.add_constructor(_tag, _keep(_tag))
_Dumper.add_representer(_Tagged, lambda dumper, value: dumper.represent_scalar(value.tag, str(value)))


def merge(into: Dict, top: Dict) -> Dict:
    """`top`'s settings over `into`'s, recursing into sections both have; returns `into`.
    What it takes from `top` is copied: a later merge into `into` leaves `top` as it was.
    A key left empty in `top` (YAML null, e.g. a section whose lines are all commented out)
    sets nothing: rosparam has no null value to set."""
    for k, v in top.items():
        if v is None:
            continue
        if isinstance(v, dict) and isinstance(into.get(k), dict):
            merge(into[k], v)
        else:
            into[k] = copy.deepcopy(v)
    return into


def load(path: str) -> Dict:
    """A YAML override file as a mapping ({} when empty); anything else is refused by name."""
    with open(path) as f:
        doc = yaml.load(f, Loader=_Loader)
    if doc is None:
        return {}
    if not isinstance(doc, dict):
        raise ValueError("%s: an override file must hold a YAML mapping, not %s" % (path, type(doc).__name__))
    return doc


def unreadable(path: str) -> str:
    """Why `path` cannot serve as an override file ('' if it can), for a start-up error."""
    try:
        load(path)
    except (OSError, ValueError, yaml.YAMLError) as e:
        return str(e)
    return ""


def write(path: str, doc: Dict, header: str = "") -> None:
    """`doc` as an override file (a `# header` line first if given), angle tags as they were read."""
    with open(path, "w") as f:
        if header:
            f.write("# %s\n" % header)
        yaml.dump(doc, f, Dumper=_Dumper)


def write_merged(path: str, layers: Iterable[Dict], header: str) -> Dict:
    """`path`'s own settings with `layers` merged over them in order, written back to `path`."""
    doc = load(path)
    for layer in layers:
        merge(doc, layer)
    write(path, doc, header)
    return doc


def combine_mission(path: str, extra_path: str = "") -> Dict:
    """run_mission.py: `path` (the scene's bounds and classes) with MISSION_OVERRIDES and then
    --extra-overrides merged over it section by section (text appended after it would replace a
    whole section)."""
    layers = [MISSION_OVERRIDES] + ([load(extra_path)] if extra_path else [])
    return write_merged(path, layers, "written by run_mission.py: the scene's bounds and classes, its planner "
                        "settings, then --extra-overrides")

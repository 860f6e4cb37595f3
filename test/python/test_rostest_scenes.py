"""The rostests that fly a generated house pass its size and seed to sim.launch
(directly, or through test/rostest/exploration_objects.launch) and its map bounds
in an overrides file: the same house in two places. Each overrides file that sets
bounds must hold that house's box plus run_mission.py's margin, as a mission of
the same house would be bounded: a size changed without its bounds would map part
of the house outside the bounds, or a large empty margin."""
import glob
import inspect
import os
import sys
import xml.etree.ElementTree as ET

import pytest
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ROSTEST = os.path.join(ROOT, "test", "rostest")
FIND = "$(find semantic_exploration)/"
SHARED = "test/rostest/exploration_objects.launch"
SIM = "launch/sim.launch"


def _margin_m():
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    try:
        import run_mission
    finally:
        sys.path.pop(0)
    return inspect.signature(run_mission.write_overrides).parameters["margin_m"].default


def _args(element):
    return {a.get("name"): a.get("value", a.get("default")) for a in element.findall("arg")}


def _path(value):
    assert value.startswith(FIND), value  # a path this test can resolve in the repository
    return os.path.join(ROOT, value[len(FIND):])


def _flights():
    """(test file, size, seed, overrides path) of each include of the shared launch or sim.launch."""
    shared = _args(ET.parse(os.path.join(ROOT, SHARED)).getroot())
    sim = _args(ET.parse(os.path.join(ROOT, SIM)).getroot())
    out = []
    for path in sorted(glob.glob(os.path.join(ROSTEST, "*.test"))):
        for inc in ET.parse(path).getroot().iter("include"):
            target = inc.get("file", "")
            if not target.endswith((SHARED, SIM)):
                continue
            assert inc.get("pass_all_args") is None, "%s: args passed by pass_all_args are not read here" % path
            args = dict(shared if target.endswith(SHARED) else sim, **_args(inc))
            if not args.get("overrides"):
                continue
            overrides = _path(args["overrides"])
            with open(overrides) as f:
                if "bounds" not in (yaml.safe_load(f) or {}):
                    continue  # the launch's default bounds, no house of its own
            out.append((os.path.basename(path), args["size"], int(args["seed"]), overrides))
    return out


def test_every_house_flying_rostest_is_checked():
    names = [f[0] for f in _flights()]
    assert {"exploration_objects.test", "exploration_objects_classic.test",
            "exploration_objects_setpoints.test", "restart.test"} <= set(names), names


@pytest.mark.parametrize("name,size,seed,overrides", _flights())
def test_bounds_are_the_house_plus_the_mission_margin(name, size, seed, overrides):
    from semantic_exploration.sim.generator import generate
    margin = _margin_m()
    lo, hi = generate(seed=seed, size_m=yaml.safe_load(size)).bounds
    with open(overrides) as f:
        bounds = yaml.safe_load(f)["bounds"]
    assert bounds["min_m"] == pytest.approx([v - margin for v in lo], abs=1e-3), (name, overrides)
    assert bounds["max_m"] == pytest.approx([v + margin for v in hi], abs=1e-3), (name, overrides)

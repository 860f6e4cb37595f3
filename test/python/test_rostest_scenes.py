"""The rostests that fly a generated house (test/rostest/exploration_objects.launch
and the .test files that include it) pass the house's size and seed to sim.launch
and its map bounds in an overrides file, in two places. Each overrides file's
bounds must be that house's box plus run_mission.py's margin, as a mission of the
same house would be bounded: a size changed without its bounds would map part of
the house outside the bounds, or a large empty margin."""
import glob
import os
import xml.etree.ElementTree as ET

import pytest
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ROSTEST = os.path.join(ROOT, "test", "rostest")
SHARED = "exploration_objects.launch"
MARGIN_M = 0.5  # scripts/run_mission.py write_overrides()


def _args(element):
    return {a.get("name"): a.get("value", a.get("default")) for a in element.findall("arg")}


def _file(value):
    return os.path.join(ROSTEST, os.path.basename(value))  # $(find semantic_exploration)/test/rostest/NAME


def _flights():
    defaults = _args(ET.parse(os.path.join(ROSTEST, SHARED)).getroot())
    out = []
    for path in sorted(glob.glob(os.path.join(ROSTEST, "*.test"))):
        for inc in ET.parse(path).getroot().iter("include"):
            if inc.get("file", "").endswith("/" + SHARED):
                args = dict(defaults, **_args(inc))
                out.append((os.path.basename(path), args["size"], int(args["seed"]), _file(args["overrides"])))
    return out


def test_the_shared_launch_is_used():
    names = [f[0] for f in _flights()]
    assert {"exploration_objects.test", "exploration_objects_classic.test",
            "exploration_objects_setpoints.test"} <= set(names), names


@pytest.mark.parametrize("name,size,seed,overrides", _flights())
def test_bounds_are_the_house_plus_the_mission_margin(name, size, seed, overrides):
    from semantic_exploration.sim.generator import generate
    lo, hi = generate(seed=seed, size_m=yaml.safe_load(size)).bounds
    with open(overrides) as f:
        bounds = yaml.safe_load(f)["bounds"]
    assert bounds["min_m"] == pytest.approx([v - MARGIN_M for v in lo], abs=1e-3), (name, overrides)
    assert bounds["max_m"] == pytest.approx([v + MARGIN_M for v in hi], abs=1e-3), (name, overrides)

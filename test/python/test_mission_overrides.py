"""run_mission.py's overrides for the C++ nodes: the scene's bounds and classes,
the mission's own planner settings and --extra-overrides, merged section by
section (eval/overrides.py), so that a `planner:` section in --extra-overrides
adds to the mission's instead of replacing it."""
import math

import pytest

import run_mission  # noqa: E402
from semantic_exploration.eval import overrides  # noqa: E402

GT = {"bounds_min": [0.0, 0.0, 0.0], "bounds_max": [8.0, 6.0, 3.0]}


def _written(tmp_path, extra_text=None):
    path = tmp_path / "overrides.yaml"
    run_mission.write_overrides(str(path), GT, ["chair"])
    extra = ""
    if extra_text is not None:
        extra = tmp_path / "extra.yaml"
        extra.write_text(extra_text)
    run_mission.combine_overrides(str(path), str(extra))
    return overrides.load(str(path))  # the angle tags as written, which plain safe_load refuses


def test_the_mission_owns_the_time_limit(tmp_path):
    # 600 s from config/semantic.yaml would end a --sim-limit-s 2700 run at 600 s.
    doc = _written(tmp_path)
    assert doc["planner"] == {"time_limit_s": 0.0}
    assert doc["bounds"] == {"min_m": [-0.5, -0.5, -0.5], "max_m": [8.5, 6.5, 3.5]}
    assert doc["classes"] == {"of_interest": ["chair"]}


def test_extra_overrides_add_to_a_section_and_win_key_by_key(tmp_path):
    doc = _written(tmp_path, "planner:\n  seed: 4\nbounds:\n  max_m: [9, 7, 3]\nobject_map:\n  save_tsdf: true\n")
    assert doc["planner"] == {"time_limit_s": 0.0, "seed": 4}  # appended text would have dropped the limit
    assert doc["bounds"] == {"min_m": [-0.5, -0.5, -0.5], "max_m": [9, 7, 3]}
    assert doc["object_map"] == {"save_tsdf": True}
    assert _written(tmp_path, "planner:\n  time_limit_s: 1500.0\n")["planner"] == {"time_limit_s": 1500.0}


def test_an_empty_file_or_section_changes_nothing(tmp_path):
    assert _written(tmp_path, "")["planner"] == {"time_limit_s": 0.0}
    # A section whose lines are all commented out is YAML null: it must not drop the time limit.
    assert _written(tmp_path, "planner:\n  # seed: 3\n")["planner"] == {"time_limit_s": 0.0}



def test_rosparam_angle_tags_reach_rosparam_as_written(tmp_path):
    # rosparam evaluates !radians expressions in pi and strips rad()/deg(); the merged file keeps the
    # tags for it instead of guessing.
    doc = _written(tmp_path, "mav:\n  yaw_rad: !degrees 90\n  pitch_rad: !radians pi/2\n  roll_rad: !radians rad(1)\n")
    assert {k: (v.tag, str(v)) for k, v in doc["mav"].items()} == {
        "yaw_rad": ("!degrees", "90"), "pitch_rad": ("!radians", "pi/2"), "roll_rad": ("!radians", "rad(1)")}
    rosparam = pytest.importorskip("rosparam")
    loaded = rosparam.load_file(str(tmp_path / "overrides.yaml"))[0][0]
    assert loaded["mav"] == {"yaw_rad": pytest.approx(math.pi / 2), "pitch_rad": pytest.approx(math.pi / 2),
                             "roll_rad": pytest.approx(1.0)}
    assert loaded["planner"] == {"time_limit_s": 0.0}


def test_a_bad_extra_file_is_refused_at_start_naming_the_option(tmp_path, capsys):
    bad = tmp_path / "list.yaml"
    bad.write_text("- planner\n")
    assert overrides.unreadable(str(bad)) == "%s: an override file must hold a YAML mapping, not list" % bad
    assert overrides.unreadable(str(tmp_path / "none.yaml")).startswith("[Errno 2] No such file or directory")
    broken = tmp_path / "broken.yaml"
    broken.write_text("planner: [1,\n")
    assert "while parsing" in overrides.unreadable(str(broken))
    for argv, why in ((["--extra-overrides", str(bad)], "--extra-overrides: %s: an override file" % bad),
                      (["--wall-limit-s", "0"], "--wall-limit-s must be > 0 s"),
                      (["--sim-limit-s", "-1"], "--sim-limit-s must be > 0 s")):
        with pytest.raises(SystemExit):
            run_mission.parse_args(argv)
        assert why in capsys.readouterr().err


def test_merge_recurses_into_sections_both_have_and_replaces_the_rest():
    into = {"a": {"b": 1, "c": {"d": 2}}, "e": [1, 2], "f": {"g": 1}}
    top = {"a": {"c": {"h": 3}}, "e": [3], "f": 5, "i": {"j": 1}}
    assert overrides.merge(into, top) == {"a": {"b": 1, "c": {"d": 2, "h": 3}}, "e": [3], "f": 5, "i": {"j": 1}}


def test_merge_copies_what_it_takes():
    top = {"planner": {"time_limit_s": 0.0}}
    into = overrides.merge({}, top)
    overrides.merge(into, {"planner": {"seed": 4}})
    assert top == {"planner": {"time_limit_s": 0.0}}

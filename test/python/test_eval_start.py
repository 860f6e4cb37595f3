"""A loaded scene without a start pose is scored (run_mission.py): the start
the simulator uses (the centre of the scene's box at 1.2 m, or --start)
goes into the exported ground truth and onto sim.launch's command line, so
the evaluation knows the observable surface."""
import json
import os

import pytest

trimesh = pytest.importorskip("trimesh")
pytest.importorskip("embreex")

from semantic_exploration.eval import final  # noqa: E402
from semantic_exploration.sim.scene import load_scene, save_habitat  # noqa: E402
from semantic_exploration.sim.simulator import start_pose_of  # noqa: E402

import run_mission  # noqa: E402
from test_eval_background import _scene  # noqa: E402

# The room of test_eval_background spans [-0.05, 3.05] x [-0.05, 2.55] x [-0.05, 2.25] m:
# its centre at 1.2 m height (the top is more than 0.3 m above), yaw 0.
CENTRE_START = (1.5, 1.25, 1.2, 0.0)


@pytest.fixture()
def habitat_scene(tmp_path):
    sc = _scene()
    sc.start = None
    sc.name = "room"
    ply = save_habitat(sc, str(tmp_path / "scene"))
    assert not os.path.exists(str(tmp_path / "scene" / "room.start.json"))
    assert load_scene(ply).start is None
    return ply


def test_simulator_start_of_a_scene_without_one(habitat_scene):
    assert start_pose_of(load_scene(habitat_scene)) == pytest.approx(CENTRE_START)
    assert start_pose_of(load_scene(habitat_scene), [0.5, 0.6, 1.0, 0.3]) == (0.5, 0.6, 1.0, 0.3)


def test_start_reaches_ground_truth_launch_and_evaluation(habitat_scene, tmp_path):
    out = str(tmp_path / "run")
    args = run_mission.parse_args(["--scene", habitat_scene, "--out", out])
    _, gt = run_mission.prepare_scene(args, out)
    assert gt["start"] == pytest.approx(CENTRE_START)
    with open(os.path.join(out, "ground_truth", "objects.json")) as f:
        assert json.load(f)["start"] == pytest.approx(CENTRE_START)
    cmd = run_mission.launch_command(args, habitat_scene, "o.yaml", 11311, gt["start"])
    (arg,) = [a for a in cmd if a.startswith("start_pose:=")]
    assert json.loads(arg[len("start_pose:="):]) == gt["start"]
    # The chair's own surface as its reconstruction: found, and scored against its observable part.
    chair = next(o for o in gt["objects"] if o["class"] == "chair")
    rec = tmp_path / "objects"
    rec.mkdir()
    mesh = trimesh.load(os.path.join(gt["gt_dir"], chair["mesh"]), force="mesh").subdivide_to_size(0.02)
    mesh.export(str(rec / "1.ply"))
    (rec / "objects.json").write_text(json.dumps({"objects": [{"id": 1, "class_name": "chair", "mesh": "1.ply"}]}))
    res = final.evaluate(out, gt, ["chair"], {"object_map": {"success": True, "dir": str(rec)}})
    assert "error" not in res, res.get("error")
    assert res["found"] == 1 and res["ground_truth"] == 1
    (m,) = res["objects"]
    # The chair stands on the floor: its bottom (0.45 x 0.45 of 2.6225 m^2) is hidden.
    assert m["observable_fraction"] == pytest.approx(1 - 0.45 * 0.45 / (2 * 0.45 * 0.45 + 4 * 0.45 * 0.9), abs=0.01)
    assert m["completeness"] == 1.0


def test_start_option(habitat_scene, tmp_path):
    out = str(tmp_path / "run")
    args = run_mission.parse_args(["--scene", habitat_scene, "--out", out, "--start", "0.6", "0.7", "1.1", "0.5"])
    assert args.start == [0.6, 0.7, 1.1, 0.5]
    _, gt = run_mission.prepare_scene(args, out)
    assert gt["start"] == [0.6, 0.7, 1.1, 0.5]
    assert "start_pose:=[0.6, 0.7, 1.1, 0.5]" in run_mission.launch_command(args, habitat_scene, "o.yaml", 1,
                                                                            gt["start"])
    # The explorable free volume needs the start too: the room's 16.5 m^3 less the furniture and the
    # 0.1 m cells that surfaces touch.
    with open(os.path.join(out, "ground_truth", "free_space.json")) as f:
        assert 13.0 < json.load(f)["explorable_free_volume_m3"] < 16.5


def test_a_start_next_to_a_wall_is_reported(habitat_scene, tmp_path):
    # Observability is computed in another process (GroundTruthIndex.start_observability); its error
    # reaches the report.
    out = str(tmp_path / "run")
    args = run_mission.parse_args(["--scene", habitat_scene, "--out", out, "--start", "0.05", "1.0", "1.0", "0"])
    _, gt = run_mission.prepare_scene(args, out)
    (tmp_path / "objects").mkdir()
    (tmp_path / "objects" / "objects.json").write_text(json.dumps({"objects": []}))
    res = final.evaluate(out, gt, ["chair"], {"object_map": {"success": True, "dir": str(tmp_path / "objects")}})
    assert "start [0.05, 1.0, 1.0] is not at least 0.125 m from every surface" in res["error"]


def test_wall_limit_guards_a_stuck_run_without_ending_a_slow_one(tmp_path):
    # make run on a loaded 2-core machine simulates slower than real time: a 600 s wall limit ended it at
    # 540 s of sim time. The default is 3 x the sim limit, at least 30 min; an explicit value is kept.
    out = str(tmp_path / "run")
    assert run_mission.parse_args(["--out", out]).wall_limit_s == 1800.0
    assert run_mission.parse_args(["--out", out, "--sim-limit-s", "1000"]).wall_limit_s == 3000.0
    assert run_mission.parse_args(["--out", out, "--sim-limit-s", "60"]).wall_limit_s == 1800.0
    assert run_mission.parse_args(["--out", out, "--wall-limit-s", "50"]).wall_limit_s == 50.0


def test_an_evaluation_with_nothing_saved_leaves_no_process_behind(habitat_scene, tmp_path):
    # A mission whose node died at start-up saved no map. The observability process started at the
    # evaluation's start must still be collected: left running, it blocked on its result pipe and
    # run_mission.py never exited (the interpreter joins it at exit).
    import multiprocessing as mp
    out = str(tmp_path / "run")
    args = run_mission.parse_args(["--scene", habitat_scene, "--out", out])
    _, gt = run_mission.prepare_scene(args, out)
    res = final.evaluate(out, gt, ["chair"], {})
    assert "found" not in res and "background" not in res
    assert mp.active_children() == []

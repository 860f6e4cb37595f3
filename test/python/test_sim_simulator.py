"""ROS-free simulator core: config validation, path rejection, poses and collision counting."""
import math
import os

import numpy as np
import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))

from semantic_exploration.sim.config import ConfigError, from_dict  # noqa: E402
from semantic_exploration.sim.scene import SceneError  # noqa: E402
from semantic_exploration.sim.simulator import (PathError, load_simulator,  # noqa: E402
                                                quaternion_from_matrix, rpy_matrix, waypoints_from_poses)

EXAMPLE = os.path.join(ROOT, "test", "data", "example_semantic.ply")


def sim_for(**over):
    cfg = from_dict(over)
    return load_simulator(cfg)


def test_sim_yaml_is_valid_and_complete():
    import yaml
    with open(os.path.join(ROOT, "config", "sim.yaml")) as f:
        d = yaml.safe_load(f)
    cfg = from_dict(d).validate()  # strict: every key in the file is a setting
    assert cfg.camera.fx == 262.5 and cfg.mav.v_max_mps == 1.5 and cfg.mav.radius_m == 0.125
    assert cfg.noise.sigma_min_m == 0.005 and cfg.noise.sigma_max_m == 0.2 and cfg.noise.s_per_m == 0.002
    assert cfg.start_pose is None and cfg.bounds_min_m is None
    # The shared parameter file's sections are accepted (and the rest ignored) too.
    with open(os.path.join(ROOT, "config", "semantic.yaml")) as f:
        unknown = []
        from_dict(yaml.safe_load(f), unknown=unknown).validate()
        assert "planner" in unknown


@pytest.mark.parametrize("over, param", [
    ({"camera": {"fx": -1.0}}, "camera/fx"),
    ({"camera": {"width": 1.5}}, "camera/width"),
    ({"noise": {"sigma_max_m": 0.001}}, "noise/sigma_max_m"),
    ({"mav": {"v_max_mps": float("nan")}}, "mav/v_max_mps"),
    ({"classes": {"of_interest": ["dragon"]}}, "classes/of_interest"),
    ({"lockstep": True, "lockstep_nodes": []}, "lockstep_nodes"),
    ({"start_pose": [1, 2]}, "start_pose"),
    ({"bounds_min_m": [0, 0, 0]}, "bounds_max_m"),
    ({"detector": {"drop_fraction": 2.0}}, "detector/drop_fraction"),
    ({"detector": {"hidden_object_ids": [3, -1]}}, "detector/hidden_object_ids"),
    ({"detector": {"hidden_object_ids": [2.5]}}, "detector/hidden_object_ids"),
    ({"lockstep": "yes"}, "lockstep"),
    ({"camera": {"nonsense": 1}}, "camera/nonsense"),
])
def test_bad_settings_name_the_parameter(over, param):
    with pytest.raises(ConfigError) as e:
        from_dict(over).validate()
    assert e.value.param == param


def test_unknown_scene_file_is_a_scene_error():
    with pytest.raises(SceneError, match="does not exist"):
        sim_for(scene={"file": "/nonexistent/x_semantic.ply"})


def test_path_checks():
    sim = sim_for(scene={"file": EXAMPLE})
    assert sim.start == (0.5, 1.5, 1.2, 0.0)
    with pytest.raises(PathError, match="NaN"):
        sim.set_path([(1, 1, 1, 0), (float("nan"), 1, 1, 0)])
    with pytest.raises(PathError, match="outside the bounds"):
        sim.set_path([(1, 1, 1, 0), (1, 1, 7.0, 0)])
    with pytest.raises(PathError, match="NaN or infinite"):
        waypoints_from_poses([((0, 0, 1), (0, 0, 0, float("inf")))])
    with pytest.raises(PathError, match="zero quaternion"):
        waypoints_from_poses([((0, 0, 1), (0, 0, 0, 0))])
    q = (0, 0, math.sin(0.35), math.cos(0.35))
    assert waypoints_from_poses([((1, 2, 3), q)]) == [(1.0, 2.0, 3.0, pytest.approx(0.7))]
    sim.set_path([(1.0, 1.5, 1.2, 0.5)])
    reached = False
    for _ in range(1000):
        reached |= sim.step(0.01)["goal_reached"]
    assert reached and sim.collisions == 0
    assert sim.path_length_m == pytest.approx(0.5, abs=1e-3)


def test_camera_pose_and_wall_collision_counting():
    sim = sim_for(scene={"file": EXAMPLE}, camera={"T_BC_xyz_m": [0.1, 0.0, 0.05], "mount_rpy_rad": [0, 0.2, 0]})
    T = sim.T_WC()
    # Optical axis (camera z) = body x pitched down by 0.2 rad.
    assert np.allclose(T[:3, 2], [math.cos(0.2), 0, -math.sin(0.2)])
    assert np.allclose(T[:3, 3], [0.6, 1.5, 1.25])
    q = quaternion_from_matrix(rpy_matrix(0.1, -0.4, 2.5))
    x, y, z, w = q
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    assert np.allclose(R, rpy_matrix(0.1, -0.4, 2.5))
    # Fly west through the wall at x = 0 (bounds include the wall thickness).
    sim.set_path([(0.5, 1.5, 1.2, 0.0), (-0.09, 1.5, 1.2, 0.0)])
    events = []
    for _ in range(500):
        c = sim.step(0.01)["collision"]
        if c:
            events.append(c)
    assert len(events) == 1 and sim.collisions == 1
    assert events[0]["label"] in ("wall", "mirror")
    assert events[0]["position"][0] <= 0.125 + 0.011


def test_rendered_frame_has_all_images_and_detections():
    sim = sim_for(scene={"file": EXAMPLE}, classes={"of_interest": ["chair", "table"]},
                  detector={"min_mask_pixels": 20})
    sim.set_path([(0.5, 1.5, 1.2, 0.0)])
    out = sim.render()
    assert out["depth"].shape == (240, 320) and out["rgb"].shape == (240, 320, 3)
    names = {d["class_name"] for d in out["detections"]}
    assert names <= {"chair", "table"} and "table" in names
    for d in out["detections"]:
        m = out["detection_mask"] == d["instance_id"]
        assert np.all(out["instance"][m] == d["object_id"])

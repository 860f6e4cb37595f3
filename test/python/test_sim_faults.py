"""Fault injection of the simulator (FaultsConfig, faults.py): validation with the
parameter's name, the tf gap window, seeded frame drops and detection images at
another resolution, each counted."""
import os

import numpy as np
import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))

from semantic_exploration.sim.config import ConfigError, FaultsConfig, from_dict  # noqa: E402
from semantic_exploration.sim.faults import FaultInjector  # noqa: E402

NS = 1_000_000_000


def test_faults_are_off_by_default_in_code_and_yaml():
    import yaml
    with open(os.path.join(ROOT, "config", "sim.yaml")) as f:
        cfg = from_dict(yaml.safe_load(f)).validate()
    assert cfg.faults == FaultsConfig()
    assert cfg.faults.tf_gap_s is None and cfg.faults.detector_scale == 1.0 and cfg.faults.frame_drop_fraction == 0.0
    inj = FaultInjector(cfg.faults)
    mask = np.arange(12, dtype=np.uint16).reshape(3, 4)
    for k in range(100):
        t = NS + k * NS // 10
        assert not inj.withhold_pose(t) and not inj.drop_frame(t)
        assert inj.detection_image(mask) is mask
    assert all(v == 0 for v in inj.counts.values())


@pytest.mark.parametrize("over, param", [
    ({"faults": {"tf_gap_s": [5.0, 4.0]}}, "faults/tf_gap_s"),
    ({"faults": {"tf_gap_s": [1.0]}}, "faults/tf_gap_s"),
    ({"faults": {"tf_gap_s": [-1.0, 2.0]}}, "faults/tf_gap_s"),
    ({"faults": {"tf_gap_s": [1.0, float("inf")]}}, "faults/tf_gap_s"),
    ({"faults": {"detector_scale": 0.0}}, "faults/detector_scale"),
    ({"faults": {"detector_scale": float("nan")}}, "faults/detector_scale"),
    ({"faults": {"frame_drop_fraction": 1.0}}, "faults/frame_drop_fraction"),
    ({"faults": {"frame_drop_fraction": -0.1}}, "faults/frame_drop_fraction"),
    ({"faults": {"seed": -1}}, "faults/seed"),
    ({"faults": {"gap": 1}}, "faults/gap"),
])
def test_bad_fault_settings_name_the_parameter(over, param):
    with pytest.raises(ConfigError) as e:
        from_dict(over).validate()
    assert e.value.param == param


def test_tf_gap_withholds_poses_and_counts_frames_inside_the_window():
    cfg = from_dict({"faults": {"tf_gap_s": [2, 3]}}).validate()  # integers are accepted as seconds
    assert cfg.faults.tf_gap_s == [2.0, 3.0]
    inj = FaultInjector(cfg.faults)
    frames = [NS + k * NS // 10 for k in range(40)]  # 1.0 .. 4.9 s at 10 Hz
    sent_without_tf = [t for t in frames if inj.withhold_pose(t) and not inj.drop_frame(t)]
    # 2.0, 2.1, ..., 3.0 s: 11 frames (closed window)
    assert [round(t / NS, 1) for t in sent_without_tf] == [round(2.0 + 0.1 * k, 1) for k in range(11)]
    assert inj.counts["poses_withheld"] == 11 and inj.counts["frames_without_tf"] == 11
    assert inj.counts["frames_dropped"] == 0
    poses = [NS + k * NS // 50 for k in range(200)]  # 50 Hz tf: 2.0 .. 3.0 s holds 51 stamps
    assert sum(inj.in_tf_gap(t) for t in poses) == 51


def test_frame_drops_are_seeded_and_near_the_fraction():
    def pattern(seed):
        inj = FaultInjector(from_dict({"faults": {"frame_drop_fraction": 0.2, "seed": seed}}).validate().faults)
        return [inj.drop_frame(NS + k) for k in range(2000)], inj.counts
    a, counts = pattern(7)
    assert a == pattern(7)[0] and a != pattern(8)[0]
    assert counts["frames_dropped"] == sum(a)
    assert 0.17 * 2000 < sum(a) < 0.23 * 2000  # binomial(2000, 0.2): sigma 18 frames
    assert counts["frames_without_tf"] == 0


def test_detection_image_at_another_resolution_keeps_ids():
    inj = FaultInjector(from_dict({"faults": {"detector_scale": 0.5}}).validate().faults)
    mask = np.zeros((240, 320), np.uint16)
    mask[100:140, 40:120] = 3
    small = inj.detection_image(mask)
    assert small.shape == (120, 160) and small.dtype == np.uint16
    assert set(np.unique(small).tolist()) == {0, 3}
    assert np.count_nonzero(small == 3) == 20 * 40  # the mask block halves on both axes
    big = FaultInjector(from_dict({"faults": {"detector_scale": 2.0}}).validate().faults).detection_image(mask)
    assert big.shape == (480, 640) and np.count_nonzero(big == 3) == 4 * np.count_nonzero(mask == 3)
    assert inj.counts["detections_rescaled"] == 1

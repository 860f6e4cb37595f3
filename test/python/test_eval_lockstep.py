"""The mission's side of deterministic runs (eval/lockstep.py), without ROS: rows
written at frame boundaries hold exactly the messages stamped at or before
their time, whatever order the messages arrived in."""
import threading
from types import SimpleNamespace as NS

import pytest
import yaml

from semantic_exploration.eval import lockstep
from semantic_exploration.eval.runlog import RunLog

S = lockstep.NS


def stamp(t_s):
    ns = int(round(t_s * S))
    return NS(secs=ns // S, nsecs=ns % S)


def pose(t_s, x):
    return NS(header=NS(stamp=stamp(t_s)), pose=NS(position=NS(x=x, y=0.0, z=0.0)))


def stats(t_s, volume):
    return NS(header=NS(stamp=stamp(t_s)), explored_volume_m3=volume, frontier_count=1, surface_observed_share=-1.0,
              integration_time_ms=0.0)


def test_rows_hold_the_messages_stamped_up_to_their_time_in_any_arrival_order():
    rows = {}
    for order in (False, True):
        log = RunLog()
        st = lockstep.StampedLog(log, clock_ns=lambda: 0)
        msgs = [("/mav/pose", pose(0.9, 0.0)), ("/mav/pose", pose(1.0, 1.0)), ("/background_map/stats",
                stats(1.0, 10.0)), ("/mav/pose", pose(1.1, 3.0)), ("/background_map/stats", stats(1.1, 20.0))]
        # Stats before poses or poses before stats (each topic in its own order, as over one connection).
        for topic, m in sorted(msgs, key=lambda tm: tm[0]) if order else msgs:
            st.put(topic, m)
        st.advance(1 * S)
        rows[order] = log.row(1.0, None, [])
        assert rows[order]["explored_volume_m3"] == 10.0 and rows[order]["path_length_m"] == 1.0
        st.advance(int(1.1 * S))
        assert log.row(1.1, None, [])["explored_volume_m3"] == 20.0 and log.path_length_m == 3.0
    assert rows[False] == rows[True]


def test_row_clock_gives_each_grid_time_once():
    c = lockstep.RowClock(1.0)
    assert c.rows_until(int(0.9 * S)) == [0.0]
    assert c.rows_until(int(1.0 * S)) == [1.0]
    assert c.rows_until(int(1.1 * S)) == []
    assert c.rows_until(int(3.05 * S)) == [2.0, 3.0]


def test_wait_for_a_frame_message_that_comes_after_the_frame_report():
    st = lockstep.StampedLog(RunLog(), clock_ns=lambda: 0)
    late = threading.Timer(0.2, lambda: st.put("/background_map/stats", stats(2.0, 5.0)))
    late.start()
    assert st.wait_for(["/background_map/stats"], 2 * S, timeout_s=10.0) == []
    assert st.wait_for(["/background_map/stats", "/mav/pose"], 2 * S, timeout_s=0.05) == ["/mav/pose"]


class FakeBarrier:
    def __init__(self, frames):
        self.frames, self.acked = list(frames), []

    def next_frame(self, timeout_s):
        return self.frames.pop(0) if self.frames else None

    def ack(self, t_ns):
        self.acked.append(t_ns)


def test_loop_writes_rows_takes_snapshots_and_stops_at_a_frame():
    log = RunLog()
    st = lockstep.StampedLog(log, clock_ns=lambda: 0)
    frames = [int(round(t * S)) for t in (1.0, 1.5, 2.0, 2.5)]
    for t in (1.0, 1.5, 2.0, 2.5):
        for topic, m in (("/mav/pose", pose(t, t)), ("/background_map/stats", stats(t, 10 * t)),
                         ("/object_map/objects", NS(header=NS(stamp=stamp(t)), objects=[]))):
            st.put(topic, m)
    barrier = FakeBarrier(frames)
    written, snaps = [], []
    why, t_end = lockstep.run_lockstep(
        barrier, st, lockstep.RowClock(1.0), lambda t: written.append((t, log.row(t, None, [])["explored_volume_m3"])),
        snaps.append, lambda t: "sim_time_limit" if t is not None and t > 2.2 else "")
    assert (why, t_end) == ("sim_time_limit", 2.5)
    assert written == [(0.0, 0.0), (1.0, 10.0), (2.0, 20.0)]
    assert snaps == [1.0, 1.5, 2.0, 2.5]
    assert barrier.acked == frames[:3]  # the stop frame is held: the maps are saved at it


def deterministic(tmp_path, nodes_text, user_sim_text):
    """deterministic_setup on these overrides and a config/ of two one-line files; (nodes file, args)."""
    overrides = tmp_path / "overrides.yaml"
    overrides.write_text(nodes_text)
    user = tmp_path / "user_sim.yaml"
    user.write_text(user_sim_text)
    cfg = tmp_path / "config"
    cfg.mkdir()
    (cfg / "deterministic.yaml").write_text("planner:\n  ompl_termination: iterations\n")
    (cfg / "deterministic_sim.yaml").write_text("lockstep_planner: true\n")
    args = NS(sim_overrides=str(user))
    lockstep.deterministic_setup(args, str(tmp_path), str(overrides), str(cfg))
    return overrides, args


def test_deterministic_setup_merges_the_overrides(tmp_path):
    overrides, args = deterministic(tmp_path, "bounds:\n  min_m: [0, 0, 0]\nplanner:\n  seed: 4\n",
                                    "detector:\n  min_mask_pixels: 50\n")
    user = tmp_path / "user_sim.yaml"
    assert yaml.safe_load(overrides.read_text()) == {"bounds": {"min_m": [0, 0, 0]},
                                                     "planner": {"seed": 4, "ompl_termination": "iterations"}}
    assert args.user_sim_overrides == str(user)
    assert yaml.safe_load(open(args.sim_overrides).read()) == {"detector": {"min_mask_pixels": 50},
                                                              "lockstep_planner": True}


@pytest.mark.parametrize("params,expected", [
    ({"/planner/planner/ompl_termination": "iterations", "/planner/planner/ompl_iterations": 1000}, True),
    ({"/planner/planner/time_budget_s": 0.1}, False)])
def test_report_names_the_planner_timing(params, expected):
    text = lockstep.timing_of(expected, lambda k, d: params.get(k, d))
    assert text == ("OMPL stops after 1000 iterations per candidate; deterministic (lockstep planner and mission)"
                    if expected else "OMPL wall-time budget of 0.1 s per candidate; paths depend on the machine's "
                    "speed, two runs differ")


def test_deterministic_setup_keeps_rosparam_angle_tags_of_the_simulator_overrides(tmp_path):
    # The simulator's overrides are merged with config/deterministic_sim.yaml; a tagged angle must
    # reach rosparam as written instead of failing the dump.
    _, args = deterministic(tmp_path, "planner:\n  seed: 4\n", "mav:\n  start_yaw_rad: !degrees 90\n")
    assert "start_yaw_rad: !degrees '90'" in open(args.sim_overrides).read()
    rosparam = pytest.importorskip("rosparam")
    loaded = rosparam.load_file(args.sim_overrides)[0][0]
    assert loaded["mav"]["start_yaw_rad"] == pytest.approx(1.5707963) and loaded["lockstep_planner"] is True

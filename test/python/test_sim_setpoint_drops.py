"""What mav_sim refuses of a setpoint and how it counts it (issue 15, the soak
of setpoint_position/local): check_setpoint names one reason per refused
setpoint (the first that applies, in the order setpoints.py lists), takes
non-unit quaternions and positions on the bounds, and reads the yaw of a
quaternion with components near 1e200 (their sum of squares overflows);
DropCounter counts per reason, publishes the cumulative counts after every
drop, and logs each reason at most once per period. The node-level count is
soak_sim_setpoints.test."""
import math

import pytest

from semantic_exploration.sim.drops import DropCounter
from semantic_exploration.sim.setpoints import REASONS, SetpointRefused, check_setpoint
from semantic_exploration.sim.simulator import waypoints_from_poses

BOUNDS = ((0.0, 0.0, 0.0), (8.0, 6.0, 3.0))
UP = (0.0, 0.0, 0.0, 1.0)
NAN, INF = float("nan"), float("inf")


def reason(frame, position, quaternion, bounds=BOUNDS):
    try:
        check_setpoint(frame, "world", position, quaternion, bounds)
    except SetpointRefused as e:
        assert e.reason in REASONS
        return e.reason
    return None


def test_each_defect_is_refused_under_its_reason():
    assert reason("map", (1, 1, 1), UP) == "setpoint_wrong_frame"
    assert reason("/map", (1, 1, 1), UP) == "setpoint_wrong_frame"
    assert reason("world", (NAN, 1, 1), UP) == "setpoint_not_finite"
    assert reason("world", (1, 1, 1), (0, 0, INF, 1)) == "setpoint_not_finite"
    assert reason("world", (1, -INF, 1), UP) == "setpoint_not_finite"
    assert reason("world", (1, 1, 1), (0, 0, 0, 0)) == "setpoint_zero_quaternion"
    assert reason("world", (1, 1, 1), (5e-324, 0, 0, 0)) == "setpoint_zero_quaternion"  # norm below 1e-6
    assert reason("world", (1, 1, 1), (0, 0, 5e-7, 5e-7)) == "setpoint_zero_quaternion"  # norm 7.1e-7
    assert reason("world", (8.01, 1, 1), UP) == "setpoint_out_of_bounds"
    assert reason("world", (1, 1, -0.01), UP) == "setpoint_out_of_bounds"
    assert reason("world", (1e30, 1, 1), UP) == "setpoint_out_of_bounds"
    # The first defect that applies names the drop.
    assert reason("map", (NAN, 1e30, 1), (0, 0, 0, 0)) == "setpoint_wrong_frame"
    assert reason("world", (NAN, 1e30, 1), (0, 0, 0, 0)) == "setpoint_not_finite"
    assert reason("world", (1e30, 1, 1), (0, 0, 0, 0)) == "setpoint_zero_quaternion"


def test_usable_setpoints_are_taken():
    assert check_setpoint("world", "world", (1, 2, 1.5), UP, BOUNDS) == (1.0, 2.0, 1.5, 0.0)
    for frame in ("", "/world"):
        assert reason(frame, (1, 1, 1), UP) is None
    assert reason("world", (0, 0, 0), UP) is None and reason("world", (8, 6, 3), UP) is None  # on the bounds
    assert reason("world", (1e30, 1, 1), UP, bounds=None) is None  # no scene yet: checked later
    # Not unit: normalised. (0, 0, 2, 2) is a quarter turn: yaw pi/2; (0, 0, 1e-5, 0) a half turn.
    x, y, z, yaw = check_setpoint("world", "world", (1, 1, 1), (0, 0, 2, 2), BOUNDS)
    assert yaw == pytest.approx(math.pi / 2, abs=1e-12)
    assert abs(check_setpoint("world", "world", (1, 1, 1), (0, 0, 1e-5, 0), BOUNDS)[3]) == pytest.approx(math.pi)


def test_yaw_of_a_quaternion_with_huge_components():
    # (0, 0, 1e200, 1e200) is the quarter turn (0, 0, 0.707, 0.707): yaw pi/2. A sum of squares
    # overflows to inf, the quaternion divided by it is 0, and the yaw came out 0.
    (wp,) = waypoints_from_poses([((1, 1, 1), (0, 0, 1e200, 1e200))])
    assert wp[3] == pytest.approx(math.pi / 2, abs=1e-12)
    assert check_setpoint("world", "world", (1, 1, 1), (0, 0, -1e300, 1e300), BOUNDS)[3] == \
        pytest.approx(-math.pi / 2, abs=1e-12)


def test_drop_counter_counts_publishes_and_logs_once_per_period():
    published, logged, now = [], [], [0.0]
    drops = DropCounter(published.append, lambda r, n, d: logged.append((r, n, d)), period_s=5.0,
                        clock=lambda: now[0])
    assert published == [{}]  # at start, as the C++ nodes
    for t, r in [(0.0, "setpoint_wrong_frame"), (1.0, "setpoint_wrong_frame"), (1.0, "setpoint_not_finite"),
                 (4.9, "setpoint_wrong_frame"), (6.0, "setpoint_wrong_frame"), (6.5, "setpoint_not_finite")]:
        now[0] = t
        drops.drop(r, "at %.1f" % t)
    drops.drop("setpoint_out_of_bounds", "three at once", 3)
    drops.drop("setpoint_out_of_bounds", "none", 0)
    assert drops.counts() == {"setpoint_wrong_frame": 4, "setpoint_not_finite": 2, "setpoint_out_of_bounds": 3}
    assert drops.total() == 9 and drops.count("setpoint_unreadable") == 0
    assert len(published) == 1 + 7  # after each drop (not after n = 0), cumulative
    assert published[2] == {"setpoint_wrong_frame": 2}
    assert published[-1] == drops.counts()
    # Each reason logged when 5 s or more passed since its last line: wrong_frame at 0 and 6, not_finite at 1 and 6.5.
    assert logged == [("setpoint_wrong_frame", 1, "at 0.0"), ("setpoint_not_finite", 1, "at 1.0"),
                      ("setpoint_wrong_frame", 4, "at 6.0"), ("setpoint_not_finite", 2, "at 6.5"),
                      ("setpoint_out_of_bounds", 3, "three at once")]

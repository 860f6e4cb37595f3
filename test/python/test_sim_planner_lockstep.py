"""mav_sim's planner lockstep (sim/planner_lockstep.py) with a stand-in planner service:
when it asks, with which stamps, whether it waits for the planner's inputs and for
the path, and when it asks again."""
import sys
import threading
import types

import pytest

from semantic_exploration.sim.planner_lockstep import NS, PlannerLockstep


class FakeRospy(types.ModuleType):
    def __init__(self, answer):
        super().__init__("rospy")
        self.answer, self.calls, self.args = answer, 0, []

    class Time:
        def __init__(self, secs=0, nsecs=0):
            self.ns = secs * NS + nsecs

    def wait_for_service(self, name, timeout=None):
        if self.answer is None:
            raise RuntimeError("service %s not available" % name)

    def ServiceProxy(self, name, cls, persistent=False):
        def call(*args):
            self.calls += 1
            self.args.append(tuple(a.ns for a in args))
            return self.answer()
        return call


def answer(success, pending=False, message=""):
    return types.SimpleNamespace(success=success, pending=pending, message=message)


@pytest.fixture
def planner(monkeypatch):
    def install(answer):
        rospy = FakeRospy(answer)
        srv = types.ModuleType("semantic_exploration.srv")
        srv.PlanOnce = object
        monkeypatch.setitem(sys.modules, "rospy", rospy)
        monkeypatch.setitem(sys.modules, "semantic_exploration.srv", srv)
        return rospy
    return install


def test_asks_only_while_idle_and_waits_for_the_path(planner):
    pl = PlannerLockstep("/planner/plan_once", retry_s=1.0, timeout_s=10.0, startup_timeout_s=1.0)
    planner(lambda: (threading.Timer(0.2, pl.path_handled).start(), answer(True))[1])
    assert pl.due(0, idle=True) and not pl.due(0, idle=False)
    logs = []
    assert pl.plan(2 * NS, lambda level, text: logs.append(text)) is True
    assert (pl.calls, pl.paths, logs) == (1, 1, [])
    assert not pl.due(2 * NS + NS // 2, idle=True)  # a new path is being flown; the retry clock runs
    pl.goal_reached(5 * NS)
    assert pl.due(5 * NS, idle=True)


def test_no_path_asks_again_after_the_retry_period(planner):
    fake = planner(lambda: answer(False))
    pl = PlannerLockstep("/planner/plan_once", retry_s=1.0, timeout_s=10.0, startup_timeout_s=1.0)
    assert pl.plan(3 * NS, print) is False
    assert not pl.due(3 * NS + NS // 2, idle=True) and pl.due(4 * NS, idle=True)
    assert fake.calls == 1 and pl.paths == 0


def test_a_published_path_that_never_comes_is_reported(planner):
    planner(lambda: answer(True))
    pl = PlannerLockstep("/planner/plan_once", retry_s=1.0, timeout_s=0.1, startup_timeout_s=1.0)
    logs = []
    assert pl.plan(NS, lambda level, text: logs.append((level, text))) is False
    assert logs[0][0] == "warn" and "no longer repeatable" in logs[0][1]


def test_pending_inputs_are_waited_for_with_sim_time_stopped(planner):
    # The planner answers pending twice (the frame's inputs still on their
    # way), then plans: three calls with the same stamps, one path.
    answers = iter([answer(False, pending=True), answer(False, pending=True), answer(True)])
    pl = PlannerLockstep("/planner/plan_once", retry_s=1.0, timeout_s=10.0, startup_timeout_s=1.0)
    fake = planner(lambda: next(answers))
    threading.Timer(0.2, pl.path_handled).start()
    logs = []
    assert pl.plan(7 * NS + 50, lambda level, text: logs.append(text), frame_ns=7 * NS, pose_ns=6 * NS + 90) is True
    assert fake.args == [(7 * NS + 50, 7 * NS, 6 * NS + 90)] * 3
    assert (pl.calls, pl.pending, pl.paths) == (1, 2, 1)
    assert len(logs) == 1 and "after 2 pending answer(s)" in logs[0]  # info, once


def test_inputs_that_never_arrive_are_planned_without(planner):
    fake = planner(lambda: answer(False, pending=len(fake.args) < 1000, message="waiting for object_map/objects"))
    pl = PlannerLockstep("/planner/plan_once", retry_s=1.0, timeout_s=0.1, startup_timeout_s=1.0)
    logs = []
    assert pl.plan(3 * NS, lambda level, text: logs.append((level, text)), frame_ns=3 * NS, pose_ns=3 * NS) is False
    # Asked again until the wall-time limit, then once without frame and pose stamps.
    assert len(fake.args) > 2 and fake.args[-2] == (3 * NS, 3 * NS, 3 * NS) and fake.args[-1] == (3 * NS, 0, 0)
    assert logs[0][0] == "warn" and "object_map/objects" in logs[0][1] and "no longer repeatable" in logs[0][1]


def test_a_planner_that_is_not_up_is_asked_again(planner):
    planner(None)
    pl = PlannerLockstep("/planner/plan_once", retry_s=0.5, timeout_s=1.0, startup_timeout_s=0.1)
    logs = []
    assert pl.plan(NS, lambda level, text: logs.append(text)) is False
    assert "not available" in logs[0] and pl.due(NS + NS // 2, idle=True)


def test_settings_are_checked():
    from semantic_exploration.sim.config import ConfigError, from_dict
    cfg = from_dict({"lockstep": True, "lockstep_nodes": ["background_map"], "lockstep_planner": True}).validate()
    assert cfg.lockstep_planner and cfg.lockstep_planner_retry_s == 1.0
    with pytest.raises(ConfigError, match="lockstep_planner_retry_s"):
        from_dict({"lockstep_planner_retry_s": 0.0}).validate()
    with pytest.raises(ConfigError, match="lockstep_planner"):
        from_dict({"lockstep_planner": "yes"}).validate()
    with pytest.raises(ConfigError, match="lockstep_planner.*needs lockstep"):
        from_dict({"lockstep_planner": True}).validate()

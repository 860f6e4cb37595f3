"""What held a run open when it ended: RunLog.open_conditions() reads the planner's last
status (the paper's three conditions), run_mission.py puts it in summary.json
(end_conditions) and the experiment report's run table names it."""
from types import SimpleNamespace as NS

from semantic_exploration.eval.runlog import RunLog


def status(**kw):
    base = dict(state=2, iteration=9, active_frontiers=0, background_observed_share=0.5, frontiers_done=True,
                background_done=True, objects_done=True, last_condition="", object_ids=[1], retired_object_ids=[],
                planning_time_s=0.01)
    base.update(kw)
    return NS(**base)


def between_iterations():
    """A "planning" status as the planner node publishes it between iterations (publishStatus): the
    message itself where its package is built, else the same fields at their defaults."""
    try:
        from semantic_exploration.msg import ExplorationStatus
        return ExplorationStatus(state=1, iteration=10, message="planning")
    except ImportError:
        return status(state=1, iteration=10, active_frontiers=0, background_observed_share=0.0,
                      frontiers_done=False, background_done=False, objects_done=False, object_ids=[],
                      planning_time_s=0.0)


def test_nothing_before_the_first_iteration_then_the_conditions_not_yet_met():
    log = RunLog()
    assert log.open_conditions() == {}
    assert log.row(0.0, 0.0, [])["active_frontiers"] == ""
    log._on_status(between_iterations())
    assert log.open_conditions() == {} and log.row(0.5, 0.5, [])["active_frontiers"] == ""
    log._on_status(status(active_frontiers=162, background_observed_share=0.98201, frontiers_done=False,
                          objects_done=False, retired_object_ids=[4, 7]))
    expected = {"active_frontiers": 162, "background_observed_share": 0.982, "not_done": ["frontiers", "objects"],
                "last_condition": ""}
    assert log.open_conditions() == expected
    assert log.row(1.0, 1.0, [])["active_frontiers"] == 162
    # The planner's statuses between iterations leave the conditions (and the iteration's time) at 0:
    # they must not read as "no frontier left, nothing done".
    log._on_status(between_iterations())
    assert log.open_conditions() == expected and log.row(2.0, 2.0, [])["active_frontiers"] == 162


def test_an_explored_end_leaves_nothing_open_and_names_the_last_condition():
    log = RunLog()
    log._on_status(status(state=3, last_condition="frontiers"))
    cond = log.open_conditions()
    assert cond["not_done"] == [] and cond["last_condition"] == "frontiers" and cond["active_frontiers"] == 0


def test_a_status_without_the_fields_reports_nothing():
    # A bag recorded before ExplorationStatus carried the conditions: the report leaves them out.
    log = RunLog()
    log._on_status(NS(state=2, iteration=3, object_ids=[], retired_object_ids=[], planning_time_s=0.2))
    assert log.result is not None
    assert log.open_conditions() == {} and log.row(1.0, 1.0, [])["active_frontiers"] == ""

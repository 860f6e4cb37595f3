"""The paired comparison behind the paper's claims (eval/claims.py): a sign
test with hand-computed answers, runs paired by name, and the claims' text."""
import numpy as np
import pytest

pytest.importorskip("matplotlib")
from semantic_exploration.eval import claims, experiments  # noqa: E402

from test_eval_experiments import make_run  # noqa: E402


def test_sign_test_by_hand():
    # 2 of 9 better: 2 (C(9,0) + C(9,1) + C(9,2)) / 2^9 = 2 * 46 / 512
    assert claims.sign_test_p(2, 7) == pytest.approx(92 / 512)
    assert claims.sign_test_p(7, 2) == pytest.approx(92 / 512)
    assert claims.sign_test_p(0, 6) == pytest.approx(2 / 64)  # six of six: 0.031
    assert claims.sign_test_p(0, 5) == pytest.approx(2 / 32)  # five of five is not enough at 5%
    assert claims.sign_test_p(5, 5) == 1.0  # 2 * 638 / 1024 capped
    assert claims.sign_test_p(0, 0) == 1.0


def test_runs_pair_by_name():
    assert claims.pair_key("/x/runs/scene0_run1_semantic", "semantic") == "scene0_run1"
    assert claims.pair_key("/x/runs/scene0_run1_classic/", "classic") == "scene0_run1"
    assert claims.pair_key("/x/runs/s0", "semantic") is None


def campaign(tmp_path, found_at):
    """One run per mode and pair: found_at = {pair: (semantic s, classic s)} at which all 4 objects are found."""
    by_mode = {"semantic": [], "classic": []}
    for pair, times in found_at.items():
        for mode, t in zip(("semantic", "classic"), times):
            by_mode[mode].append(make_run(str(tmp_path / ("%s_%s" % (pair, mode))), [0, t, 100], [0, 5, 10],
                                          [0, 4, 4]))
    return by_mode


def test_claims_count_the_pairs(tmp_path):
    by_mode = campaign(tmp_path, {"scene0_run0": (10, 20), "scene1_run0": (30, 20), "scene2_run0": (20, 20)})
    by_mode["semantic"].append(make_run(str(tmp_path / "scene3_run0_semantic"), [0, 5], [0, 5], [0, 4]))  # no pair
    res = experiments.write_outputs(str(tmp_path / "out"), by_mode, grid_step_s=10)
    # the share seen from <= d_obj at the end: semantic 60 / 10 / 30 / 30 (unpaired), classic 20 / 20 / 20
    for mode, shares in (("semantic", (60, 10, 30, 30)), ("classic", (20, 20, 20))):
        for r, share in zip(by_mode[mode], shares):
            r["series"]["object_observed_percent"] = np.array([0.0, share, share][:len(r["t"])])
    closer = experiments.write_outputs(str(tmp_path / "out2"), by_mode, grid_step_s=10)["claims"][5]
    assert closer["holds"] is True  # medians 30% against 20%
    assert closer["measured"] == ("semantic 30%, classic 20% (medians); in 3 paired runs semantic more in 2, less "
                                  "in 1, tied in 0 (two-sided sign test p = 1.000: could be chance: the pairs do "
                                  "not tell the modes apart at 5%)")
    sooner = res["claims"][1]
    assert sooner["paired"] == {"pairs": 3, "better": 1, "worse": 1, "tied": 1, "p": 1.0}
    assert sooner["measured"].endswith(
        "in 3 paired runs semantic sooner in 1, later in 1, tied in 1 (two-sided sign test p = 1.000: could be chance: "
        "the pairs do not tell the modes apart at 5%)")
    assert res["claims"][5]["measured"] == "not measured"  # no observed-share column in these runs
    report = open(str(tmp_path / "out" / "report.md")).read()  # each run's time in the run table
    assert "| ../scene1_run0_semantic | semantic | explored | 100.0 s | - | 100% | 30 s |" in report


def test_six_pairs_one_way_are_unlikely_to_be_chance(tmp_path):
    by_mode = campaign(tmp_path, {"scene%d_run0" % i: (20, 30 + i) for i in range(6)})
    sooner = experiments.write_outputs(str(tmp_path / "out"), by_mode, grid_step_s=10)["claims"][1]
    assert sooner["holds"] is True
    assert sooner["paired"]["better"] == 6 and sooner["paired"]["p"] == pytest.approx(1 / 32)
    assert "(two-sided sign test p = 0.031: unlikely to be chance)" in sooner["measured"]


def test_pairs_without_the_figure_are_left_out(tmp_path):
    by_mode = campaign(tmp_path, {"scene0_run0": (10, 20), "scene1_run0": (30, 20)})
    by_mode["semantic"][0]["series"]["object_observed_percent"] = np.array([0.0, 50.0, 60.0])
    by_mode["classic"][0]["series"]["object_observed_percent"] = np.array([0.0, 10.0, 20.0])
    # scene1's runs have no observed share (nan throughout): not a pair for that claim
    value = lambda r: claims._last(r["series"]["object_observed_percent"])  # noqa: E731
    assert claims.paired(by_mode, value, True) == {"pairs": 1, "better": 1, "worse": 0, "tied": 0, "p": 1.0}
    # a run that never finds all (inf) is later than one that does, and ties with another that never does
    d = tmp_path / "never"
    never = {"semantic": [make_run(str(d / ("scene%d_run0_semantic" % i)), [0, 50], [0, 5], [0, 3])
                          for i in (0, 1)],
             "classic": [make_run(str(d / "scene0_run0_classic"), [0, 50], [0, 5], [0, 4]),
                         make_run(str(d / "scene1_run0_classic"), [0, 50], [0, 5], [0, 2])]}
    t100 = lambda r: experiments.time_to_reach(r["t"], r["series"]["found_percent"], 100.0)  # noqa: E731
    assert claims.paired(never, t100, False) == {"pairs": 2, "better": 0, "worse": 1, "tied": 1, "p": 1.0}

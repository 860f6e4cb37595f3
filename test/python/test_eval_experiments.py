"""Aggregation of runs into median / percentile curves, with known answers."""
import csv
import json
import os

import numpy as np
import pytest

pytest.importorskip("matplotlib")
from semantic_exploration.eval import experiments  # noqa: E402


def make_run(d, times, explored, found, n_gt=4, reason="explored", detector=None):
    os.makedirs(d)
    with open(os.path.join(d, "timeseries.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["wall_s", "sim_s", "explored_volume_m3", "ground_truth_found", "path_length_m"])
        for t, e, n in zip(times, explored, found):
            w.writerow([t, t, e, n, t * 0.5])
    with open(os.path.join(d, "summary.json"), "w") as f:
        json.dump({"ground_truth_objects": n_gt, "termination_reason": reason, "collisions": 0,
                   "detector": detector}, f)
    return experiments.read_run(d)


def test_resample_is_stepwise_and_holds_the_last_value():
    t = np.array([1.0, 3.0])
    y = np.array([10.0, 30.0])
    assert experiments.resample(t, y, np.array([0.0, 1.0, 2.0, 3.0, 9.0])).tolist() == [0, 10, 10, 30, 30]


def test_median_and_percentiles_over_three_runs(tmp_path):
    runs = [make_run(str(tmp_path / str(i)), [0, 10, 20], [0, v, 2 * v], [0, f, 4])
            for i, (v, f) in enumerate([(10, 1), (20, 2), (30, 3)])]
    agg = experiments.aggregate(runs, np.array([0.0, 10.0, 20.0]))
    assert agg["explored_volume_m3"]["median"].tolist() == [0, 20, 40]
    # numpy's linear percentile of (10, 20, 30): p10 = 12, p90 = 28
    assert agg["explored_volume_m3"]["p10"][1] == pytest.approx(12.0)
    assert agg["explored_volume_m3"]["p90"][1] == pytest.approx(28.0)
    assert agg["found_percent"]["median"].tolist() == [0, 50, 100]


def test_time_to_reach():
    t = np.array([0.0, 5.0, 9.0])
    assert experiments.time_to_reach(t, np.array([0, 50, 100.0]), 100) == 9.0
    assert experiments.time_to_reach(t, np.array([0, 50, 75.0]), 100) == float("inf")
    assert np.isnan(experiments.time_to_reach(t, np.full(3, np.nan), 100))  # not measured, not "never"


def test_outputs_are_written(tmp_path):
    a = [make_run(str(tmp_path / "a0"), [0, 10, 20], [0, 10, 20], [0, 2, 4])]
    b = [make_run(str(tmp_path / "b0"), [0, 10, 30], [0, 5, 30], [0, 1, 2])]
    res = experiments.write_outputs(str(tmp_path / "out"), {"semantic": a, "classic": b}, grid_step_s=10)
    for name in ("report.md", "curves.csv", "explored_volume_m3.png", "found_percent.png"):
        assert os.path.getsize(str(tmp_path / "out" / name)) > 0
    rows = {r["mode"]: r for r in res["rows"]}
    assert rows["semantic"]["found_percent_median"] == 100.0
    assert rows["semantic"]["time_to_all_found_s_median"] == 20.0
    assert rows["classic"]["found_percent_median"] == 50.0
    report = open(str(tmp_path / "out" / "report.md")).read()
    assert "| semantic | 1 | 100% | - | - | 20.0 m3 | 20 s |" in report  # spurious, duplicated: no evaluation
    assert "| classic | 1 | 50% | - | - | 30.0 m3 | never |" in report


def test_report_names_the_setup_and_the_simulator_overrides(tmp_path):
    yml = tmp_path / "sim.yaml"
    yml.write_text("# comment\ndetector:\n  min_mask_pixels: 1200  # px\nreal_time_factor: 0\n")
    assert experiments.describe_yaml(str(yml)) == "sim.yaml (detector/min_mask_pixels 1200, real_time_factor 0)"
    a = [make_run(str(tmp_path / "a0"), [0, 10], [0, 10], [0, 4])]
    experiments.write_outputs(str(tmp_path / "out"), {"semantic": a}, grid_step_s=10,
                              setup=["scenes 0 1 2", "simulator overrides: " + experiments.describe_yaml(str(yml))])
    report = open(str(tmp_path / "out" / "report.md")).read().splitlines()
    assert report[2:4] == ["- scenes 0 1 2", "- simulator overrides: sim.yaml (detector/min_mask_pixels 1200, "
                           "real_time_factor 0)"]


def test_report_names_the_detector(tmp_path):
    default = {"min_mask_pixels": 1200, "source": "config/sim.yaml"}
    far = {"min_mask_pixels": 50, "source": "detector_long_range.yaml"}
    a = [make_run(str(tmp_path / "a0"), [0, 10], [0, 10], [0, 4], detector=default)]
    experiments.write_outputs(str(tmp_path / "out"), {"semantic": a}, grid_step_s=10, setup=["scenes 0"])
    report = open(str(tmp_path / "out" / "report.md")).read().splitlines()
    assert report[3] == ("- detector: masks of at least 1200 px (config/sim.yaml; a whole chair detected from "
                         "about 4 m)")
    b = [make_run(str(tmp_path / "b0"), [0, 10], [0, 10], [0, 4], detector=far)]
    experiments.write_outputs(str(tmp_path / "mixed"), {"semantic": a, "classic": b}, grid_step_s=10)
    report = open(str(tmp_path / "mixed" / "report.md")).read().splitlines()
    assert report[2] == ("- detector: masks of at least 1200 px (config/sim.yaml; a whole chair detected from "
                         "about 4 m); masks of at least 50 px (detector_long_range.yaml; a whole chair detected "
                         "from 10 m) (differs between runs)")
    assert experiments.describe_detector(None) == "unknown"


def test_paper_claims_on_known_curves(tmp_path):
    # Semantic: all 4 found at 20 s, 30 m3 at the end; classic: all at 30 s, 32 m3.
    sem = [make_run(str(tmp_path / "s0"), [0, 10, 20, 30], [0, 10, 20, 30], [0, 2, 4, 4])]
    cls = [make_run(str(tmp_path / "c0"), [0, 10, 20, 30], [0, 12, 24, 32], [0, 1, 3, 4])]
    res = experiments.write_outputs(str(tmp_path / "out"), {"semantic": sem, "classic": cls}, grid_step_s=10)
    claims = res["claims"]
    assert [c["holds"] for c in claims] == [True, True, True, None, None, None]  # no accuracy columns
    assert claims[3]["measured"] == "not measured"
    assert claims[1]["measured"] == "semantic 20 s, classic 30 s (medians); no paired runs"
    assert "ratio 0.938" in claims[2]["measured"]  # 30 / 32
    report = open(str(tmp_path / "out" / "report.md")).read()
    assert "## The paper's claims, measured here" in report


def test_paper_claims_that_fail_say_where(tmp_path):
    # Semantic is behind at 10 s (1 vs 2 found), never finds all, and explores 20% less.
    sem = [make_run(str(tmp_path / "s0"), [0, 10, 20], [0, 8, 16], [0, 1, 3])]
    cls = [make_run(str(tmp_path / "c0"), [0, 10, 20], [0, 10, 20], [0, 2, 4])]
    res = experiments.write_outputs(str(tmp_path / "out"), {"semantic": sem, "classic": cls}, grid_step_s=10)
    c = res["claims"]
    assert [x["holds"] for x in c] == [False, False, False, None, None, None]
    assert c[0]["measured"] == "behind at 2 of 3 times (first at 10 s, by up to 25 points)"
    assert c[1]["measured"] == "semantic never, classic 20 s (medians); no paired runs"
    assert "ratio 0.800" in c[2]["measured"]
    assert experiments.write_outputs(str(tmp_path / "one"), {"semantic": sem}, grid_step_s=10)["claims"] == []


def test_implausible_runs_are_named(tmp_path):
    ok = make_run(str(tmp_path / "ok"), [0, 10, 200], [0, 1, 2], [0, 1, 2])
    assert experiments.implausible(ok, sim_limit_s=200) == ""
    # A mission that took wall time (seconds since 1970) for sim time.
    bad = make_run(str(tmp_path / "bad"), [1795335807.5], [0], [0])
    assert experiments.implausible(bad, sim_limit_s=200) == "sim time 1795335808 s is beyond the 200 s limit"


COLUMNS = ["sim_s", "explored_volume_m3", "ground_truth_found", "background_rmse_m", "object_rmse_m",
           "background_completeness", "object_completeness", "background_observed_share", "object_observed_share",
           "path_length_m"]


def write_series(d, rows, n_gt=4, reason="explored", end_s=None, end_conditions=None):
    """A run directory from hand-written rows (one dict per row; absent columns empty); end_s:
    the summary's sim time at the end (absent: the last row's); end_conditions as run_mission.py
    writes them (absent: a run from before they were written)."""
    os.makedirs(d)
    with open(os.path.join(d, "timeseries.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    with open(os.path.join(d, "summary.json"), "w") as f:
        json.dump(dict({"ground_truth_objects": n_gt, "termination_reason": reason, "collisions": 0},
                       **({} if end_s is None else {"sim_time_s": end_s}),
                       **({} if end_conditions is None else {"end_conditions": end_conditions})), f)
    return experiments.read_run(d)


def test_aggregated_curves_of_every_panel(tmp_path):
    # Three runs sampled at 0, 10 and 20 s; accuracy and completeness only at snapshots
    # (empty fields hold the value before, none before the first: no RMSE yet, 0% complete).
    runs = []
    for i, k in enumerate([1, 2, 4]):
        runs.append(write_series(str(tmp_path / str(i)), [
            {"sim_s": 0, "explored_volume_m3": 0, "ground_truth_found": 0, "path_length_m": 0},
            {"sim_s": 10, "explored_volume_m3": 10 * k, "ground_truth_found": k, "background_rmse_m": 0.01 * k,
             "object_rmse_m": 0.002 * k, "background_completeness": 0.1 * k, "object_completeness": 0.2 * k,
             "background_observed_share": 0.05 * k, "object_observed_share": 0.1 * k, "path_length_m": 2 * k},
            {"sim_s": 20, "explored_volume_m3": 20 * k, "ground_truth_found": 4, "path_length_m": 3 * k}]))
    agg = experiments.aggregate(runs, np.array([0.0, 10.0, 20.0]))
    # At 10 s the runs hold k = 1, 2, 4 times a figure f: median 2 f; numpy's linear percentiles
    # p10 = 1 + 0.2 (2 - 1) = 1.2 f and p90 = 2 + 0.8 (4 - 2) = 3.6 f.
    per_k = {"explored_volume_m3": 10.0, "found_percent": 25.0, "background_rmse_cm": 1.0, "object_rmse_cm": 0.2,
             "background_completeness_percent": 10.0, "object_completeness_percent": 20.0,
             "background_observed_percent": 5.0, "object_observed_percent": 10.0, "path_length_m": 2.0}
    assert set(per_k) == set(experiments.CURVES)
    for key, f in per_k.items():
        c = agg[key]
        assert [c["median"][1], c["p10"][1], c["p90"][1]] == pytest.approx([2 * f, 1.2 * f, 3.6 * f]), key
    # At 0 s: nothing yet (no RMSE, zeros elsewhere); at 20 s the snapshot figures hold their 10 s values.
    assert np.isnan(agg["background_rmse_cm"]["median"][0]) and np.isnan(agg["object_rmse_cm"]["p90"][0])
    assert agg["object_completeness_percent"]["median"][0] == 0.0
    assert agg["background_completeness_percent"]["median"][2] == pytest.approx(20.0)
    assert agg["found_percent"]["p10"][2] == 100.0 and agg["explored_volume_m3"]["p90"][2] == pytest.approx(72.0)
    assert agg["path_length_m"]["median"][2] == pytest.approx(6.0)


def test_eight_panels_and_the_reconstruction_claims(tmp_path):
    def run(name, rmse_bg, rmse_obj, observed, reason, end_s=None, open_=None):
        return write_series(str(tmp_path / name), [
            {"sim_s": 0, "explored_volume_m3": 0, "ground_truth_found": 0, "path_length_m": 0},
            {"sim_s": 10, "explored_volume_m3": 10, "ground_truth_found": 4, "background_rmse_m": rmse_bg,
             "object_rmse_m": rmse_obj, "background_completeness": 0.5, "object_completeness": 0.6,
             "background_observed_share": 0.3, "object_observed_share": observed, "path_length_m": 1}],
            reason=reason, end_s=end_s, end_conditions=open_)
    sem = [run("s0", 0.030, 0.010, 0.8, "explored", 250.0, {"not_done": [], "active_frontiers": 0}),
           run("s1", 0.032, 0.012, 0.9, "time_limit", 600.0,
               {"not_done": ["frontiers", "objects"], "active_frontiers": 162})]
    cls = [run("c0", 0.028, 0.011, 0.5, "explored", 300.0), run("c1", 0.030, 0.011, 0.6, "explored")]
    res = experiments.write_outputs(str(tmp_path / "out"), {"semantic": sem, "classic": cls}, grid_step_s=10)
    for key in experiments.CURVES:
        assert os.path.getsize(str(tmp_path / "out" / ("%s.png" % key))) > 0
    assert os.path.getsize(str(tmp_path / "out" / "figures_5_8.png")) > 0
    c = res["claims"]
    # Background: 3.1 vs 2.9 cm; objects: 1.1 vs 1.1 cm; observed from <= d_obj: 85% vs 55%.
    assert c[3]["holds"] is True and c[3]["measured"] == "semantic 3.10 cm, classic 2.90 cm"
    assert c[4]["holds"] is True and c[4]["measured"] == "semantic 1.10 cm, classic 1.10 cm"
    assert c[5]["holds"] is True and c[5]["measured"] == "semantic 85%, classic 55% (medians); no paired runs"
    rows = {r["mode"]: r for r in res["rows"]}
    assert rows["semantic"]["explored_share"] == 0.5 and rows["classic"]["explored_share"] == 1.0
    # Ends: semantic 250 s (explored) and 600 s (limit); classic 300 s and, without sim_time_s, its last row's 10 s.
    assert rows["semantic"]["end_sim_s_median"] == 425.0 and rows["semantic"]["explored_end_sim_s_median"] == 250.0
    assert rows["classic"]["end_sim_s_median"] == 155.0 and rows["classic"]["explored_end_sim_s_median"] == 155.0
    report = open(str(tmp_path / "out" / "report.md")).read()
    assert "| explored, time_limit | 50% | 425 s | 250 s |" in report
    # One row per run: 4 of 4 objects found (all at 10 s), 10 m3, 30% of the background and 80% of the
    # objects seen close.
    assert "| ../s0 | semantic | explored | 250.0 s | nothing (0) | 100% | 10 s | 10 m3 | 30% | 80% | 0 |" in report
    assert "| ../s1 | semantic | time_limit | 600.0 s | frontiers, objects (162) | 100% | 10 s |" in report
    assert "| ../c1 | classic | explored | 10.0 s | - | 100% | 10 s | 10 m3 | 30% | 60% | 0 |" in report
    res = experiments.write_outputs(str(tmp_path / "limit"), {"semantic": sem[1:]}, grid_step_s=10)
    assert res["rows"][0]["explored_end_sim_s_median"] is None
    assert "| time_limit | 0% | 600 s | none ended explored |" in open(str(tmp_path / "limit" / "report.md")).read()


def test_background_observed_panel_reads_what_the_mission_writes(tmp_path):
    # run_mission writes RunLog.row(); the background map's own share seen from <= d_bg
    # (MapStats.surface_observed_share, -1 until measured) must reach the Fig. 8 panel.
    from types import SimpleNamespace as NS
    from semantic_exploration.eval.runlog import RunLog

    def stats(share):
        return NS(explored_volume_m3=1.0, frontier_count=0, surface_observed_share=share,
                  integration_time_ms=0.0)

    runs = []
    for i, shares in enumerate([(-1.0, 0.2, 0.5), (-1.0, 0.4, 0.6), (0.1, 0.8, 0.9)]):
        d = tmp_path / str(i)
        d.mkdir()
        log = RunLog()
        rows = []
        for t, share in zip((0.0, 10.0, 20.0), shares):
            log.stats = stats(share)
            rows.append(log.row(t, t, []))
        assert rows[0]["background_observed_share"] == ("" if shares[0] < 0 else shares[0])
        with open(str(d / "timeseries.csv"), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
        with open(str(d / "summary.json"), "w") as f:
            json.dump({"ground_truth_objects": 1, "termination_reason": "explored", "collisions": 0}, f)
        runs.append(experiments.read_run(str(d)))
    c = experiments.aggregate(runs, np.array([0.0, 10.0, 20.0]))["background_observed_percent"]
    # 0 s: (0, 0, 10) -> median 0, p10 0, p90 8; 10 s: (20, 40, 80) -> 40, 24, 72; 20 s: (50, 60, 90) -> 60, 52, 84.
    assert c["median"] == pytest.approx([0.0, 40.0, 60.0])
    assert c["p10"] == pytest.approx([0.0, 24.0, 52.0])
    assert c["p90"] == pytest.approx([8.0, 72.0, 84.0])

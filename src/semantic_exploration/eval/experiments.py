"""Aggregation of many runs into the paper's Figures 5-8 style curves.

Each run directory holds `timeseries.csv` (written by run_mission.py once a
second of sim time: explored volume, objects found -- matched as in the final
report, at the last object-map snapshot --, ...) and `summary.json`.
Curves are resampled on a common sim-time grid; a run that ended earlier
keeps its last value (it has stopped exploring). Across runs of one mode we
report the median and the 10th/90th percentiles.
"""
import csv
import json
import os
from typing import Dict, List, Optional, Sequence

import numpy as np

from .claims import paper_claims  # noqa: F401 (part of this module's interface)
from .overrides import load as load_overrides

#: Curve -> (label, unit, figure of the paper, timeseries.csv column, scale, value before its first sample).
#: found_percent's scale is 100 / the number of ground-truth objects.
CURVES = {
    "explored_volume_m3": ("explored volume", "m^3", "Fig. 5", "explored_volume_m3", 1.0, 0.0),
    "found_percent": ("ground-truth objects found", "%", "Fig. 5", "ground_truth_found", None, 0.0),
    "background_rmse_cm": ("background accuracy (RMSE)", "cm", "Fig. 6", "background_rmse_m", 100.0, np.nan),
    "object_rmse_cm": ("object accuracy (RMSE)", "cm", "Fig. 6", "object_rmse_m", 100.0, np.nan),
    "background_completeness_percent": ("background completeness", "%", "Fig. 7", "background_completeness",
                                        100.0, 0.0),
    "object_completeness_percent": ("object completeness", "%", "Fig. 7", "object_completeness", 100.0, 0.0),
    "background_observed_percent": ("background map surface observed from <= d_bg", "%", "Fig. 8",
                                    "background_observed_share", 100.0, 0.0),
    "object_observed_percent": ("object map surface observed from <= d_obj", "%", "Fig. 8", "object_observed_share",
                                100.0, 0.0),
    "path_length_m": ("path length", "m", "", "path_length_m", 1.0, 0.0),
}


def _filled(values: Sequence[str], before: float = 0.0) -> np.ndarray:
    """Numbers from CSV fields; an empty field (no snapshot yet) holds the value before it, `before` at first."""
    out, last = [], before
    for v in values:
        last = float(v) if v not in ("", None) else last
        out.append(last)
    return np.array(out, float)


def read_run(run_dir: str) -> Dict:
    """A run's time series as the curves of CURVES (all nan where the run lacks the column)."""
    with open(os.path.join(run_dir, "timeseries.csv")) as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(run_dir, "summary.json")) as f:
        summary = json.load(f)
    t = np.array([float(r["sim_s"]) for r in rows])
    n_gt = max(1, int(summary.get("ground_truth_objects", 0)))
    series = {}
    for key, (_, _, _, column, scale, before) in CURVES.items():
        if rows and column not in rows[0]:
            series[key] = np.full(len(rows), np.nan)
            continue
        series[key] = _filled([r.get(column, "") for r in rows], before) * (100.0 / n_gt if scale is None else scale)
    order = np.argsort(t, kind="stable")
    return {"dir": run_dir, "t": t[order], "series": {k: v[order] for k, v in series.items()}, "summary": summary}


def end_s(run: Dict) -> float:
    """A run's sim time at the end: its summary's, else its last row's (nan without rows)."""
    return float(run["summary"].get("sim_time_s", run["t"][-1] if len(run["t"]) else np.nan))


def _final(run: Dict, key: str, unit: str) -> str:
    """A curve's last value with its unit, for the run table ('-' where the run lacks it)."""
    v = run["series"][key]
    return "-" if len(v) == 0 or not np.isfinite(v[-1]) else "%.0f%s" % (v[-1], unit)


def run_table(by_mode: Dict[str, List[Dict]], out_dir: str) -> List[str]:
    """report.md's table of the runs one by one: how and when each ended, and its final figures."""
    lines = ["## Runs", "",
             "| run | mode | ended | sim time at the end | still open at the end (active frontier voxels) | "
             "objects found | all found at | explored volume | background seen from <= d_bg | "
             "objects' surface seen from <= d_obj | collisions |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for mode, runs in by_mode.items():
        for r in runs:
            s = r["summary"]
            end = end_s(r)
            cond = s.get("end_conditions") or {}
            still = "-" if not cond else "%s (%d)" % (", ".join(cond.get("not_done", [])) or "nothing",
                                                      cond.get("active_frontiers", 0))
            lines.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                os.path.relpath(r["dir"], out_dir), mode, s.get("termination_reason", "?"),
                "-" if not np.isfinite(end) else "%.1f s" % end, still, _final(r, "found_percent", "%"),
                describe_time(all_found_at(r), "-"),
                _final(r, "explored_volume_m3", " m3"), _final(r, "background_observed_percent", "%"),
                _final(r, "object_observed_percent", "%"), s.get("collisions", "-")))
    return lines


def implausible(run: Dict, sim_limit_s: float, slack_s: float = 60.0) -> str:
    """Why a run cannot be aggregated ('' if it can): no samples, or sim time
    far beyond the limit the mission was given (a mission that read wall
    time as sim time), which would also blow up the common time grid."""
    if len(run["t"]) == 0:
        return "no time series"
    if run["t"][-1] > sim_limit_s + slack_s:
        return "sim time %.0f s is beyond the %.0f s limit" % (run["t"][-1], sim_limit_s)
    return ""


def resample(t: np.ndarray, y: np.ndarray, grid: np.ndarray, before: float = 0.0) -> np.ndarray:
    """Step-wise value of y at each grid time (last sample at or before it; `before` before the first)."""
    if len(t) == 0:
        return np.full(len(grid), before, float)
    idx = np.searchsorted(t, grid, side="right") - 1
    out = np.where(idx >= 0, y[np.clip(idx, 0, len(y) - 1)], before)
    return out.astype(float)


def aggregate(runs: Sequence[Dict], grid: np.ndarray) -> Dict[str, Dict[str, np.ndarray]]:
    """Per curve: median, p10, p90 over the runs that have a value at each grid time (nan where none has)."""
    import warnings
    out = {}
    for key, spec in CURVES.items():
        stack = np.stack([resample(r["t"], r["series"][key], grid, spec[5]) for r in runs])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-nan columns: no run has the figure yet
            out[key] = {"median": np.nanmedian(stack, 0), "p10": np.nanpercentile(stack, 10, 0),
                        "p90": np.nanpercentile(stack, 90, 0)}
    return out


def time_to_reach(t: np.ndarray, y: np.ndarray, level: float) -> float:
    """First sim time at which y >= level (inf if never; nan if y has no value at all: not measured)."""
    if not np.isfinite(y).any():
        return float("nan")
    hit = np.nonzero(y >= level - 1e-9)[0]
    return float(t[hit[0]]) if len(hit) else float("inf")


def all_found_at(run: Dict) -> float:
    """A run's sim time when every ground-truth object was found (time_to_reach's inf and nan)."""
    return time_to_reach(run["t"], run["series"]["found_percent"], 100.0)


def describe_time(t_s: float, missing: str = "not measured") -> str:
    """A time for a report: "12 s", "never" (inf) or `missing` (nan)."""
    return "%.0f s" % t_s if np.isfinite(t_s) else (missing if np.isnan(t_s) else "never")


#: Minimum mask size (px) -> from how far a whole chair is detected (config/sim.yaml's comment).
DETECTOR_RANGES = {1200: "a whole chair detected from about 4 m", 50: "a whole chair detected from 10 m"}


def describe_detector(detector: Optional[Dict]) -> str:
    """One line naming a run's detector (summary.json "detector"), e.g.
    "masks of at least 1200 px (config/sim.yaml; a whole chair detected from about 4 m)"."""
    if not detector or detector.get("min_mask_pixels") is None:
        return "unknown"
    px = int(detector["min_mask_pixels"])
    notes = [detector.get("source") or "?"] + ([DETECTOR_RANGES[px]] if px in DETECTOR_RANGES else [])
    return "masks of at least %d px (%s)" % (px, "; ".join(notes))


def describe_yaml(path: str) -> str:
    """A YAML file's settings as "section/key value" pairs for a report (its path, then the pairs)."""
    tree = load_overrides(path)  # keeps rosparam's angle tags, which safe_load refuses
    pairs = []

    def walk(node, prefix):
        for k, v in node.items():
            if isinstance(v, dict):
                walk(v, prefix + str(k) + "/")
            else:
                tag = getattr(v, "tag", "")  # !degrees 30 is not 30 rad
                pairs.append("%s%s %s%s" % (prefix, k, tag + " " if tag else "", v))
    walk(tree, "")
    return "%s (%s)" % (os.path.basename(path), ", ".join(pairs) if pairs else "empty")


def write_outputs(out_dir: str, by_mode: Dict[str, List[Dict]], grid_step_s: float = 5.0,
                  setup: Sequence[str] = ()) -> Dict:
    """CSV of the aggregated curves, one PNG per curve, and report.md (`setup`: lines on how the runs were made)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(out_dir, exist_ok=True)
    t_end = max(float(r["t"][-1]) for runs in by_mode.values() for r in runs if len(r["t"]))
    grid = np.arange(0.0, t_end + grid_step_s, grid_step_s)
    agg = {mode: aggregate(runs, grid) for mode, runs in by_mode.items()}

    with open(os.path.join(out_dir, "curves.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["mode", "curve", "sim_s", "median", "p10", "p90"])
        for mode, curves in agg.items():
            for key, c in curves.items():
                for i, t in enumerate(grid):
                    w.writerow([mode, key, "%.1f" % t, "%.4f" % c["median"][i], "%.4f" % c["p10"][i],
                                "%.4f" % c["p90"][i]])
    plots = []

    def draw(ax, key):
        label, unit, figure = CURVES[key][:3]
        for mode, curves in agg.items():
            c = curves[key]
            line, = ax.plot(grid, c["median"], label="%s (median)" % mode)
            ax.fill_between(grid, c["p10"], c["p90"], color=line.get_color(), alpha=0.2,
                            label="%s (10th-90th percentile)" % mode)
        if not any(np.isfinite(curves[key]["median"]).any() for curves in agg.values()):
            ax.text(0.5, 0.5, "not measured in these runs", ha="center", va="center", transform=ax.transAxes)
        ax.set_xlabel("sim time (s)")
        ax.set_ylabel("%s (%s)" % (label, unit))
        if figure:
            ax.set_title("%s: %s" % (figure, label), fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)

    for key in CURVES:
        fig, ax = plt.subplots(figsize=(6, 4))
        draw(ax, key)
        fig.tight_layout()
        path = os.path.join(out_dir, "%s.png" % key)
        fig.savefig(path, dpi=100)
        plt.close(fig)
        plots.append(path)
    panels = [k for k, spec in CURVES.items() if spec[2]]  # the paper's Figures 5-8: eight panels
    fig, axes = plt.subplots(2, 4, figsize=(20, 8))
    for ax, key in zip(axes.T.ravel(), panels):
        draw(ax, key)
    fig.tight_layout()
    path = os.path.join(out_dir, "figures_5_8.png")
    fig.savefig(path, dpi=80)
    plt.close(fig)
    plots.insert(0, path)

    rows = []
    for mode, runs in by_mode.items():
        final_found = [r["series"]["found_percent"][-1] for r in runs]
        final_vol = [r["series"]["explored_volume_m3"][-1] for r in runs]
        t100 = [all_found_at(r) for r in runs]
        reasons = sorted(set(r["summary"].get("termination_reason", "?") for r in runs))
        explored = sum(r["summary"].get("termination_reason") == "explored" for r in runs)
        # sim time at the end: of every run, and of those that ended explored (the paper's end)
        ends = [end_s(r) for r in runs]
        explored_ends = [e for e, r in zip(ends, runs) if r["summary"].get("termination_reason") == "explored"]
        evs = [r["summary"].get("evaluation") or {} for r in runs]
        scored = [e for e in evs if "spurious" in e]  # runs whose final maps were matched to the ground truth
        rows.append({"mode": mode, "runs": len(runs), "found_percent_median": float(np.median(final_found)),
                     # map objects on no ground-truth object, ground-truth objects under several map objects
                     "spurious": sum(len(e["spurious"]) for e in scored) if scored else None,
                     "duplicated": sum(len(e.get("duplicates", [])) for e in scored) if scored else None,
                     "explored_share": explored / len(runs),
                     "end_sim_s_median": float(np.median(ends)),
                     "explored_end_sim_s_median": float(np.median(explored_ends)) if explored_ends else None,
                     "explored_m3_median": float(np.median(final_vol)),
                     "time_to_all_found_s_median": float(np.median(t100)),
                     "collisions": int(sum(r["summary"].get("collisions", 0) for r in runs)),
                     "termination": ", ".join(reasons)})
    detectors = sorted({describe_detector(r["summary"].get("detector")) for runs in by_mode.values() for r in runs})
    setup = list(setup) + ["detector: " + "; ".join(detectors) + (" (differs between runs)" if len(detectors) > 1
                                                                   else "")]
    lines = ["# Experiment report", ""] + ["- %s" % l for l in setup] + [""] + [
             "Median over runs; curves show the median and the 10th-90th percentile band.", "",
             "Spurious: final map objects on no ground-truth object; duplicated: ground-truth objects more than "
             "one final map object lies on (both summed over the runs).", "",
             "| mode | runs | objects found (final, median) | spurious | duplicated | "
             "explored volume (final, median) | time to find all (median) | collisions | termination | "
             "ended explored | sim time at the end (median) | sim time at the end of the runs that ended "
             "explored (median) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append("| %s | %d | %.0f%% | %s | %s | %.1f m3 | %s | %d | %s | %.0f%% | %.0f s | %s |" % (
            r["mode"], r["runs"], r["found_percent_median"], "-" if r["spurious"] is None else r["spurious"],
            "-" if r["duplicated"] is None else r["duplicated"], r["explored_m3_median"],
            describe_time(r["time_to_all_found_s_median"]),
            r["collisions"], r["termination"], 100 * r["explored_share"], r["end_sim_s_median"],
            "none ended explored" if r["explored_end_sim_s_median"] is None
            else "%.0f s" % r["explored_end_sim_s_median"]))
    claims = paper_claims(agg, grid, rows, runs_by_mode=by_mode)
    if claims:
        lines += ["", "## The paper's claims, measured here", "", "| claim | holds | measured |", "|---|---|---|"]
        lines += ["| %s | %s | %s |" % (c["claim"], {True: "yes", False: "no", None: "n/a"}[c["holds"]],
                                        c["measured"]) for c in claims]
    lines += ["", "Figures: " + ", ".join("[%s](%s)" % (os.path.basename(p), os.path.basename(p)) for p in plots),
              "", "Data: [curves.csv](curves.csv)", ""]
    for mode, runs in by_mode.items():
        lines.append("- %s runs: %s" % (mode, ", ".join(os.path.relpath(r["dir"], out_dir) for r in runs)))
    lines += [""] + run_table(by_mode, out_dir)
    with open(os.path.join(out_dir, "report.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    return {"rows": rows, "plots": plots, "claims": claims}

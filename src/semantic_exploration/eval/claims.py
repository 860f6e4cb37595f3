"""The paper's Section V-B claims, semantic vs classic, checked on a
campaign's median curves (eval.experiments.aggregate) and per-mode rows.
The two claims that one mode does better also count the paired runs (same
scene and planner seed, one per mode) in which it did, with a sign test:
campaign runs vary a lot (all chairs found after 21-191 s in one campaign),
and a median over a few runs can turn either way by chance."""
import math
import os
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

#: Largest difference of final median RMSE (cm) that still counts as "similar accuracy".
SIMILAR_RMSE_CM = 0.5


def _last(series: np.ndarray) -> float:
    """A curve's last finite value (nan if none)."""
    v = series[np.isfinite(series)]
    return float(v[-1]) if len(v) else float("nan")


def _final(curve: Dict[str, np.ndarray]) -> float:
    """The median curve's last finite value (nan if none)."""
    return _last(curve["median"])


def sign_test_p(better: int, worse: int) -> float:
    """Exact two-sided sign test: the chance of a split at least this uneven
    among better + worse pairs if either mode were as likely to do better
    (ties left out); 1.0 without untied pairs."""
    n = better + worse
    if n == 0:
        return 1.0
    tail = sum(math.comb(n, i) for i in range(min(better, worse) + 1))
    return min(1.0, 2 * tail / 2 ** n)  # integers: exact, and no float overflow for large n


def pair_key(run_dir: str, mode: str) -> Optional[str]:
    """The run's name without its mode (run_experiments.py names runs <scene>_run<k>_<mode>); None if it has none."""
    name = os.path.basename(os.path.normpath(run_dir))
    return name[:-len(mode) - 1] if name.endswith("_" + mode) else None


def paired(runs_by_mode: Dict[str, Sequence[Dict]], value: Callable[[Dict], float], higher_is_better: bool) -> Dict:
    """Semantic against classic run by run over the pairs both modes flew and
    have the figure for (value nan: not measured; inf, e.g. never found all,
    compares as a value): {"pairs", "better", "worse", "tied", "p"} (p: sign_test_p)."""
    def by_key(mode):
        return {k: r for k, r in ((pair_key(r["dir"], mode), r) for r in runs_by_mode.get(mode, [])) if k}
    sem, cls = by_key("semantic"), by_key("classic")
    better = worse = tied = 0
    for k in sorted(set(sem) & set(cls)):
        a, b = value(sem[k]), value(cls[k])
        if np.isnan(a) or np.isnan(b):
            continue
        if a == b:
            tied += 1
        elif (a > b) == higher_is_better:
            better += 1
        else:
            worse += 1
    return {"pairs": better + worse + tied, "better": better, "worse": worse, "tied": tied,
            "p": sign_test_p(better, worse)}


def describe_pairs(pr: Dict, better: str, worse: str) -> str:
    """'in 9 paired runs semantic sooner in 2, later in 7, tied in 0 (two-sided sign test p = 0.180: ...)'."""
    if pr["pairs"] == 0:
        return "no paired runs"
    verdict = ("unlikely to be chance" if pr["p"] < 0.05
               else "could be chance: the pairs do not tell the modes apart at 5%")
    return "in %d paired run%s semantic %s in %d, %s in %d, tied in %d (two-sided sign test p = %.3f: %s)" % (
        pr["pairs"], "s" if pr["pairs"] != 1 else "", better, pr["better"], worse, pr["worse"], pr["tied"], pr["p"], verdict)


def paper_claims(agg: Dict[str, Dict[str, Dict[str, np.ndarray]]], grid: np.ndarray, rows: Sequence[Dict],
                 volume_tolerance: float = 0.10, runs_by_mode: Optional[Dict[str, Sequence[Dict]]] = None
                 ) -> List[Dict]:
    """Each entry: claim text, holds (bool, or None where the runs lack the figure) and the measured figure.

    1. Semantic finds at least as many objects as classic at every time.
    2. Semantic reaches 100% of the objects sooner (median time to all found).
    3. Semantic's final explored volume is within volume_tolerance of classic's.
    4-5. Semantic's final background and object accuracy (RMSE) are within
       SIMILAR_RMSE_CM of classic's ("similar accuracy").
    6. Semantic observes more of the objects' surface from <= d_obj (final median).

    With runs_by_mode (each run as eval.experiments.read_run gives it), claims 2
    and 6 also carry "paired" (see paired()) and say it in "measured"; "holds"
    stays the medians' verdict."""
    from .experiments import all_found_at, describe_time  # here: experiments imports this module
    if "semantic" not in agg or "classic" not in agg:
        return []
    sem, cls = agg["semantic"], agg["classic"]
    deficit = cls["found_percent"]["median"] - sem["found_percent"]["median"]
    behind = np.nonzero(deficit > 1e-9)[0]
    t_sem = next(r["time_to_all_found_s_median"] for r in rows if r["mode"] == "semantic")
    t_cls = next(r["time_to_all_found_s_median"] for r in rows if r["mode"] == "classic")
    v_sem, v_cls = sem["explored_volume_m3"]["median"][-1], cls["explored_volume_m3"]["median"][-1]
    ratio = v_sem / v_cls if v_cls > 0 else float("nan")

    runs_by_mode = runs_by_mode or {}
    t_pairs = paired(runs_by_mode, all_found_at, False)
    out = [
        {"claim": "semantic finds at least as many objects as classic at every time (median)",
         "holds": len(behind) == 0,
         "measured": "always" if len(behind) == 0 else "behind at %d of %d times (first at %.0f s, by up to %.0f points)"
         % (len(behind), len(grid), grid[behind[0]], deficit.max())},
        {"claim": "semantic finds 100% of the objects sooner (median time)",
         "holds": None if np.isnan(t_sem) or np.isnan(t_cls) else bool(np.isfinite(t_sem) and t_sem < t_cls),
         "measured": "semantic %s, classic %s (medians); %s" % (
             describe_time(t_sem), describe_time(t_cls), describe_pairs(t_pairs, "sooner", "later")), "paired": t_pairs},
        {"claim": "semantic's explored volume is within %.0f%% of classic's (final median)" % (100 * volume_tolerance),
         "holds": bool(np.isfinite(ratio) and abs(ratio - 1.0) <= volume_tolerance),
         "measured": "%.1f vs %.1f m3 (ratio %.3f)" % (v_sem, v_cls, ratio)},
    ]
    for key, what in (("background_rmse_cm", "background"), ("object_rmse_cm", "object")):
        a, b = _final(sem[key]), _final(cls[key])
        known = np.isfinite(a) and np.isfinite(b)
        out.append({"claim": "semantic's %s accuracy is similar to classic's (final median RMSE within %.1f cm)"
                    % (what, SIMILAR_RMSE_CM),
                    "holds": bool(abs(a - b) <= SIMILAR_RMSE_CM) if known else None,
                    "measured": "semantic %.2f cm, classic %.2f cm" % (a, b) if known else "not measured"})
    a, b = _final(sem["object_observed_percent"]), _final(cls["object_observed_percent"])
    known = np.isfinite(a) and np.isfinite(b)
    o_pairs = paired(runs_by_mode, lambda r: _last(r["series"]["object_observed_percent"]), True)
    out.append({"claim": "semantic observes more of the objects from <= d_obj than classic (final median)",
                "holds": bool(a > b) if known else None,
                "measured": "semantic %.0f%%, classic %.0f%% (medians); %s" % (
                    a, b, describe_pairs(o_pairs, "more", "less")) if known else "not measured",
                "paired": o_pairs})
    return out

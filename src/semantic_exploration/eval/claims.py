"""The paper's Section V-B claims, semantic vs classic, checked on a
campaign's median curves (eval.experiments.aggregate) and per-mode rows."""
from typing import Dict, List, Sequence

import numpy as np

#: Largest difference of final median RMSE (cm) that still counts as "similar accuracy".
SIMILAR_RMSE_CM = 0.5


def _final(curve: Dict[str, np.ndarray]) -> float:
    """The median curve's last finite value (nan if none)."""
    m = curve["median"][np.isfinite(curve["median"])]
    return float(m[-1]) if len(m) else float("nan")


def paper_claims(agg: Dict[str, Dict[str, Dict[str, np.ndarray]]], grid: np.ndarray, rows: Sequence[Dict],
                 volume_tolerance: float = 0.10) -> List[Dict]:
    """Each entry: claim text, holds (bool, or None where the runs lack the figure) and the measured figure.

    1. Semantic finds at least as many objects as classic at every time.
    2. Semantic reaches 100% of the objects sooner (median time to all found).
    3. Semantic's final explored volume is within volume_tolerance of classic's.
    4-5. Semantic's final background and object accuracy (RMSE) are within
       SIMILAR_RMSE_CM of classic's ("similar accuracy").
    6. Semantic observes more of the objects' surface from <= d_obj (final median).
    """
    if "semantic" not in agg or "classic" not in agg:
        return []
    sem, cls = agg["semantic"], agg["classic"]
    deficit = cls["found_percent"]["median"] - sem["found_percent"]["median"]
    behind = np.nonzero(deficit > 1e-9)[0]
    t_sem = next(r["time_to_all_found_s_median"] for r in rows if r["mode"] == "semantic")
    t_cls = next(r["time_to_all_found_s_median"] for r in rows if r["mode"] == "classic")
    v_sem, v_cls = sem["explored_volume_m3"]["median"][-1], cls["explored_volume_m3"]["median"][-1]
    ratio = v_sem / v_cls if v_cls > 0 else float("nan")

    def secs(x):
        return "%.0f s" % x if np.isfinite(x) else "never"

    out = [
        {"claim": "semantic finds at least as many objects as classic at every time (median)",
         "holds": len(behind) == 0,
         "measured": "always" if len(behind) == 0 else "behind at %d of %d times (first at %.0f s, by up to %.0f points)"
         % (len(behind), len(grid), grid[behind[0]], deficit.max())},
        {"claim": "semantic finds 100% of the objects sooner (median time)",
         "holds": bool(np.isfinite(t_sem) and t_sem < t_cls),
         "measured": "semantic %s, classic %s" % (secs(t_sem), secs(t_cls))},
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
    out.append({"claim": "semantic observes more of the objects from <= d_obj than classic (final median)",
                "holds": bool(a > b) if known else None,
                "measured": "semantic %.0f%%, classic %.0f%%" % (a, b) if known else "not measured"})
    return out

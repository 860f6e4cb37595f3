"""Snapshots of the object map during a run, scored with the final report's
matching (GroundTruthIndex.found: a map object's mesh lies on a ground-truth
object), so that the time series' "objects found" is the report's measure.

run_mission.py takes a snapshot every period_s of sim time through
object_map/save and hands the matched ids to its RunLog; the cost (wall time
spent saving and matching) goes into the run's summary.
"""
import os
import time
from typing import Callable, Dict, Optional

from . import metrics
from .truth import GroundTruthIndex


class ObjectSnapshots:
    """save(directory) -> {"success": bool, "message": str, ...} writes the object map
    (objects.json and meshes) into directory, as object_map/save does."""

    def __init__(self, index: GroundTruthIndex, save: Callable[[str], Dict], directory: str, period_s: float):
        if period_s <= 0:
            raise ValueError("snapshot period must be > 0 s (got %g)" % period_s)
        self.index, self.save, self.directory, self.period_s = index, save, directory, period_s
        self.count = 0
        self.failed = 0
        self.wall_s = 0.0            # spent saving and matching, s
        self.last_error = ""
        self._next_s: Optional[float] = None

    def due(self, sim_s: float) -> bool:
        return self._next_s is None or sim_s >= self._next_s

    def take(self, sim_s: float, log) -> Optional[list]:
        """Saves and matches the object map now (sim_s), hands the found ids to
        log.set_found and returns them (None if the save failed)."""
        t0 = time.monotonic()
        self._next_s = (sim_s // self.period_s + 1) * self.period_s  # on the period's grid
        res = self.save(self.directory)
        ids = None
        if res.get("success") and os.path.exists(os.path.join(self.directory, "objects.json")):
            ids = self.index.found(metrics.load_reconstruction(self.directory))
            log.set_found(ids, sim_s)
            self.count += 1
        else:
            self.failed += 1
            self.last_error = res.get("message", "")
        self.wall_s += time.monotonic() - t0
        return ids

    def summary(self, run_wall_s: float) -> Dict:
        return {"period_s": self.period_s, "count": self.count, "failed": self.failed,
                "wall_s": round(self.wall_s, 2),
                "share_of_wall": round(self.wall_s / run_wall_s, 4) if run_wall_s > 0 else None,
                "last_error": self.last_error}

"""Map snapshots during a run, for the time series of the paper's figures.

- ObjectSnapshots: the object map every period_s of sim time (object_map/save),
  matched at once with the final report's matching (GroundTruthIndex.found: a
  map object's mesh lies on a ground-truth object), so that the time series'
  "objects found" is the report's measure; the matched meshes' vertices are
  kept for scoring after the run.
- OccupiedSnapshots: the background map's occupied voxel centres every
  period_s (one ~occupied cloud), kept for scoring after the run.
- score_series: after the run, once the ground truth's observability is
  known, the accuracy and completeness of each snapshot, added to
  timeseries.csv (each row holds the last snapshot at or before it).

Run_mission.py records the cost (wall time spent taking and scoring snapshots).
"""
import csv
import glob
import os
import time
from typing import Callable, Dict, List, Optional

import numpy as np

from . import metrics
from .truth import GroundTruthIndex

#: timeseries.csv columns score_series adds
SERIES_COLUMNS = ["object_rmse_m", "object_completeness", "background_rmse_m", "background_completeness"]


class _Periodic:
    def __init__(self, period_s: float):
        if period_s <= 0:
            raise ValueError("snapshot period must be > 0 s (got %g)" % period_s)
        self.period_s = period_s
        self.count = self.failed = 0
        self.wall_s = 0.0  # spent taking snapshots, s
        self.last_error = ""
        self._next_s: Optional[float] = None

    def due(self, sim_s: float) -> bool:
        return self._next_s is None or sim_s >= self._next_s

    def _schedule(self, sim_s: float) -> None:
        self._next_s = (sim_s // self.period_s + 1) * self.period_s  # on the period's grid

    def summary(self, run_wall_s: float) -> Dict:
        return {"period_s": self.period_s, "count": self.count, "failed": self.failed,
                "wall_s": round(self.wall_s, 2),
                "share_of_wall": round(self.wall_s / run_wall_s, 4) if run_wall_s > 0 else None,
                "last_error": self.last_error}


class ObjectSnapshots(_Periodic):
    """save(directory) -> {"success": bool, "message": str, ...} writes the object map
    (objects.json and meshes) into directory, as object_map/save does; keep_dir
    (optional) receives the matched vertices of each snapshot."""

    def __init__(self, index: GroundTruthIndex, save: Callable[[str], Dict], directory: str, period_s: float,
                 keep_dir: str = ""):
        super().__init__(period_s)
        self.index, self.save, self.directory, self.keep_dir = index, save, directory, keep_dir

    def take(self, sim_s: float, log) -> Optional[list]:
        """Saves and matches the object map now (sim_s), hands the found ids to
        log.set_found and returns them (None if the save failed)."""
        t0 = time.monotonic()
        self._schedule(sim_s)
        res = self.save(self.directory)
        ids = None
        if res.get("success") and os.path.exists(os.path.join(self.directory, "objects.json")):
            matched = self.index.matched(metrics.load_reconstruction(self.directory))
            ids = sorted({gid for gid, _ in matched})
            log.set_found(ids, sim_s)
            if self.keep_dir:
                os.makedirs(self.keep_dir, exist_ok=True)
                np.savez(os.path.join(self.keep_dir, "objects_%09.2f.npz" % sim_s), sim_s=sim_s,
                         gt_ids=np.array([g for g, _ in matched], np.int64),
                         **{"v%d" % i: v.astype(np.float32) for i, (_, v) in enumerate(matched)})
            self.count += 1
        else:
            self.failed += 1
            self.last_error = res.get("message", "")
        self.wall_s += time.monotonic() - t0
        return ids


class OccupiedSnapshots(_Periodic):
    """grab() -> (N, 3) occupied voxel centres of the background map (or None
    if none came), kept in directory."""

    def __init__(self, grab: Callable[[], Optional[np.ndarray]], directory: str, period_s: float):
        super().__init__(period_s)
        self.grab, self.directory = grab, directory

    def take(self, sim_s: float) -> bool:
        t0 = time.monotonic()
        self._schedule(sim_s)
        pts = self.grab()
        if pts is not None:
            os.makedirs(self.directory, exist_ok=True)
            np.save(os.path.join(self.directory, "occupied_%09.2f.npy" % sim_s), np.asarray(pts, np.float32))
            self.count += 1
        else:
            self.failed += 1
            self.last_error = "no ~occupied cloud"
        self.wall_s += time.monotonic() - t0
        return pts is not None


def _time_of(path: str) -> float:
    return float(os.path.basename(path).split("_", 1)[1].rsplit(".", 1)[0])


def score_series(index: GroundTruthIndex, directory: str, completeness_stride: int = 8) -> Dict[float, Dict]:
    """Sim time -> the SERIES_COLUMNS figures of the snapshots in directory.
    Background completeness is estimated on every completeness_stride-th
    observable sample (the samples lie in spatial order, so the subset covers
    every surface evenly); the accuracy uses every occupied voxel."""
    out: Dict[float, Dict] = {}
    for path in sorted(glob.glob(os.path.join(directory, "objects_*.npz"))):
        with np.load(path) as z:
            matched = [(int(g), z["v%d" % i].astype(np.float64)) for i, g in enumerate(z["gt_ids"])]
        out.setdefault(_time_of(path), {}).update(index.object_summary(matched))
    bg = None
    for path in sorted(glob.glob(os.path.join(directory, "occupied_*.npy"))):
        pts = np.load(path).astype(np.float64)
        if bg is None:
            bg = index.background
            counted = bg.samples[bg.visible_or_wait(index)][::completeness_stride]
        if len(pts):
            rmse = float(np.sqrt(np.mean(metrics.nearest_distance(bg.tree, pts) ** 2)))
            comp = float(np.mean(metrics.within(metrics.kd_tree(pts), counted, index.threshold_m)))
        else:
            rmse, comp = float("nan"), 0.0
        out.setdefault(_time_of(path), {}).update(background_rmse_m=rmse, background_completeness=comp)
    return out


def add_series_columns(csv_path: str, scores: Dict[float, Dict], final: Optional[Dict] = None) -> None:
    """Adds SERIES_COLUMNS to timeseries.csv: each row gets the figures of the last
    snapshot at or before its sim_s that has them (empty before the first), the
    last row `final` (the report's figures) where given."""
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return
    fields = list(rows[0]) + [c for c in SERIES_COLUMNS if c not in rows[0]]
    times = sorted(scores)
    for r in rows:
        t = float(r["sim_s"])
        for c in SERIES_COLUMNS:
            have = [s for s in times if s <= t + 1e-6 and c in scores[s]]
            v = scores[have[-1]][c] if have else None
            r[c] = "" if v is None or not np.isfinite(v) else "%.5f" % v
    for c, v in (final or {}).items():
        if c in SERIES_COLUMNS:
            rows[-1][c] = "" if v is None or not np.isfinite(v) else "%.5f" % v
    with open(csv_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)


def series_files(directory: str) -> List[str]:
    return sorted(glob.glob(os.path.join(directory, "objects_*.npz")) +
                  glob.glob(os.path.join(directory, "occupied_*.npy")))


def cloud_xyz(msg) -> np.ndarray:
    """(N, 3) float32 x, y, z of a sensor_msgs/PointCloud2 with float32 x, y, z fields."""
    off = {f.name: f.offset for f in msg.fields}
    raw = np.frombuffer(bytes(msg.data), np.uint8).reshape(-1, msg.point_step)
    return np.stack([raw[:, off[c]:off[c] + 4].copy().view(np.float32)[:, 0] for c in "xyz"], 1)


def grab_occupied(topic: str = "/background_map/occupied", timeout_s: float = 5.0, since=None) -> Optional[np.ndarray]:
    """The background map's current ~occupied cloud (live, needs rospy.init_node): subscribing
    makes the node send one; a cloud stamped before `since` (rospy.Time; default half a
    second before the call: what the latched topic kept from an earlier subscription) is
    skipped. None if none came within timeout_s of wall time."""
    import threading
    import rospy
    from sensor_msgs.msg import PointCloud2
    if since is None:
        since = rospy.get_rostime() - rospy.Duration(0.5)  # a frame or so: the cloud has its last frame's stamp
    got, ready = [], threading.Event()

    def on_cloud(msg):
        if msg.header.stamp >= since and not got:
            got.append(msg)
            ready.set()
    sub = rospy.Subscriber(topic, PointCloud2, on_cloud, queue_size=2)
    try:
        ready.wait(timeout_s)
    finally:
        sub.unregister()
    return cloud_xyz(got[0]) if got else None


def finish_series(index: GroundTruthIndex, directory: str, csv_path: str, rec: Optional[Dict],
                  background: Optional[metrics.SurfaceScore], keep: bool = False) -> Dict:
    """After a run's final scoring: scores the snapshots in directory, adds
    the columns to csv_path (the last row from the saved maps: rec and the
    report's background score), deletes the snapshots unless keep; returns
    {"snapshots_scored", "scoring_wall_s"}."""
    import shutil
    t0 = time.monotonic()
    scores = score_series(index, directory)
    final = index.object_summary(index.matched(rec)) if rec is not None else {}
    if background is not None:
        final.update(background_rmse_m=background.rmse_m, background_completeness=background.completeness)
    add_series_columns(csv_path, scores, final)
    if not keep:
        shutil.rmtree(directory, ignore_errors=True)
    return {"snapshots_scored": len(scores), "scoring_wall_s": round(time.monotonic() - t0, 2)}

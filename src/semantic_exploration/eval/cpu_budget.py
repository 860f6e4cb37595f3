"""The onboard CPU budget of a run: what each mapping node spent per camera
frame (FrameIntegrated.cpu_ms: the handling thread's CPU time plus that of
background_map's integration pool and object_map's render for
instance_matching), and what that costs of one core at the camera rate.

A node's share of one core = its mean CPU ms per frame x the camera rate / 1000:
the mean, not the median, because a core's load is the sum of all frames.
It assumes the node handles every camera frame: for a node that reported
fewer frames than the camera sent it is an upper bound.
The target (issue 16): the mapping nodes together at most 25% of one core.
"""
import math
from typing import Dict, List, Optional

#: the nodes whose CPU the budget holds, in report order
MAPPING_NODES = ("background_map", "object_map", "instance_matching", "depth_history")
#: at most this share of one core for all mapping nodes together
TARGET_CORE_SHARE = 0.25


def nearest_rank(values: List[float], p: float) -> float:
    """The p-th percentile (0 < p <= 100) of values by the nearest-rank rule (the value at
    rank ceil(p/100 n) of the sorted values, as the nodes' own MapStats figures); 0 if empty."""
    if not values:
        return 0.0
    v = sorted(values)
    return v[max(1, math.ceil(min(p, 100.0) / 100.0 * len(v))) - 1]


class CpuBudget:
    """FrameIntegrated reports of the mapping nodes, collected over a run."""

    def __init__(self):
        self.cpu_ms: Dict[str, List[float]] = {n: [] for n in MAPPING_NODES}
        self._stamps: Dict[str, List[float]] = {n: [] for n in MAPPING_NODES}

    def add(self, node: str, stamp_s: float, cpu_ms: float) -> None:
        """One frame of `node` (its ROS name, any namespace); other nodes (the mission's own
        lockstep reports) are ignored."""
        n = node.rstrip("/").rsplit("/", 1)[-1]
        if n in self.cpu_ms:
            self.cpu_ms[n].append(float(cpu_ms))
            self._stamps[n].append(float(stamp_s))

    def measured_rate_hz(self) -> Optional[float]:
        """Frames per second of stamp time that background_map reported (None under two frames)."""
        s = sorted(set(self._stamps["background_map"]))
        return (len(s) - 1) / (s[-1] - s[0]) if len(s) > 1 and s[-1] > s[0] else None

    def summary(self, camera_rate_hz: Optional[float]) -> Dict:
        """Per node: frames, median_ms, p95_ms, mean_ms, core_share; the total share and whether
        the target holds (None without any frame). camera_rate_hz None: the measured rate."""
        rate, source = camera_rate_hz, "configured"
        if not rate:
            rate, source = self.measured_rate_hz(), "measured"
        nodes = {}
        for n, v in self.cpu_ms.items():
            mean = sum(v) / len(v) if v else 0.0
            nodes[n] = {"frames": len(v), "median_ms": nearest_rank(v, 50.0), "p95_ms": nearest_rank(v, 95.0),
                        "mean_ms": mean, "core_share": mean * rate / 1000.0 if rate else None}
        shares = [d["core_share"] for d in nodes.values() if d["frames"]]
        total = sum(shares) if shares and None not in shares else None
        holds = None if total is None else total <= TARGET_CORE_SHARE
        line = "CPU target (mapping nodes at most %s of one core): %s" % (_pct(TARGET_CORE_SHARE), (
            "not measured (no frame reports)" if holds is None else "%s (%s of one core at %.3g Hz)" % (
                "holds" if holds else "does NOT hold", _pct(total), rate)))
        return {"camera_rate_hz": rate, "camera_rate_source": source if rate else None, "nodes": nodes,
                "total_core_share": total, "target_core_share": TARGET_CORE_SHARE, "target_holds": holds,
                "target_line": line}


def _pct(x: Optional[float]) -> str:
    return "-" if x is None else "%.1f%%" % (100.0 * x)


def report_lines(s: Dict) -> List[str]:
    """Markdown lines of the report's "Onboard CPU budget" section for a summary() dict."""
    rate = s["camera_rate_hz"]
    lines = ["CPU time per camera frame of each mapping node (its frame_integrated reports: the handling "
             "thread plus background_map's integration pool and object_map's render for instance_matching); "
             "share of one core = mean ms per frame x %s (an upper bound for a node that reported fewer frames "
             "than the camera sent)." % (
                 "%.3g Hz (%s camera rate)" % (rate, s["camera_rate_source"]) if rate else "the camera rate (unknown)"),
             "", "| node | frames | median ms | p95 ms | mean ms | share of one core |", "|---|---|---|---|---|---|"]
    for n, d in s["nodes"].items():
        lines.append("| %s | %d | %.2f | %.2f | %.2f | %s |" % (
            n, d["frames"], d["median_ms"], d["p95_ms"], d["mean_ms"], _pct(d["core_share"]))
            if d["frames"] else "| %s | 0 | - | - | - | - |" % n)
    return lines + ["| total | | | | | %s |" % _pct(s["total_core_share"]), "", s["target_line"]]

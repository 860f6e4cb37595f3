"""What a run's nodes published, collected from live subscriptions (run_mission.py)
or from a recorded bag (bag.py), so that both write the same report and time series.

Messages are read by field name only; the module imports no ROS package unless
`subscribe` is called.
"""
import math
from typing import Dict, List, Optional

from .cpu_budget import CpuBudget

#: topic -> handler name; record.launch records these for evaluation.
TOPICS = {
    "/planner/status": "_on_status",
    "/background_map/stats": "_on_stats",
    "/object_map/objects": "_on_objects",
    "/mav/collisions": "_on_collisions",
    "/mav/pose": "_on_pose",
    "/dropped_input": "_on_drops",
    "/mav_sim/faults": "_on_faults",
    "/frame_integrated": "_on_frame",
}

#: (node, reason) -> how the report names one such drop; the headline line of the report.
DROP_HEADLINES = [
    ("background_map", "no_tf", "depth frames without tf"),
    ("background_map", "frame_gap", "camera frames missing from the depth stream"),
    ("instance_matching", "size_mismatch", "detection frames with mismatched size"),
    ("background_map", "size_mismatch", "depth frames with mismatched size"),
    ("background_map", "no_camera_info", "depth frames before camera_info"),
    ("background_map", "bad_depth", "depth frames that cannot be read"),
    ("background_map", "out_of_bounds", "depth frames outside the map bounds"),
    ("object_map", "no_tf", "detection frames without tf (object map)"),
]

#: fault-injection counters of mav_sim (faults.py) -> report wording
FAULT_NAMES = {
    "frames_without_tf": "camera frames sent without tf",
    "poses_withheld": "tf / mav/pose messages withheld",
    "frames_dropped": "camera frames not sent",
    "detections_rescaled": "detection images at another resolution",
}


def short_node(name: str) -> str:
    return name.rstrip("/").rsplit("/", 1)[-1]


class RunLog:
    """Latest status, map stats, objects, collisions, path length and drop counts of a run."""

    def __init__(self):
        self.status = None
        self.result = None  # the last status that closed an iteration (see _on_status)
        self.retired_objects = []  # objects the planner retired by evidence (ExplorationStatus.retired_object_ids)
        self.stats = None
        self.objects = None
        self.collisions = 0
        self.path_length_m = 0.0
        self.drops: Dict[str, Dict[str, int]] = {}   # node (short name) -> reason -> count
        self.faults: Dict[str, int] = {}             # injected by mav_sim
        self.last_pose = None                        # (x, y, z) of the last mav/pose
        self.cpu = CpuBudget()                       # the mapping nodes' CPU time per frame
        # Ground-truth ids matched by the object map's meshes (eval.metrics' matching, the final
        # report's) at the last snapshot, and its sim time; None before the first or without snapshots.
        self.found_ids: Optional[List[int]] = None
        self.found_at_s: Optional[float] = None
        self._last_pos = None
        self._frozen = False
        self._drops_stamp_s = 0.0  # sim time of the newest /dropped_input message

    def freeze(self):
        """Keeps every figure as it is now (the run stopped; a simulator that
        goes on while the maps are saved adds nothing to it). One exception:
        the simulator's fault counts still come in up to the sim time of the
        newest drop count. Each topic has its own connection, so at the stop
        a node's count of frame k can be here while the simulator's count of
        the fault it injected into frame k (sent before the frame) is not yet;
        the report would then show more drops than faults."""
        self._frozen = True

    def _late_faults(self, topic: str, msg) -> bool:
        return topic == "/mav_sim/faults" and msg.header.stamp.to_sec() <= self._drops_stamp_s

    # ------------------------------------------------------------- input
    def subscribe(self):
        """Live: subscribes every topic of TOPICS (needs rospy.init_node)."""
        import rospy
        from geometry_msgs.msg import PoseStamped
        from std_msgs.msg import UInt32
        from semantic_exploration.msg import DropCounts, ExplorationStatus, FrameIntegrated, MapStats, ObjectArray
        types = {"/planner/status": ExplorationStatus, "/background_map/stats": MapStats,
                 "/object_map/objects": ObjectArray, "/mav/collisions": UInt32, "/mav/pose": PoseStamped,
                 "/dropped_input": DropCounts, "/mav_sim/faults": DropCounts, "/frame_integrated": FrameIntegrated}
        for topic in TOPICS:  # four nodes report every frame: room for a second of them
            rospy.Subscriber(topic, types[topic], lambda msg, t=topic: self.handle(t, msg),
                             queue_size=200 if topic == "/frame_integrated" else 50)
        return self

    def handle(self, topic: str, msg) -> None:
        """Feeds one message of `topic` (live, or read from a bag); other
        topics, and everything after freeze() but the late fault counts
        freeze() names, are ignored."""
        h = TOPICS.get(topic)
        if h is not None and (not self._frozen or self._late_faults(topic, msg)):
            getattr(self, h)(msg)

    def _on_status(self, msg):
        self.status = msg
        # An iteration's status is the one with its conditions filled in and its time measured
        # (> 0). The planner's statuses between iterations (waiting, planning, a rejected path)
        # leave both at 0, and so does an iteration whose planning threw (its conditions unknown).
        if getattr(msg, "planning_time_s", 0.0) > 0.0:
            self.result = msg
        # Statuses between iterations ("planning") carry no object lists; keep the last iteration's.
        if msg.object_ids:
            self.retired_objects = sorted(getattr(msg, "retired_object_ids", None) or [])

    def _on_stats(self, msg):
        self.stats = msg

    def _on_objects(self, msg):
        self.objects = msg

    def _on_collisions(self, msg):
        self.collisions = msg.data

    def _on_pose(self, msg):
        p = msg.pose.position
        if self._last_pos is not None:
            self.path_length_m += math.dist(self._last_pos, (p.x, p.y, p.z))
        self._last_pos = self.last_pose = (p.x, p.y, p.z)

    def _on_drops(self, msg):
        self.drops[short_node(msg.node)] = dict(zip(msg.reasons, (int(c) for c in msg.counts)))
        self._drops_stamp_s = max(self._drops_stamp_s, msg.header.stamp.to_sec())

    def _on_faults(self, msg):
        self.faults = dict(zip(msg.reasons, (int(c) for c in msg.counts)))

    def _on_frame(self, msg):
        self.cpu.add(msg.node, msg.header.stamp.to_sec(), msg.cpu_ms)

    # ------------------------------------------------------------ output
    def object_observed_share(self):
        """Share of the map objects' surface voxels observed from <= d_obj (the object map's
        own figure, per object in ObjectInfo), over all map objects; "" before any voxel."""
        objs = self.objects.objects if self.objects else []
        n = sum(o.voxel_count for o in objs)
        return round(sum(o.observed_fraction * o.voxel_count for o in objs) / n, 4) if n else ""

    def background_observed_share(self):
        """Share of the background map's own observed surface (its occupied voxels) seen from
        <= d_bg (MapStats.surface_observed_share, measured every surface_share_period_s); "" before
        the map has measured it (-1) or without stats. Over the reconstruction, not the ground
        truth, as the paper's Fig. 8 seems to be (its object share drops for occluded artefacts)."""
        share = self.stats.surface_observed_share if self.stats is not None else -1.0
        return round(share, 4) if 0.0 <= share <= 1.0 else ""

    def set_found(self, gt_ids, sim_s: float) -> None:
        """The ground-truth ids a snapshot of the object map matches (GroundTruthIndex.found), taken at sim_s."""
        if not self._frozen:
            self.found_ids, self.found_at_s = sorted(gt_ids), sim_s

    def found_proxy(self, gt_objs, margin_m=0.1):
        """A proxy of the ground-truth objects found, from the published
        objects alone (no mesh): the ids whose box (grown by margin_m) holds a
        map object's centroid of the same class. It can differ from the
        mesh matching of eval.metrics (the found figure of the report and of
        the time series' ground_truth_found), e.g. for a merged or misplaced object."""
        found = set()
        for o in (self.objects.objects if self.objects else []):
            c = (o.centroid.x, o.centroid.y, o.centroid.z)
            for g in gt_objs:
                if g["class"] == o.class_name and all(
                        g["bbox_min"][i] - margin_m <= c[i] <= g["bbox_max"][i] + margin_m for i in range(3)):
                    found.add(g["id"])
        return found

    def row(self, sim_s, wall_s, gt_objs):
        """One line of timeseries.csv; wall_s is None for a bag (written empty)."""
        st = self.stats
        return {"wall_s": round(wall_s, 2) if wall_s is not None else "", "sim_s": round(sim_s, 2),
                "iteration": self.status.iteration if self.status else 0,
                "explored_volume_m3": round(st.explored_volume_m3, 3) if st else 0.0,
                "frontier_count": st.frontier_count if st else 0,
                # the planner's: frontier voxels neither observed nor retired (explored asks for none)
                "active_frontiers": getattr(self.result, "active_frontiers", ""),
                "objects_in_map": len(self.objects.objects) if self.objects else 0,
                "ground_truth_found": len(self.found_ids) if self.found_ids is not None else "",
                "found_at_s": round(self.found_at_s, 2) if self.found_at_s is not None else "",
                "ground_truth_found_proxy": len(self.found_proxy(gt_objs)),
                "object_observed_share": self.object_observed_share(),
                "background_observed_share": self.background_observed_share(),
                "path_length_m": round(self.path_length_m, 3), "collisions": self.collisions,
                "planning_time_s": round(self.status.planning_time_s, 4) if self.status else 0.0,
                "integration_time_ms": round(st.integration_time_ms, 3) if st else 0.0,
                "dropped_frames": self.drops.get("background_map", {}).get("frame_gap", 0),
                "dropped_no_tf": self.drops.get("background_map", {}).get("no_tf", 0)}

    def open_conditions(self) -> Dict:
        """The planner's last word on the paper's three conditions: which still held the run
        open, from the last iteration's status ({} before the first, or from a bag of statuses
        without these fields). A mode that does not pursue a condition reports it done."""
        st = self.result
        if st is None or not hasattr(st, "frontiers_done"):
            return {}
        held = [name for name, done in (("frontiers", st.frontiers_done), ("background", st.background_done),
                                        ("objects", st.objects_done)) if not done]
        return {"active_frontiers": int(st.active_frontiers), "background_observed_share":
                round(float(st.background_observed_share), 4), "not_done": held,
                "last_condition": getattr(st, "last_condition", "")}

    def finished(self):
        return self.status is not None and self.status.state == 3  # ExplorationStatus.STATE_FINISHED

    def line(self, sim_s, wall_s, n_gt):
        explored = self.stats.explored_volume_m3 if self.stats else 0.0
        frontiers = self.stats.frontier_count if self.stats else 0
        found = len(self.objects.objects) if self.objects else 0
        it = self.status.iteration if self.status else 0
        msg = self.status.message if self.status else "waiting for the planner"
        return ("[mission] wall %5.0f s  sim %6.1f s  iteration %3d  explored %7.1f m3  frontiers %6d  "
                "objects %d (ground truth %d)  collisions %d  | %s" %
                (wall_s, sim_s, it, explored, frontiers, found, n_gt, self.collisions, msg))

    def drop_summary(self) -> Dict:
        """{"by_node": {node: {reason: n}}, "headline": [(what, n)], "injected": {fault: n}}."""
        headline = [(what, self.drops[node][reason]) for node, reason, what in DROP_HEADLINES
                    if self.drops.get(node, {}).get(reason, 0) > 0]
        return {"by_node": {n: dict(sorted(r.items())) for n, r in sorted(self.drops.items())},
                "headline": headline, "injected": dict(self.faults)}

    def drop_report_lines(self) -> List[str]:
        """Markdown lines of the report's "Dropped input" section."""
        d = self.drop_summary()
        lines = ["dropped: " + (", ".join("%d %s" % (n, what) for what, n in d["headline"]) or "nothing"), ""]
        if any(d["by_node"].values()):
            lines += ["| node | reason | count |", "|---|---|---|"]
            for node, reasons in d["by_node"].items():
                lines += ["| %s | %s | %d |" % (node, r, n) for r, n in reasons.items()]
            lines.append("")
        if any(d["injected"].values()):
            lines += ["injected by the simulator (faults): " + ", ".join(
                "%d %s" % (n, FAULT_NAMES.get(k, k)) for k, n in d["injected"].items() if n), ""]
        st = self.stats
        if st is not None:
            lines.append("background map: %d frames integrated, %d invalid depth pixels" % (
                st.frames_integrated, st.invalid_depth_pixels))
        return lines

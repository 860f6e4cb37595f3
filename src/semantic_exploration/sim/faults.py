"""Fault injection: the simulator sends bad input on purpose (FaultsConfig), so that
end-to-end runs show the nodes dropping and counting it instead of stalling.

ROS-free; the node asks per frame and per pose what to do, and this class
counts what it injected (for the run's report):
  frames_without_tf    camera frames sent inside the tf gap (no world->body tf at their stamp)
  poses_withheld       tf/mav/pose messages not sent inside the gap
  frames_dropped       camera frames not sent at all
  detections_rescaled  frames whose detection instance image has another size than depth
"""

from typing import Dict

import numpy as np

from .config import FaultsConfig

NS = 1_000_000_000


class FaultInjector:
    def __init__(self, cfg: FaultsConfig):
        cfg.validate()
        self.cfg = cfg
        self.rng = np.random.default_rng(cfg.seed)
        self.counts: Dict[str, int] = {"frames_without_tf": 0, "poses_withheld": 0, "frames_dropped": 0,
                                       "detections_rescaled": 0}

    def in_tf_gap(self, t_ns: int) -> bool:
        """True if sim time t_ns (ns) lies in the tf gap [start, end] (closed)."""
        g = self.cfg.tf_gap_s
        return g is not None and int(round(g[0] * NS)) <= t_ns <= int(round(g[1] * NS))

    def withhold_pose(self, t_ns: int) -> bool:
        """Whether the world->body tf and mav/pose at t_ns are withheld (counted)."""
        if self.in_tf_gap(t_ns):
            self.counts["poses_withheld"] += 1
            return True
        return False

    def drop_frame(self, t_ns: int) -> bool:
        """Whether the camera frame at t_ns is not sent. Draws one random number
        per frame, so the drop pattern depends only on the seed and the frame count.
        A frame that is sent inside the tf gap is counted as frames_without_tf."""
        if self.rng.random() < self.cfg.frame_drop_fraction:
            self.counts["frames_dropped"] += 1
            return True
        if self.in_tf_gap(t_ns):
            self.counts["frames_without_tf"] += 1
        return False

    def detection_image(self, mask: np.ndarray) -> np.ndarray:
        """The detector's instance image at detector_scale times the depth size
        (nearest neighbour, so ids stay ids); unchanged (and uncounted) at scale 1."""
        s = self.cfg.detector_scale
        h, w = mask.shape[:2]
        h2, w2 = max(1, int(round(h * s))), max(1, int(round(w * s)))
        if (h2, w2) == (h, w):
            return mask
        self.counts["detections_rescaled"] += 1
        rows = np.minimum((np.arange(h2) + 0.5) * h / h2, h - 1).astype(int)
        cols = np.minimum((np.arange(w2) + 0.5) * w / w2, w - 1).astype(int)
        return np.ascontiguousarray(mask[rows[:, None], cols[None, :]])

"""A stand-in instance-segmentation detector built from the ground-truth instance image.

Like a detector trained for the classes of interest it reports only those
classes, with per-frame instance ids (not the scene's object ids). Options make
it imperfect in the ways real detectors are: small masks are missed, a
fraction of detections is dropped, and masks bleed over their borders onto
neighbouring surfaces. Chosen objects can be hidden from it altogether (in
view, never detected), to test what a map does with visible undetected objects.
"""

from typing import Dict, List, Tuple

import numpy as np
from scipy import ndimage

from .classes import ClassTable
from .config import DetectorConfig


class Detector:
    def __init__(self, cfg: DetectorConfig, classes: ClassTable):
        cfg.validate()
        self.cfg = cfg
        self.classes = classes
        self.rng = np.random.default_rng(cfg.seed)
        self.hidden = frozenset(cfg.hidden_object_ids)  # scene object ids never reported
        self._interest = np.zeros(65536, bool)
        for n in classes.of_interest:
            self._interest[classes.id(n)] = True

    def detect(self, instance: np.ndarray, class_img: np.ndarray) -> Tuple[np.ndarray, List[Dict]]:
        """Returns (16-bit mask image with per-frame ids, 0 = none; list of detection dicts).

        Each dict has instance_id, class_id, class_name, confidence and
        object_id (the ground-truth object, for tests and evaluation only).
        """
        c = self.cfg
        out = np.zeros(instance.shape, np.uint16)
        sel = self._interest[class_img] & (instance > 0)
        ids, counts = np.unique(instance[sel], return_counts=True)
        dets: List[Dict] = []
        bleeding = []
        for oid, n in zip(ids.tolist(), counts.tolist()):
            # Draw every random number for every candidate so that the stream
            # does not depend on which detections survive.
            r_drop, r_bleed, r_conf = self.rng.random(3)
            if n < c.min_mask_pixels or r_drop < c.drop_fraction or oid in self.hidden:
                continue
            k = len(dets) + 1
            mask = instance == oid
            out[mask] = k
            cls = int(class_img[mask][0])
            dets.append({"instance_id": k, "class_id": cls, "class_name": self.classes.name(cls),
                         "confidence": float(c.confidence_min + r_conf * (c.confidence_max - c.confidence_min)),
                         "object_id": int(oid)})
            if r_bleed < c.bleed_probability and c.bleed_pixels > 0:
                bleeding.append((k, mask))
        for k, mask in bleeding:
            grown = ndimage.binary_dilation(mask, np.ones((3, 3), bool), iterations=self.cfg.bleed_pixels)
            out[grown & (out == 0)] = k  # bleed onto neighbouring surfaces, not onto other detections
        return out, dets

    def set_hidden(self, object_ids) -> None:
        """Replaces the set of hidden scene object ids (from the next detect() on)."""
        self.hidden = frozenset(int(i) for i in object_ids)

"""A ground truth prepared once for scoring any number of reconstructions.

Sampling the true surfaces, building their k-d trees and deciding which
samples are observable (`observable`) cost seconds to tens of seconds per
scene and do not depend on the reconstruction; a run's time series scores
many map snapshots against the same ground truth. `GroundTruthIndex` does
that work once, lazily (object matching alone needs neither the background
nor the observability), and `metrics.evaluate_objects` /
`metrics.evaluate_background` are one-shot uses of it.
"""
import os
from typing import Dict, List, Optional

import numpy as np

from . import metrics, observable
from .metrics import (COMPLETENESS_THRESHOLD_M, ObjectEvaluation, ObjectMatch, SurfaceScore, face_normals,
                      kd_tree, read_ply_vertices, sample_surface_faces, score_surface, spatial_order, within)


class TruthSurface:
    """Samples of one true surface, their k-d tree, and (when asked) which are observable."""

    def __init__(self, samples: np.ndarray, visible_fn, path: str = "", faces: Optional[np.ndarray] = None):
        self.samples = samples
        self.lo, self.hi = (samples.min(0), samples.max(0)) if len(samples) else (np.zeros(3), np.zeros(3))
        self.path, self.faces = path, faces  # the mesh and each sample's face in it
        self._visible_fn = visible_fn
        self._visible = None
        self._tree = None

    @property
    def tree(self):
        if self._tree is None:
            self._tree = kd_tree(self.samples)
        return self._tree

    @property
    def visible(self) -> np.ndarray:
        """(N,) bool over samples: the ones completeness counts."""
        if self._visible is None:
            self._visible = self._visible_fn()
        return self._visible

    def visible_or_wait(self, index: "GroundTruthIndex") -> np.ndarray:
        index._finish_observability()
        return self.visible


class GroundTruthIndex:
    """Scores reconstructions against one exported ground truth (`gt`: metrics.load_ground_truth).

    classes: the classes of interest (the objects evaluate_objects matches).
    Object surfaces are sampled object_spacing_m apart, the whole scene
    (evaluate_background) background_spacing_m apart with observability
    computed at probes probe_spacing_m apart. observable_only=False counts
    every sample in completeness; view is the observable.ViewModel.
    """

    def __init__(self, gt: Dict, classes: List[str], observable_only: bool = True, view=None,
                 object_spacing_m: float = 0.005, background_spacing_m: float = 0.01,
                 probe_spacing_m: float = 0.1, threshold_m: float = COMPLETENESS_THRESHOLD_M, seed: int = 0,
                 processes: int = 2):
        self.gt = gt
        self.gt_objects = [o for o in gt["objects"] if o["class"] in classes]
        self.observable_only = observable_only
        self.view = view
        self.object_spacing_m, self.background_spacing_m = object_spacing_m, background_spacing_m
        self.probe_spacing_m, self.threshold_m, self.seed = probe_spacing_m, threshold_m, seed
        self.processes = processes  # observability is computed over this many processes
        self._objects: Optional[Dict[int, TruthSurface]] = None
        self._background: Optional[TruthSurface] = None
        self._probes: Optional[Dict[str, tuple]] = None  # background mesh -> (probes, their faces, seen)
        self._pending = None  # (process, pipe, sinks) of start_observability

    def _path(self, rel: str) -> str:
        return os.path.join(self.gt["dir"], rel)

    def _obs(self):
        return metrics._observability(self.gt, self.observable_only, self.view)

    @property
    def objects(self) -> Dict[int, TruthSurface]:
        """Ground-truth id -> its surface, for the objects of interest."""
        if self._objects is None:
            self._objects = {}
            for o in self.gt_objects:
                path = self._path(o["mesh"])
                pts, faces = sample_surface_faces(path, self.object_spacing_m, self.seed)

                def visible(path=path, pts=pts, faces=faces):
                    if not self.observable_only:
                        return np.ones(len(pts), bool)
                    return self._obs().mask(pts, face_normals(path, faces))
                self._objects[o["id"]] = TruthSurface(pts, visible, path, faces)
        return self._objects

    @property
    def background(self) -> TruthSurface:
        """Every surface of the scene (see metrics.evaluate_background)."""
        if self._background is None:
            meshes = [self.gt["background_mesh"]] + [o["mesh"] for o in self.gt["objects"]]
            sampled = [sample_surface_faces(self._path(m), self.background_spacing_m, self.seed) for m in meshes]

            def visible():
                if not self.observable_only:
                    return np.ones(sum(len(p) for p, _ in sampled), bool)
                self._probe_masks()
                return np.concatenate([observable.carry_probe_masks(pts, faces, *self._probes[m])
                                       for m, (pts, faces) in zip(meshes, sampled)])
            # Samples in spatial order: the tree builds faster and completeness queries them in that order.
            samples = np.vstack([p for p, _ in sampled])
            order = spatial_order(samples)

            def visible_sorted():
                return visible()[order]
            self._background = TruthSurface(samples[order], visible_sorted)
        return self._background

    def _mask_jobs(self, objects: bool):
        """(points, normals) jobs of the masks still unknown: the background
        meshes' probes, and with objects the objects' samples; and where each answer goes."""
        jobs, sinks = [], []
        if objects:
            for s in self.objects.values():
                if s._visible is None:
                    jobs.append((s.samples, face_normals(s.path, s.faces)))
                    sinks.append(s)
        if self._probes is None:
            self._probes = {}
            for m in [self.gt["background_mesh"]] + [o["mesh"] for o in self.gt["objects"]]:
                probes, probe_faces = sample_surface_faces(self._path(m), self.probe_spacing_m, self.seed,
                                                           face_centres=True)
                self._probes[m] = (probes, probe_faces, None)
                jobs.append((probes, face_normals(self._path(m), probe_faces)))
                sinks.append(m)
        return jobs, sinks

    def _assign(self, sinks, results) -> None:
        for sink, seen in zip(sinks, results):
            if isinstance(sink, TruthSurface):
                sink._visible = seen
            else:
                self._probes[sink] = self._probes[sink][:2] + (seen,)

    def _probe_masks(self, objects: bool = False) -> None:
        """The background meshes' probe observability (and, with objects, the
        objects' sample observability) in one batch over self.processes."""
        self._finish_observability()
        jobs, sinks = self._mask_jobs(objects)
        if jobs:
            self._assign(sinks, observable.masks(self._obs(), jobs, self.processes))

    def prepare_observability(self) -> None:
        """Decides which samples are observable, objects and background together
        (spread over self.processes); scoring does it on first need otherwise."""
        if self.observable_only:
            self._probe_masks(objects=True)

    def start_observability(self) -> None:
        """Starts prepare_observability in a forked process (with its own
        workers), so that what needs no observability (sampling the background,
        building trees, matching objects) runs meanwhile; the first use of a
        mask waits for it. Done in this process where fork is not available."""
        import multiprocessing as mp
        if self._pending is not None or not self.observable_only or "fork" not in mp.get_all_start_methods():
            return
        jobs, sinks = self._mask_jobs(objects=True)
        if not jobs:
            return
        receive, send = mp.Pipe(duplex=False)
        proc = mp.get_context("fork").Process(target=_observability_worker,
                                              args=(self.gt, self.view, jobs, self.processes, send), daemon=False)
        proc.start()
        send.close()
        self._pending = (proc, receive, sinks)

    def close(self) -> None:
        """Collects a process start_observability left running, keeping its result. Call it when done:
        a process left behind blocks on its result pipe, and the interpreter waits for it at exit."""
        try:
            self._finish_observability()
        except RuntimeError:  # its error is only of interest to a use of the masks, and there is none now
            pass

    def _finish_observability(self) -> None:
        if self._pending is None:
            return
        proc, receive, sinks = self._pending
        self._pending = None
        try:
            kind, payload = receive.recv()
        except EOFError:
            kind, payload = "error", "the observability process ended without an answer (exit code %s)" % (
                proc.exitcode,)
        finally:
            receive.close()
            proc.join()
        if kind != "ok":
            raise RuntimeError(payload)
        self._assign(sinks, payload)

    def match(self, class_name: str, vertices: np.ndarray):
        """(ground-truth id or None, fraction of the vertices within the
        threshold of it): the object of class_name that most vertices lie on,
        matched if that is more than half of them."""
        best, best_frac = None, 0.0
        if len(vertices):
            lo, hi = vertices.min(0), vertices.max(0)
            for g in self.gt_objects:
                if g["class"] != class_name:
                    continue
                s = self.objects[g["id"]]
                if np.any(lo > s.hi + self.threshold_m) or np.any(hi < s.lo - self.threshold_m):
                    continue  # no vertex within the threshold of its samples: a fraction of 0
                frac = float(np.mean(within(s.tree, vertices, self.threshold_m)))
                if frac > best_frac:
                    best, best_frac = g["id"], frac
        return (best if best_frac > 0.5 else None), best_frac

    def matched(self, rec: Dict) -> List:
        """(ground-truth id, vertices) of each map object of `rec` (metrics.load_reconstruction)
        that matches one; no observability needed."""
        out = []
        for o in rec.get("objects", []):
            verts = read_ply_vertices(os.path.join(rec["dir"], o["mesh"]))
            gid, _ = self.match(o["class_name"], verts)
            if gid is not None:
                out.append((gid, verts))
        return out

    def found(self, rec: Dict) -> List[int]:
        """Ground-truth ids some map object of `rec` matches; no observability needed."""
        return sorted({gid for gid, _ in self.matched(rec)})

    def object_summary(self, matched) -> Dict:
        """Accuracy and completeness of all matched map objects together, for a
        time series: {"object_rmse_m": RMSE over the vertices of every matched
        map object (nan if none), "object_completeness": mean over the
        ground-truth objects of interest of the share of their observable
        surface within the threshold of a vertex of a map object matched to
        them (0 for one not found)}. matched: [(ground-truth id, vertices)]."""
        d2, n = 0.0, 0
        by_gt: Dict[int, List[np.ndarray]] = {}
        for gid, verts in matched:
            d = metrics.nearest_distance(self.objects[gid].tree, verts)
            d2, n = d2 + float(np.sum(d ** 2)), n + len(d)
            by_gt.setdefault(gid, []).append(verts)
        comp = []
        for g in self.gt_objects:
            s = self.objects[g["id"]]
            vis = s.visible_or_wait(self)
            if g["id"] not in by_gt or not vis.any():
                comp.append(0.0 if vis.any() else np.nan)
                continue
            tree = kd_tree(np.vstack(by_gt[g["id"]]))
            comp.append(float(np.mean(within(tree, s.samples[vis], self.threshold_m))))
        comp = [c for c in comp if np.isfinite(c)]
        return {"object_rmse_m": float(np.sqrt(d2 / n)) if n else float("nan"),
                "object_completeness": float(np.mean(comp)) if comp else float("nan")}

    def evaluate_objects(self, rec: Dict, score: bool = True) -> ObjectEvaluation:
        """See metrics.evaluate_objects."""
        surfaces = self.objects
        ev = ObjectEvaluation(n_ground_truth=len(self.gt_objects))
        matched = []  # matching needs no observability: first
        for o in rec.get("objects", []):
            verts = read_ply_vertices(os.path.join(rec["dir"], o["mesh"]))
            gid, frac = self.match(o["class_name"], verts)
            ev.matches.append(ObjectMatch(o["id"], o["class_name"], gid, frac, empty=len(verts) == 0))
            matched.append(verts)
        if score:
            self.prepare_observability()
            ev.observable_fraction = {k: float(np.mean(s.visible_or_wait(self))) for k, s in surfaces.items()}
        for m, verts in zip(ev.matches, matched):
            if m.gt_id is not None and score:
                s = surfaces[m.gt_id]
                m.score = score_surface(verts, s.samples, self.threshold_m, s.tree, s.visible)
        ev.found_gt_ids = sorted({m.gt_id for m in ev.matches if m.gt_id is not None})
        return ev

    def evaluate_background(self, occupied_points: np.ndarray) -> SurfaceScore:
        """See metrics.evaluate_background."""
        s = self.background
        return score_surface(occupied_points, s.samples, self.threshold_m, s.tree, s.visible_or_wait(self))


def _observability_worker(gt, view, jobs, processes, send) -> None:
    """start_observability's process: the scene's Observability and the masks of jobs, sent back."""
    try:
        send.send(("ok", observable.masks(observable.for_ground_truth(gt, view), jobs, processes)))
    except Exception as e:  # the waiting process raises it
        send.send(("error", "%s: %s" % (type(e).__name__, e)))
    finally:
        send.close()

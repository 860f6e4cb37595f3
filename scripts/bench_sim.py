#!/usr/bin/env python3
"""Frames per second of the simulator's camera: depth (with noise) + colour + instance + class
images of a generated house (15 x 12 x 3 m) at 320 x 240, on one core.

Poses are random collision-free positions in the house at 0.6-2.2 m with random
yaw (fixed seed). The renderer it replaced (sim/reference_renderer.py, commit
9440b49) renders the same poses in the same run, each pose by one and then the
other, so that load from other processes weighs on both alike. Prints the
figures and appends JSON lines to --out: sim_render_320x240_house_fps (peer:
the reference renderer) and sim_render_speedup_vs_reference.
"""
import argparse
import json
import math
import os
import sys
import time


def write_lines(lines, out=None):
    """Prints the JSON lines of a benchmark and appends them to `out` (make bench's results/bench/*.jsonl)."""
    for line in lines:
        print(json.dumps(line))
    if out:
        os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
        with open(out, "a") as f:
            f.writelines(json.dumps(line) + "\n" for line in lines)


def main(argv=None):
    try:
        import semantic_exploration.sim  # noqa: F401
    except ImportError:
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src"))
    import numpy as np
    from semantic_exploration.sim.classes import ClassTable
    from semantic_exploration.sim.config import CameraConfig, NoiseConfig
    from semantic_exploration.sim.generator import generate
    from semantic_exploration.sim.mav import CollisionChecker
    from semantic_exploration.sim.reference_renderer import ReferenceRenderer
    from semantic_exploration.sim.renderer import Renderer
    from semantic_exploration.sim.simulator import R_OPTICAL, rpy_matrix

    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default=None, help="append the JSON line here")
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--size", type=float, nargs=3, default=[15.0, 12.0, 3.0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--backend", default="auto", help="ray casting: auto, embree3 or embreex")
    a = ap.parse_args(argv)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core

    scene = generate(a.seed, a.size)
    renderer = Renderer(scene, CameraConfig(), ClassTable(), noise=NoiseConfig(enabled=True), backend=a.backend)
    reference = ReferenceRenderer(scene, CameraConfig(), ClassTable(), noise=NoiseConfig(enabled=True))
    cc = CollisionChecker(scene.triangles(), 0.125)
    rng = np.random.default_rng(1)
    poses = []
    while len(poses) < a.frames:
        p = rng.uniform([0.2, 0.2, 0.6], [a.size[0] - 0.2, a.size[1] - 0.2, 2.2])
        if cc.collides(p):
            continue
        T = np.eye(4)
        T[:3, :3] = rpy_matrix(0.0, 0.0, rng.uniform(-math.pi, math.pi)) @ R_OPTICAL
        T[:3, 3] = p
        poses.append(T)
    for T in poses[:10]:  # warm-up
        renderer.render(T)
        reference.render(T)
    times, ref_times, cpu, ref_cpu = [], [], [], []
    for T in poses:
        for r, ts, cs in ((renderer, times, cpu), (reference, ref_times, ref_cpu)):
            t0, c0 = time.perf_counter(), time.thread_time()
            out = r.render(T)
            ts.append(time.perf_counter() - t0)
            cs.append(time.thread_time() - c0)  # CPU time: what the frame costs however loaded the machine is
            assert out["depth"].shape == (240, 320)
    med, ref_med = float(np.median(times)), float(np.median(ref_times))
    fps, ref_fps = 1.0 / med, 1.0 / ref_med
    print("sim render (depth+rgb+instance+class, noise on) %dx%d, house %gx%gx%g m, %d triangles, one core:"
          % (320, 240, *a.size, len(scene.faces)))
    print("  renderer (%s):   median %.2f ms/frame = %.1f fps (p90 %.2f ms), CPU %.2f ms/frame"
          % (renderer.backend, med * 1e3, fps, float(np.percentile(times, 90)) * 1e3, float(np.median(cpu)) * 1e3))
    print("  reference (9440b49): median %.2f ms/frame = %.1f fps (p90 %.2f ms), CPU %.2f ms/frame"
          % (ref_med * 1e3, ref_fps, float(np.percentile(ref_times, 90)) * 1e3, float(np.median(ref_cpu)) * 1e3))
    print("  speed-up %.2fx (target >= 2)" % (fps / ref_fps))
    lines = [{"name": "sim_render_320x240_house_fps", "value": round(fps, 2), "unit": "Hz",
              "peer": "reference_renderer (9440b49)", "peer_value": round(ref_fps, 2)},
             {"name": "sim_render_speedup_vs_reference", "value": round(fps / ref_fps, 3), "unit": "x",
              "peer": None, "peer_value": None}]
    write_lines(lines, a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

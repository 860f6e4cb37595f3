#!/usr/bin/env python3
"""CPU time of the simulator's loop per second of sim time: physics at 100 Hz and a camera frame
(depth with noise, colour, instance, class, detections) at 10 Hz while the MAV flies a square in
the generated 15 x 12 x 3 m house, without ROS.

The loop runs in two child processes, one after the other: with one BLAS thread (what mav_sim
sets, scripts/mav_sim.py blas_setup) and with OpenBLAS's default (a thread per core), whose
worker spins in sched_yield after every small numpy product. A child's CPU time is user + system
over all its threads (os.wait4), so the spinning thread counts. Prints the figures and appends
JSON lines to --out: sim_loop_cpu_ms_per_sim_s and sim_loop_sim_s_per_wall_s (peer: the BLAS
default) and sim_loop_cpu_ratio_blas_default_vs_one. The wall figures depend on the machine's
load (a spinning thread costs more where the second core is idle); the CPU ratio less so.
"""
import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from bench_sim import write_lines  # noqa: E402


def child(sim_s: float) -> None:
    """The loop itself; prints {"wall_s", "sim_s"} as JSON."""
    try:
        import semantic_exploration.sim  # noqa: F401
    except ImportError:
        sys.path.insert(0, os.path.join(HERE, "..", "src"))
    from semantic_exploration.sim.config import SimConfig
    from semantic_exploration.sim.simulator import Simulator

    cfg = SimConfig()
    sim = Simulator.from_config(cfg)
    x, y, z, yaw = sim.pose
    square = [(x, y, z, yaw), (x + 1.0, y, z, yaw), (x + 1.0, y + 1.0, z, yaw + 1.5), (x, y + 1.0, z, yaw + 3.0),
              (x, y, z, yaw)]
    dt = 1.0 / cfg.mav.physics_rate_hz
    steps_per_frame = max(1, int(round(cfg.mav.physics_rate_hz / cfg.camera.rate_hz)))
    steps = int(round(sim_s / dt))
    t0 = time.perf_counter()
    for k in range(steps):
        if not sim.follower.active:
            sim.set_path(square, checked=True)  # around and around; collisions do not matter here
        if k % steps_per_frame == 0:
            sim.render()
        sim.step(dt)
    print(json.dumps({"wall_s": time.perf_counter() - t0, "sim_s": steps * dt}))


def run_child(sim_s: float, blas_threads):
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    if blas_threads is not None:
        env["OPENBLAS_NUM_THREADS"] = str(blas_threads)
    p = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--child", "--sim-s", str(sim_s)], env=env,
                         stdout=subprocess.PIPE, text=True)
    out = p.stdout.read()
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)  # reaped here: Popen must not wait for it again
    if p.returncode != 0:
        raise RuntimeError("bench_sim_loop child exited with %d" % p.returncode)
    res = json.loads(out.strip().splitlines()[-1])
    res["cpu_s"] = usage.ru_utime + usage.ru_stime
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default=None, help="append the JSON lines here")
    ap.add_argument("--sim-s", type=float, default=20.0, help="sim seconds per child")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.child:
        child(a.sim_s)
        return 0
    # Start-up (imports, scene generation) is outside the loop's wall time but inside its CPU time;
    # a short run of each gives it, to subtract.
    base = {n: run_child(0.0, t) for n, t in (("one", 1), ("default", None))}
    runs = {n: run_child(a.sim_s, t) for n, t in (("one", 1), ("default", None))}
    per = {n: 1e3 * (runs[n]["cpu_s"] - base[n]["cpu_s"]) / runs[n]["sim_s"] for n in runs}
    print("simulator loop (physics 100 Hz, a frame every 0.1 s, generated 15 x 12 x 3 m house), %.0f s of sim time:"
          % a.sim_s)
    for n, label in (("one", "one BLAS thread (mav_sim)"), ("default", "BLAS default threads")):
        print("  %-26s CPU %.1f ms per sim s (loop wall %.2f s, %.2f sim s per wall s)"
              % (label, per[n], runs[n]["wall_s"], runs[n]["sim_s"] / runs[n]["wall_s"]))
    ratio = per["default"] / per["one"]
    print("  BLAS default / one thread: %.2fx the CPU" % ratio)
    lines = [{"name": "sim_loop_cpu_ms_per_sim_s", "value": round(per["one"], 1), "unit": "ms",
              "peer": "OpenBLAS default threads", "peer_value": round(per["default"], 1)},
             {"name": "sim_loop_sim_s_per_wall_s", "value": round(runs["one"]["sim_s"] / runs["one"]["wall_s"], 2),
              "unit": "x", "peer": "OpenBLAS default threads",
              "peer_value": round(runs["default"]["sim_s"] / runs["default"]["wall_s"], 2)},
             {"name": "sim_loop_cpu_ratio_blas_default_vs_one", "value": round(ratio, 3), "unit": "x",
              "peer": None, "peer_value": None}]
    write_lines(lines, a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

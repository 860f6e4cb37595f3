#!/usr/bin/env python3
"""mav_sim: Habitat-style MAV simulator node (see src/semantic_exploration/sim/node.py).

catkin installs this script with a /usr/bin/python3 shebang, which does not see
the project's venv (embreex, trimesh). The launch file runs it with the venv's
python through launch-prefix; if it is started some other way without those
modules, it re-executes itself with $SEMEXP_VENV/bin/python, or with the
nearest .venv above this file (<repo>/.venv, also from <repo>/.colcon/install).
"""
import os
import sys


def _venv_candidates():
    env = os.environ.get("SEMEXP_VENV")
    if env:
        yield env
    # <repo>/.venv seen from the source tree (scripts/) or from a build/install space inside the repo.
    d = os.path.dirname(os.path.realpath(__file__))
    for _ in range(8):
        yield os.path.join(d, ".venv")
        parent = os.path.dirname(d)
        if parent == d:
            break
        d = parent


def _ensure_ray_tracer():
    try:
        import embreex  # noqa: F401
        import trimesh  # noqa: F401
        return
    except ImportError:
        pass
    if os.environ.get("SEMEXP_SIM_REEXEC") != "1":
        for venv in _venv_candidates():
            py = os.path.abspath(os.path.join(venv, "bin", "python"))
            if os.path.isfile(py) and os.access(py, os.X_OK):
                os.environ["SEMEXP_SIM_REEXEC"] = "1"
                os.execv(py, [py, os.path.realpath(__file__)] + sys.argv[1:])
    sys.stderr.write("mav_sim: cannot import embreex/trimesh. Run scripts/setup.sh and set SEMEXP_VENV to its venv "
                     "(or pass python:=<venv>/bin/python to sim_only.launch).\n")
    sys.exit(1)


#: OpenBLAS's kernels for the simulator's numpy where the processor has AVX2 and FMA. OpenBLAS
#: picks its kernels by processor model, and with another choice numpy's results can differ in
#: their last bits: a deterministic flight of a house parted at 301 s of sim time between an
#: Intel Xeon with its own choice (SkylakeX) and the same flight with these, which gave an AMD
#: EPYC's figures (docs/BENCHMARKS.md, "Deterministic flights on other processors").
BLAS_CORETYPE = "Haswell"


def cpu_flags(cpuinfo="/proc/cpuinfo"):
    """The processor's feature flags (the first "flags" line of cpuinfo) as a set, empty where
    there is none (aarch64 names them "Features"), or None where the file cannot be read."""
    try:
        with open(cpuinfo) as f:
            return set(next((line for line in f if line.startswith("flags")), "").split())
    except OSError:
        return None


def _has_avx2_fma(cpuinfo="/proc/cpuinfo"):
    flags = cpu_flags(cpuinfo) or set()
    return "avx2" in flags and "fma" in flags


def blas_setup():
    """To be called before numpy loads:
    - one BLAS thread: the simulator's matrices are 3x3 and 4x4, and after each call OpenBLAS's
      worker thread spins in sched_yield; with the default (a thread per core) that thread kept a
      second core busy for the whole run (docs/BENCHMARKS.md, "End to end");
    - BLAS_CORETYPE's kernels where the processor can run them, so that runs on other processors
      compute alike.
    A setting in the environment wins."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    # An empty setting (a launch file's unset $(optenv ...)) is no setting: OpenBLAS would fall back to a
    # choice of its own.
    if _has_avx2_fma() and not os.environ.get("OPENBLAS_CORETYPE"):
        os.environ["OPENBLAS_CORETYPE"] = BLAS_CORETYPE


if __name__ == "__main__":
    blas_setup()
    _ensure_ray_tracer()
    try:
        from semantic_exploration.sim.node import main
    except ImportError:  # running from the source tree without an install space
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "src"))
        from semantic_exploration.sim.node import main
    main()

"""mav_sim runs numpy on one BLAS thread (scripts/mav_sim.py one_blas_thread): OpenBLAS's worker
threads spin in sched_yield after each call and kept a second core busy during missions.
Counted in a child interpreter, as the setting only acts before numpy loads."""
import os
import subprocess
import sys

import pytest

from conftest import ROOT

_COUNT = """
import os, sys
sys.path.insert(0, {scripts!r})
import mav_sim
if {call}:
    mav_sim.one_blas_thread()
import numpy as np
a = np.ones((64, 64))
a @ a
print(len(os.listdir("/proc/self/task")))
"""


def _threads_after_a_matrix_product(call, env_threads=None):
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    if env_threads is not None:
        env["OPENBLAS_NUM_THREADS"] = str(env_threads)
    code = _COUNT.format(scripts=os.path.join(ROOT, "scripts"), call=call)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return int(out.stdout.strip())


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="counts threads in /proc")
def test_the_simulator_starts_no_blas_worker_thread():
    assert _threads_after_a_matrix_product(call=True) == 1


def _cores():
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


@pytest.mark.skipif(_cores() < 2 or not os.path.isdir("/proc/self/task"),
                    reason="OpenBLAS makes no worker thread where this process may use one core only")
def test_without_it_numpy_starts_worker_threads_and_a_setting_in_the_environment_wins():
    # The control: this numpy's BLAS does start workers by default, so the count above means something.
    assert _threads_after_a_matrix_product(call=False) > 1
    assert _threads_after_a_matrix_product(call=True, env_threads=2) == 2

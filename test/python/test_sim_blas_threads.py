"""mav_sim runs numpy on one BLAS thread (scripts/mav_sim.py blas_setup): OpenBLAS's worker
threads spin in sched_yield after each call and kept a second core busy during missions. And on
OpenBLAS's Haswell kernels where the processor has AVX2 and FMA, so that other processors compute
alike. Counted in a child interpreter, as the settings only act before numpy loads."""
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
    mav_sim.blas_setup()
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


_CORE = """
import ctypes, sys
sys.path.insert(0, {scripts!r})
import mav_sim
mav_sim.blas_setup()
import numpy as np
np.ones((8, 8)) @ np.ones((8, 8))
libs = [line.split()[-1] for line in open("/proc/self/maps") if "openblas" in line.split()[-1]]
if not libs:
    print("no OpenBLAS")
else:
    f = ctypes.CDLL(libs[0]).openblas_get_corename
    f.restype = ctypes.c_char_p
    print(f().decode())
"""


def _blas_core(env_core=None):
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    if env_core is not None:
        env["OPENBLAS_CORETYPE"] = env_core
    code = _CORE.format(scripts=os.path.join(ROOT, "scripts"))
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          check=True).stdout.strip()


def _avx2_fma():
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    import mav_sim
    return mav_sim._has_avx2_fma()


@pytest.mark.skipif(not os.path.isfile("/proc/self/maps") or not _avx2_fma(),
                    reason="a Linux processor with AVX2 and FMA (the kernels are pinned only there)")
def test_the_simulator_runs_openblas_haswell_kernels_and_a_setting_in_the_environment_wins():
    core = _blas_core()
    if core == "no OpenBLAS":
        pytest.skip("numpy's BLAS is not OpenBLAS here")
    assert core == "Haswell"
    assert _blas_core("Sandybridge") == "Sandybridge"


def test_the_kernels_are_pinned_only_where_the_processor_has_avx2_and_fma(tmp_path):
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    import mav_sim
    for flags, expected in (("fpu sse2 avx avx2 fma", True), ("fpu sse2 avx avx2", False), ("fpu sse2 fma", False)):
        (tmp_path / "cpuinfo").write_text("processor\t: 0\nflags\t\t: %s\n" % flags)
        assert mav_sim._has_avx2_fma(str(tmp_path / "cpuinfo")) is expected, flags
    assert mav_sim._has_avx2_fma(str(tmp_path / "missing")) is False

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
import sys
sys.path.insert(0, {scripts!r})
import mav_sim
mav_sim.blas_setup()
import numpy as np
np.ones((8, 8)) @ np.ones((8, 8))
from semantic_exploration.sim import blas
print(blas.openblas_corename(), "|", blas.openblas_config())
"""


def _blas_core(env_core=None):
    """(kernels' name, build configuration) of the OpenBLAS in a child that ran blas_setup, or Nones."""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    if env_core is not None:
        env["OPENBLAS_CORETYPE"] = env_core
    env["PYTHONPATH"] = os.pathsep.join([os.path.join(ROOT, "src")] + [p for p in [env.get("PYTHONPATH")] if p])
    code = _CORE.format(scripts=os.path.join(ROOT, "scripts"))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    core, config = (x.strip() for x in out.stdout.strip().split("|"))
    return (None if core == "None" else core), (None if config == "None" else config)


def test_the_simulator_runs_openblas_haswell_kernels_and_a_setting_in_the_environment_wins():
    import mav_sim
    if not mav_sim._has_avx2_fma():
        pytest.skip("the kernels are pinned only where the processor has AVX2 and FMA")
    core, config = _blas_core()
    if core is None or "DYNAMIC_ARCH" not in (config or ""):
        pytest.skip("numpy's BLAS here is not an OpenBLAS that picks its kernels at run time (%s)" % config)
    assert core == "Haswell"
    assert _blas_core("Sandybridge")[0] == "Sandybridge"
    assert _blas_core("")[0] == "Haswell"  # an empty setting is none


def test_the_kernels_are_pinned_only_where_the_processor_has_avx2_and_fma(tmp_path, monkeypatch):
    import mav_sim
    cases = (("flags\t\t: fpu sse2 avx avx2 fma\n", True),
             ("flags\t\t: fpu sse2 avx avx2\n", False),
             ("flags\t\t: fpu sse2 fma\n", False),
             ("vmx flags\t: avx2 fma\nflags\t\t: fpu sse2\n", False),        # VMX features are not the processor's
             ("Features\t: fp asimd evtstrm aes pmull sha1 sha2 crc32\n", False))  # aarch64 (Jetson)
    for text, expected in cases:
        (tmp_path / "cpuinfo").write_text("processor\t: 0\n" + text)
        assert mav_sim._has_avx2_fma(str(tmp_path / "cpuinfo")) is expected, text
    assert mav_sim._has_avx2_fma(str(tmp_path / "missing")) is False
    # Without them blas_setup leaves the kernels to OpenBLAS.
    monkeypatch.delenv("OPENBLAS_CORETYPE", raising=False)
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")
    monkeypatch.setattr(mav_sim, "_has_avx2_fma", lambda cpuinfo="/proc/cpuinfo": False)
    mav_sim.blas_setup()
    assert "OPENBLAS_CORETYPE" not in os.environ
    monkeypatch.setattr(mav_sim, "_has_avx2_fma", lambda cpuinfo="/proc/cpuinfo": True)
    mav_sim.blas_setup()
    assert os.environ["OPENBLAS_CORETYPE"] == mav_sim.BLAS_CORETYPE

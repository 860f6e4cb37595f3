"""Which kernels the OpenBLAS loaded into this process runs (for mav_sim's start-up line and its
test). numpy may bring its own OpenBLAS (pip wheels, whose symbols carry a suffix) or use the
system's; the library is found among this process's mapped files."""
import ctypes
from typing import Optional

#: openblas_get_corename as the system library and numpy's wheels (numpy < 2, >= 2) export it.
_CORENAME_SYMBOLS = ("openblas_get_corename", "openblas_get_corename64_", "scipy_openblas_get_corename64_")
_CONFIG_SYMBOLS = ("openblas_get_config", "openblas_get_config64_", "scipy_openblas_get_config64_")


def _mapped_openblas(maps="/proc/self/maps"):
    try:
        with open(maps) as f:
            fields = [line.split() for line in f]
    except OSError:
        return []
    # A mapping's sixth field is its file; anonymous mappings have five.
    return list(dict.fromkeys(x[5] for x in fields if len(x) >= 6 and "openblas" in x[5].lower()))


def _call(symbols) -> Optional[str]:
    for path in _mapped_openblas():
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for name in symbols:
            f = getattr(lib, name, None)
            if f is not None:
                f.restype = ctypes.c_char_p
                out = f()
                return out.decode() if out else None
    return None


def openblas_corename() -> Optional[str]:
    """The kernels' name (e.g. "Haswell", "SkylakeX"), or None where numpy's BLAS is not a loaded OpenBLAS."""
    return _call(_CORENAME_SYMBOLS)


def openblas_config() -> Optional[str]:
    """OpenBLAS's build configuration ("... DYNAMIC_ARCH ..." where it picks kernels at run time), or None."""
    return _call(_CONFIG_SYMBOLS)

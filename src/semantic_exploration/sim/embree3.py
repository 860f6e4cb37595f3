"""First-hit ray casting through Embree 3's C API (Debian's libembree3-3), with ctypes.

Why not embreex alone: its ``run`` traces one ray per call from a Python-level
loop; Embree 3's stream call ``rtcIntersectNp`` takes a whole image of rays
in one call, as separate float arrays, and traces coherent camera rays as
packets. On the simulator's 320 x 240 camera it is about 3x faster.

Only the few functions and the structs that a triangle mesh and first-hit
queries need are declared, with the layout of Embree 3.x built with
RTC_MAX_INSTANCE_LEVEL_COUNT 1 (Debian 12's 3.13.5, Ubuntu 20.04's 3.8).
"""

import ctypes
import ctypes.util
from typing import Optional

import numpy as np

_INVALID_ID = 0xFFFFFFFF
_GEOMETRY_TYPE_TRIANGLE = 0
_BUFFER_TYPE_INDEX, _BUFFER_TYPE_VERTEX = 0, 1
_FORMAT_UINT3, _FORMAT_FLOAT3 = 0x5003, 0x9003
_BUILD_QUALITY_HIGH = 2
_CONTEXT_FLAG_COHERENT = 1
_MAX_INSTANCE_LEVELS = 8  # hit instID pointers handed over; Embree reads only as many as it was built with

#: Embree's device configuration: one build thread (the BVH is built once per
#: scene, and the simulator shares the machine with the mapping), and vector
#: kernels no wider than AVX2. Embree picks its kernels at run time, and where
#: two faces tie (coincident faces: generated furniture has some) kernels of
#: other widths can report the other face, so a pixel's instance differs and a
#: deterministic flight parts from its twin on a machine with other vector
#: units (AVX-512 against AVX2: docs/BENCHMARKS.md "Deterministic flights on
#: other processors"). Intel Core and Xeon processors since Haswell and AMD's
#: since Zen have AVX2; where it is missing Embree takes the widest it has.
DEVICE_CONFIG = "threads=1,max_isa=avx2"

_f = ctypes.POINTER(ctypes.c_float)
_u = ctypes.POINTER(ctypes.c_uint)


class _Context(ctypes.Structure):
    """struct RTCIntersectContext (RTC_MAX_INSTANCE_LEVEL_COUNT 1, no RTC_MIN_WIDTH)."""
    _fields_ = [("flags", ctypes.c_int), ("filter", ctypes.c_void_p), ("instID", ctypes.c_uint * 1)]


class _RayHitNp(ctypes.Structure):
    """struct RTCRayHitNp: one pointer per ray and hit field (SOA stream)."""
    _fields_ = [(n, _f) for n in ("org_x", "org_y", "org_z", "tnear", "dir_x", "dir_y", "dir_z", "time",
                                  "tfar")] + \
               [(n, _u) for n in ("mask", "id", "flags")] + \
               [(n, _f) for n in ("Ng_x", "Ng_y", "Ng_z", "u", "v")] + \
               [("primID", _u), ("geomID", _u), ("instID", _u * _MAX_INSTANCE_LEVELS)]


_lib = None


def library() -> Optional[ctypes.CDLL]:
    """libembree3, or None if it is not installed."""
    global _lib
    if _lib is None:
        name = ctypes.util.find_library("embree3") or "libembree3.so.3"
        try:
            lib = ctypes.CDLL(name)
        except OSError:
            _lib = False
            return None
        vp = ctypes.c_void_p
        for fn, res, args in (
                ("rtcNewDevice", vp, [ctypes.c_char_p]),
                ("rtcGetDeviceError", ctypes.c_int, [vp]),
                ("rtcReleaseDevice", None, [vp]),
                ("rtcNewScene", vp, [vp]),
                ("rtcSetSceneBuildQuality", None, [vp, ctypes.c_int]),
                ("rtcCommitScene", None, [vp]),
                ("rtcReleaseScene", None, [vp]),
                ("rtcNewGeometry", vp, [vp, ctypes.c_int]),
                ("rtcSetNewGeometryBuffer", vp, [vp, ctypes.c_int, ctypes.c_uint, ctypes.c_int, ctypes.c_size_t,
                                                 ctypes.c_size_t]),
                ("rtcCommitGeometry", None, [vp]),
                ("rtcAttachGeometry", ctypes.c_uint, [vp, vp]),
                ("rtcReleaseGeometry", None, [vp]),
                ("rtcIntersectNp", None, [vp, ctypes.POINTER(_Context), ctypes.POINTER(_RayHitNp), ctypes.c_uint])):
            f = getattr(lib, fn)
            f.restype, f.argtypes = res, args
        _lib = lib
    return _lib or None


class EmbreeError(RuntimeError):
    """Embree refused the scene (the message says what it reported)."""


class TriangleScene:
    """A static triangle mesh that answers first-hit queries for many rays at once."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, device_config: str = DEVICE_CONFIG):
        """``device_config``: Embree's configuration string. (Embree 3.13 takes an ISA name it does not
        know for its narrowest kernels, SSE2, rather than failing.)"""
        lib = library()
        if lib is None:
            raise EmbreeError("libembree3 is not installed")
        self._lib = lib
        self.device_config = device_config
        self._device = lib.rtcNewDevice(device_config.encode())
        if not self._device:
            raise EmbreeError("rtcNewDevice failed (configuration %r)" % device_config)
        self._scene = lib.rtcNewScene(self._device)
        lib.rtcSetSceneBuildQuality(self._scene, _BUILD_QUALITY_HIGH)
        geom = lib.rtcNewGeometry(self._device, _GEOMETRY_TYPE_TRIANGLE)
        v = np.ascontiguousarray(vertices, np.float32).reshape(-1, 3)
        f = np.ascontiguousarray(faces, np.uint32).reshape(-1, 3)
        for kind, fmt, arr in ((_BUFFER_TYPE_VERTEX, _FORMAT_FLOAT3, v), (_BUFFER_TYPE_INDEX, _FORMAT_UINT3, f)):
            ptr = lib.rtcSetNewGeometryBuffer(geom, kind, 0, fmt, 12, len(arr))
            if not ptr:
                raise EmbreeError("rtcSetNewGeometryBuffer failed (error %d)" % lib.rtcGetDeviceError(self._device))
            ctypes.memmove(ptr, arr.ctypes.data, arr.nbytes)
        lib.rtcCommitGeometry(geom)
        lib.rtcAttachGeometry(self._scene, geom)
        lib.rtcReleaseGeometry(geom)
        lib.rtcCommitScene(self._scene)
        err = lib.rtcGetDeviceError(self._device)
        if err:
            raise EmbreeError("building the scene failed (Embree error %d)" % err)
        self._context = _Context(_CONTEXT_FLAG_COHERENT, None, (ctypes.c_uint * 1)(_INVALID_ID))
        self._n = 0

    def _buffers(self, n: int) -> None:
        """Ray and hit arrays for n rays, and the pointer struct Embree reads them through."""
        self._n = n
        rows = lambda k: np.zeros((k, -(-n // 4) * 4), np.float32)[:, :n]  # noqa: E731 (rows 16-byte aligned)
        self.org = rows(3)
        self.dir = rows(3)
        self._tnear = np.zeros(n, np.float32)
        self._time = np.zeros(n, np.float32)
        self._tfar = np.empty(n, np.float32)
        self._mask = np.full(n, 0xFFFFFFFF, np.uint32)  # every mask bit: no ray is masked out
        self._id = np.arange(n, dtype=np.uint32)
        self._flags = np.zeros(n, np.uint32)
        self._ng = rows(3)
        self._uv = rows(2)
        self._prim = np.empty(n, np.uint32)
        self._geom = np.empty(n, np.uint32)
        self._inst = np.empty(n, np.uint32)
        fp = lambda a: a.ctypes.data_as(_f)  # noqa: E731
        up = lambda a: a.ctypes.data_as(_u)  # noqa: E731
        self._rayhit = _RayHitNp(
            fp(self.org[0]), fp(self.org[1]), fp(self.org[2]), fp(self._tnear),
            fp(self.dir[0]), fp(self.dir[1]), fp(self.dir[2]), fp(self._time), fp(self._tfar),
            up(self._mask), up(self._id), up(self._flags),
            fp(self._ng[0]), fp(self._ng[1]), fp(self._ng[2]), fp(self._uv[0]), fp(self._uv[1]),
            up(self._prim), up(self._geom), (_u * _MAX_INSTANCE_LEVELS)(*[up(self._inst)] * _MAX_INSTANCE_LEVELS))

    def first_hit(self, origin, directions: np.ndarray) -> np.ndarray:
        """Index of the first triangle that each ray origin + t directions[i] (t > 0) meets, -1 for
        none; directions (N, 3). Returns (N,) int32."""
        d = np.asarray(directions).reshape(-1, 3)
        if len(d) != self._n:
            self._buffers(len(d))
        self.org[:] = np.asarray(origin, np.float32).reshape(3, 1)
        self.dir[:] = d.T
        return self.trace()

    def trace(self) -> np.ndarray:
        """first_hit() of the rays already written into ``org`` and ``dir`` ((3, N) float32; first_hit()
        allocates them for N rays)."""
        self._tfar.fill(np.inf)
        self._geom.fill(_INVALID_ID)
        self._lib.rtcIntersectNp(self._scene, ctypes.byref(self._context), ctypes.byref(self._rayhit), self._n)
        return np.where(self._geom == _INVALID_ID, -1, self._prim.view(np.int32))

    def __del__(self):
        lib = getattr(self, "_lib", None)
        if lib is not None:
            if getattr(self, "_scene", None):
                lib.rtcReleaseScene(self._scene)
            if getattr(self, "_device", None):
                lib.rtcReleaseDevice(self._device)

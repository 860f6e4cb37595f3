"""The Python side of the map-block codec (include/semantic_exploration/core/map_blocks.hpp):
reads and writes msg/MapBlocks.msg for tests and tools, with the same layout and encoding
as the C++ side.

Layout: a block is block_size^3 voxels, x fastest, then y, then z; block (bx, by, bz) holds
voxels (bx * bs .. bx * bs + bs - 1, ...); voxel (0, 0, 0)'s minimum corner is `origin`.
Encoding (ENCODING_LOG_ODDS_I8): one int8 per voxel, log-odds x 10 rounded and clamped to
[-127, 127], a negative log-odds never rounds to 0 or above; -128 = unknown. The message
carries the int8 bits as uint8.
"""
import math
from typing import Dict, Tuple

import numpy as np

ENCODING_LOG_ODDS_I8 = 0
UNKNOWN_I8 = -128
I8_PER_LOG_ODDS = 10
# core VoxelState
UNKNOWN, FREE, OCCUPIED = 0, 1, 2


class MapBlocksError(ValueError):
    """A MapBlocks message that cannot be read (unknown encoding, sizes that disagree)."""


def encode_log_odds(l) -> np.ndarray:
    """int8 codes of log-odds values (NaN = unknown), as map_blocks::encodeMilli."""
    l = np.asarray(l, dtype=np.float64)
    milli = np.round(np.nan_to_num(l, nan=0.0) * 1000.0)  # the map's fixed point (thousandths)
    steps = milli / (1000 // I8_PER_LOG_ODDS)
    q = np.clip(np.sign(steps) * np.floor(np.abs(steps) + 0.5), -127, 127)  # halves away from 0, as lround
    q = np.where((milli < 0) & (q >= 0), -1, q)
    return np.where(np.isnan(l), UNKNOWN_I8, q).astype(np.int8)


def decode_log_odds(q) -> np.ndarray:
    """Log-odds of int8 codes; NaN where unknown."""
    q = np.asarray(q, dtype=np.int8)
    return np.where(q == UNKNOWN_I8, np.nan, q.astype(np.float64) / I8_PER_LOG_ODDS)


def state_of(q: int, free_below: int = 0) -> int:
    """VoxelState of a code: UNKNOWN, FREE (below free_below) or OCCUPIED."""
    if q == UNKNOWN_I8:
        return UNKNOWN
    return FREE if q < free_below else OCCUPIED


class DecodedBlocks:
    """The voxels of one MapBlocks message: block coordinates -> (bs, bs, bs) int8 array indexed [x, y, z]."""

    def __init__(self, origin, resolution_m: float, block_size: int, sequence: int, full: bool):
        self.origin = np.asarray(origin, dtype=np.float64)
        self.resolution_m, self.block_size = float(resolution_m), int(block_size)
        self.sequence, self.full = int(sequence), bool(full)
        self.blocks: Dict[Tuple[int, int, int], np.ndarray] = {}

    def voxel_index(self, p_W) -> Tuple[int, int, int]:
        return tuple(int(math.floor((p_W[k] - self.origin[k]) / self.resolution_m)) for k in range(3))

    def value(self, p_W) -> int:
        """The int8 code of the voxel holding p_W (m, world); UNKNOWN_I8 outside every block."""
        v = self.voxel_index(p_W)
        bs = self.block_size
        b = self.blocks.get(tuple(i // bs for i in v))  # floor division: negative indices too
        return UNKNOWN_I8 if b is None else int(b[v[0] % bs, v[1] % bs, v[2] % bs])

    def state(self, p_W, free_below: int = 0) -> int:
        return state_of(self.value(p_W), free_below)


def decode(msg) -> DecodedBlocks:
    """Reads a semantic_exploration/MapBlocks message (detailed blocks, then uniform ones)."""
    if msg.encoding != ENCODING_LOG_ODDS_I8:
        raise MapBlocksError("MapBlocks encoding %d unsupported" % msg.encoding)
    bs = int(msg.block_size)
    if bs <= 0 or not (msg.resolution_m > 0):
        raise MapBlocksError("MapBlocks block_size %d, resolution_m %r" % (bs, msg.resolution_m))
    n = bs ** 3
    coords = np.asarray(msg.coords, dtype=np.int32).reshape(-1, 3) if len(msg.coords) % 3 == 0 else None
    payload = np.frombuffer(bytes(msg.payload), dtype=np.int8)
    if coords is None or payload.size != coords.shape[0] * n:
        raise MapBlocksError("MapBlocks: %d coords and %d payload bytes disagree" % (len(msg.coords), payload.size))
    ucoords = np.asarray(msg.uniform_coords, dtype=np.int32).reshape(-1, 3) if len(msg.uniform_coords) % 3 == 0 \
        else None
    uvalues = np.frombuffer(bytes(msg.uniform_values), dtype=np.int8)
    if ucoords is None or uvalues.size != ucoords.shape[0]:
        raise MapBlocksError("MapBlocks: %d uniform coords and %d uniform values disagree"
                             % (len(msg.uniform_coords), uvalues.size))
    o = msg.origin
    out = DecodedBlocks((o.x, o.y, o.z), msg.resolution_m, bs, msg.sequence, msg.full)
    for i, c in enumerate(coords):
        # stored [z][y][x] (x fastest): transpose to [x, y, z]
        out.blocks[tuple(int(v) for v in c)] = payload[i * n:(i + 1) * n].reshape(bs, bs, bs).transpose(2, 1, 0)
    for c, v in zip(ucoords, uvalues):
        out.blocks[tuple(int(x) for x in c)] = np.full((bs, bs, bs), v, dtype=np.int8)
    return out


def encode(msg, grid_xyz: np.ndarray, origin, resolution_m: float, block_size: int, sequence: int, full: bool):
    """Fills a MapBlocks message with the int8 codes of `grid_xyz` (indexed [x, y, z], voxel (0, 0, 0)
    at `origin`), one detailed block per block_size^3 cube; each grid dimension must be a multiple
    of block_size. Returns msg."""
    g = np.asarray(grid_xyz, dtype=np.int8)
    bs = int(block_size)
    if any(s % bs for s in g.shape):
        raise MapBlocksError("grid %s is not whole blocks of %d" % (g.shape, bs))
    msg.sequence, msg.full = sequence, full
    msg.resolution_m, msg.block_size, msg.encoding = resolution_m, bs, ENCODING_LOG_ODDS_I8
    msg.origin.x, msg.origin.y, msg.origin.z = (float(v) for v in origin)
    coords, payload = [], []
    for bx in range(g.shape[0] // bs):
        for by in range(g.shape[1] // bs):
            for bz in range(g.shape[2] // bs):
                b = g[bx * bs:(bx + 1) * bs, by * bs:(by + 1) * bs, bz * bs:(bz + 1) * bs]
                coords += [bx, by, bz]
                payload.append(np.ascontiguousarray(b.transpose(2, 1, 0)).tobytes())  # x fastest
    msg.coords = coords
    msg.payload = b"".join(payload)
    msg.uniform_coords, msg.uniform_values = [], b""
    return msg

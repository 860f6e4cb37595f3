"""Free-space rasterisation of a scene: the explorable volume the scoring compares maps with."""

import numpy as np

from .scene_model import Scene, SceneError


def free_space_grid(scene: Scene, resolution_m: float = 0.1, start=None, margin_m: float = 0.0):
    """Explorable free space: voxels not touched by any surface and 6-connected to the start.

    Surfaces are rasterised by dense sampling (spacing resolution/4), so thin
    walls close the volume. Returns (free bool grid (nx, ny, nz), origin (3,)
    lower corner of voxel (0,0,0), resolution).
    """
    from scipy import ndimage
    lo, hi = scene.bounds
    lo = lo - margin_m
    hi = hi + margin_m
    shape = np.maximum(np.ceil((hi - lo) / resolution_m).astype(int), 1)
    occ = np.zeros(shape, bool)
    step = resolution_m / 4.0
    tri = scene.triangles()
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    lab = np.linalg.norm(b - a, axis=1)
    lac = np.linalg.norm(c - a, axis=1)
    n = np.maximum(np.ceil(np.maximum(lab, lac) / step).astype(int), 1)
    for k in np.unique(n):
        sel = n == k
        # Barycentric lattice with k steps along each edge.
        i, j = np.meshgrid(np.arange(k + 1), np.arange(k + 1), indexing="ij")
        keep = i + j <= k
        u = (i[keep] / k)[None, :, None]
        w = (j[keep] / k)[None, :, None]
        pts = a[sel][:, None] + u * (b[sel] - a[sel])[:, None] + w * (c[sel] - a[sel])[:, None]
        idx = np.floor((pts.reshape(-1, 3) - lo) / resolution_m).astype(int)
        idx = np.clip(idx, 0, shape - 1)
        occ[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    free = ~occ
    if start is None:
        start = scene.start
    if start is None:
        return free, lo, resolution_m
    s = np.floor((np.asarray(start[:3]) - lo) / resolution_m).astype(int)
    if np.any(s < 0) or np.any(s >= shape) or not free[tuple(s)]:
        raise SceneError("start position %s is not in free space" % (list(start[:3]),))
    labels, _ = ndimage.label(free)
    return labels == labels[tuple(s)], lo, resolution_m

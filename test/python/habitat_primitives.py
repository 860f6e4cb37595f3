"""A Habitat-style scene built from boxes, without the house generator: an
L-shaped corridor between two rooms, written as ``<name>_semantic.ply``
(binary PLY: vertices with colour, faces with ``vertex_indices`` and a
0-based ``object_id``, -1 for none) and ``<name>.house`` (``ASCII 1.1`` with
C and O records), the two files a Habitat / Matterport3D scene comes as.

Plan view (z up, 0.5 m cells, floor at z = 0, ceiling at HEIGHT_M). Each
cell edge that borders a cell that is not free gets a wall 0.1 m thick on
the far side, 0.1 m longer at both ends to close corners; where the
corridor meets a room those ends reach 0.1 m into the opening, leaving it
0.8 m wide:

- room A: x in [0, 3), y in [0, 3), a cabinet against its west wall;
- corridor, first leg: x in [3, 6), y in [1, 2) (1 m wide), east from room A;
- corridor, second leg: x in [5, 6), y in [2, 5), north;
- room B: x in [4, 7.5), y in [5, 8), a table in its middle.
"""
import json
import os
import struct

import numpy as np

CELL_M = 0.5
HEIGHT_M = 2.6
WALL_M = 0.1
#: free rectangles (x0, y0, x1, y1), m
FREE = [(0.0, 0.0, 3.0, 3.0), (3.0, 1.0, 6.0, 2.0), (5.0, 2.0, 6.0, 5.0), (4.0, 5.0, 7.5, 8.0)]
#: start pose in room A (x, y, z, yaw), m and rad
START = (1.5, 1.5, 1.2, 0.0)
#: object index (0-based, as in the PLY) -> (category, colour)
OBJECTS = {0: ("wall", (200, 200, 190)), 1: ("floor", (120, 100, 80)), 2: ("ceiling", (230, 230, 230)),
           3: ("cabinet", (90, 60, 40)), 4: ("table", (150, 110, 70))}
#: furniture boxes (object index, (x0, y0, z0), (x1, y1, z1)), m
FURNITURE = [(3, (0.0, 1.8, 0.0), (0.45, 2.8, 0.9)), (4, (5.2, 6.1, 0.0), (6.4, 6.9, 0.75))]


def free_cells():
    """The set of free (i, j) cells of CELL_M."""
    cells = set()
    for x0, y0, x1, y1 in FREE:
        for i in range(int(round(x0 / CELL_M)), int(round(x1 / CELL_M))):
            for j in range(int(round(y0 / CELL_M)), int(round(y1 / CELL_M))):
                cells.add((i, j))
    return cells


def boxes():
    """(object index, lo, hi) of every box of the scene."""
    cells = free_cells()
    out = []
    for (i, j) in sorted(cells):
        x0, y0, x1, y1 = i * CELL_M, j * CELL_M, (i + 1) * CELL_M, (j + 1) * CELL_M
        out.append((1, (x0, y0, -WALL_M), (x1, y1, 0.0)))
        out.append((2, (x0, y0, HEIGHT_M), (x1, y1, HEIGHT_M + WALL_M)))
        # A wall along each edge that borders a cell that is not free, reaching past the corners.
        if (i + 1, j) not in cells:
            out.append((0, (x1, y0 - WALL_M, -WALL_M), (x1 + WALL_M, y1 + WALL_M, HEIGHT_M + WALL_M)))
        if (i - 1, j) not in cells:
            out.append((0, (x0 - WALL_M, y0 - WALL_M, -WALL_M), (x0, y1 + WALL_M, HEIGHT_M + WALL_M)))
        if (i, j + 1) not in cells:
            out.append((0, (x0 - WALL_M, y1, -WALL_M), (x1 + WALL_M, y1 + WALL_M, HEIGHT_M + WALL_M)))
        if (i, j - 1) not in cells:
            out.append((0, (x0 - WALL_M, y0 - WALL_M, -WALL_M), (x1 + WALL_M, y0, HEIGHT_M + WALL_M)))
    out.extend(FURNITURE)
    return out


def box_mesh(lo, hi):
    """8 vertices and 12 outward-facing triangles of an axis-aligned box."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                  [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], dtype=np.float32)
    f = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                  [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]], dtype=np.int32)
    return v, f


def write(directory, name="l_corridor"):
    """Writes the scene and its start pose file; returns the PLY path."""
    os.makedirs(directory, exist_ok=True)
    verts, faces, ids, colours = [], [], [], []
    for oid, lo, hi in boxes():
        v, f = box_mesh(lo, hi)
        faces.append(f + sum(len(x) for x in verts))
        verts.append(v)
        ids.append(np.full(len(f), oid, dtype=np.int32))
        colours.append(np.tile(np.array(OBJECTS[oid][1], dtype=np.uint8), (len(v), 1)))
    v, f, ids, col = np.concatenate(verts), np.concatenate(faces), np.concatenate(ids), np.concatenate(colours)
    ply = os.path.join(directory, name + "_semantic.ply")
    with open(ply, "wb") as out:
        out.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\n"
                   "property float x\nproperty float y\nproperty float z\n"
                   "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                   "element face %d\nproperty list uchar int vertex_indices\nproperty int object_id\n"
                   "end_header\n" % (len(v), len(f))).encode("ascii"))
        for p, c in zip(v, col):
            out.write(struct.pack("<3f3B", *p, *c))
        for tri, oid in zip(f, ids):
            out.write(struct.pack("<B3ii", 3, *tri, oid))
    lo, hi = v.min(0), v.max(0)
    cats = sorted({c for c, _ in OBJECTS.values()})
    lines = ["ASCII 1.1",
             "H %s primitives 0 0 0 0 0 %d %d 0 0 0 0 0 0 0 0 %s 0 0 0 0 0"
             % (name, len(OBJECTS), len(cats), " ".join("%.4f" % x for x in (*lo, *hi)))]
    for k, c in enumerate(cats):
        lines.append("C %d %d %s 0 %s 0 0 0 0 0" % (k, k + 1, c, c))
    for oid, (c, _) in sorted(OBJECTS.items()):
        lines.append("O %d 0 %d 0 0 0 1 0 0 0 1 0 0 0 0 0 0 0 0 0 0 0 0" % (oid, cats.index(c)))
    with open(os.path.join(directory, name + ".house"), "w") as out:
        out.write("\n".join(lines) + "\n")
    with open(os.path.join(directory, name + ".start.json"), "w") as out:
        json.dump({"start": list(START)}, out)
    return ply

"""Seeded generator of indoor scenes: rooms off a corridor, joined by doorways, with furniture.

The house occupies [0, X] x [0, Y] x [0, H] (z up, m). Houses wider than
about 6 m get a corridor along x with rooms on both sides, each room with a
doorway to the corridor and sometimes one to its neighbour; smaller sizes give
one room. Walls, floor and ceiling are boxes (labels wall/floor/ceiling);
exterior walls carry windows and some rooms a mirror (both non-returning).
Furniture is built from parts (boxes, cylinders, spheres) so that each class
is recognisable at 2 cm: chairs around tables and at desks, sofas with
cushions, beds, cabinets, plants, monitors/TVs, backpacks, keyboards.
"""

import math
from typing import List, Optional, Tuple

import numpy as np

from .furniture import armchair, backpack, bed, cabinet, chair, cushion, keyboard, monitor, plant, sofa, table
from .mesh_builder import MeshBuilder, vary_colour
from .scene_model import Scene

WALL_T = 0.1      # wall thickness, m
DOOR_W = 0.95     # doorway width, m
DOOR_H = 2.1      # doorway height, m
CORRIDOR_W = 1.5  # corridor width, m


# ---------------------------------------------------------------------------
# Layout
# ---------------------------------------------------------------------------
class Room:
    def __init__(self, x0, y0, x1, y1, kind):
        self.x0, self.y0, self.x1, self.y1, self.kind = x0, y0, x1, y1, kind
        self.taken: List[Tuple[float, float, float, float]] = []  # reserved footprints (x0, y0, x1, y1)

    def inner(self, margin):
        return self.x0 + margin, self.y0 + margin, self.x1 - margin, self.y1 - margin

    def free(self, rect, clearance=0.08):
        x0, y0, x1, y1 = rect
        ix0, iy0, ix1, iy1 = self.inner(WALL_T / 2 + 0.02)
        if x0 < ix0 or y0 < iy0 or x1 > ix1 or y1 > iy1:
            return False
        for t in self.taken:
            if x0 < t[2] + clearance and x1 > t[0] - clearance and y0 < t[3] + clearance and y1 > t[1] - clearance:
                return False
        return True


def _footprint(pose, half):
    x, y, yaw = pose
    c, s = abs(math.cos(yaw)), abs(math.sin(yaw))
    hx = c * half[0] + s * half[1]
    hy = s * half[0] + c * half[1]
    return (x - hx, y - hy, x + hx, y + hy)


def _wall_pose(rng, room: Room, half, side=None, pos=None):
    """A pose that puts an item of half extents ``half`` with its back against a wall of ``room``."""
    if side is None:
        side = int(rng.integers(4))
    ix0, iy0, ix1, iy1 = room.inner(WALL_T / 2 + 0.03)
    hx, hy = half
    if side == 0:    # south wall, facing +y
        lo, hi = ix0 + hy, ix1 - hy
        p = rng.uniform(lo, hi) if pos is None else pos
        return (p, iy0 + hx, math.pi / 2)
    if side == 1:    # north wall, facing -y
        lo, hi = ix0 + hy, ix1 - hy
        p = rng.uniform(lo, hi) if pos is None else pos
        return (p, iy1 - hx, -math.pi / 2)
    if side == 2:    # west wall, facing +x
        lo, hi = iy0 + hy, iy1 - hy
        p = rng.uniform(lo, hi) if pos is None else pos
        return (ix0 + hx, p, 0.0)
    lo, hi = iy0 + hy, iy1 - hy
    p = rng.uniform(lo, hi) if pos is None else pos
    return (ix1 - hx, p, math.pi)


def _try_place(b, room, half, make, tries=40, side=None, clearance=0.08):
    """Finds a free wall pose for an item and builds it; returns (pose, result) or None."""
    for _ in range(tries):
        try:
            pose = _wall_pose(b.rng, room, half, side)
        except ValueError:
            return None
        rect = _footprint(pose, half)
        if room.free(rect, clearance):
            room.taken.append(rect)
            return pose, make(pose)
    return None


def _local(pose, dx, dy):
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    return (x + c * dx - s * dy, y + s * dx + c * dy)


def _dining_group(b, room, center=None, n_chairs=None):
    rng = b.rng
    length, width = rng.uniform(1.2, 1.8), rng.uniform(0.8, 0.95)
    ix0, iy0, ix1, iy1 = room.inner(WALL_T / 2)
    along_x = (ix1 - ix0) >= (iy1 - iy0)
    for attempt in range(40):
        if attempt == 20:  # small room: a small table
            length, width = 1.0, 0.8
        half = (length / 2 + 0.5, width / 2 + 0.5) if along_x else (width / 2 + 0.5, length / 2 + 0.5)
        if center is None:
            lo_x, hi_x = ix0 + half[0] + 0.1, ix1 - half[0] - 0.1
            lo_y, hi_y = iy0 + half[1] + 0.1, iy1 - half[1] - 0.1
            if lo_x > hi_x or lo_y > hi_y:
                continue
            c = (rng.uniform(lo_x, hi_x), rng.uniform(lo_y, hi_y))
        else:
            c = center
        rect = (c[0] - half[0], c[1] - half[1], c[0] + half[0], c[1] + half[1])
        if room.free(rect):
            break
        if center is not None:
            return False
    else:
        return False
    room.taken.append(rect)
    tpose = (c[0], c[1], math.pi / 2 if along_x else 0.0)  # table local y is its length
    table(b, tpose, length, width)
    n = int(rng.integers(4, 7)) if n_chairs is None else n_chairs
    seats = []
    per_side = max(1, min(3, (n + 1) // 2))
    for side in (-1, 1):
        for k in range(per_side):
            t = (k + 0.5) / per_side - 0.5
            seats.append((side * (width / 2 + 0.12), t * (length - 0.3), math.pi if side > 0 else 0.0))
    for end in (-1, 1):
        seats.append((0.0, end * (length / 2 + 0.14), -end * math.pi / 2))
    rng.shuffle(seats)
    for dx, dy, yaw_local in seats[:n]:
        jitter = rng.uniform(-0.15, 0.15)
        px, py = _local(tpose, dx, dy)
        chair(b, (px, py, tpose[2] + yaw_local + jitter))
    return True


def _desk_group(b, room):
    rng = b.rng
    length, width = rng.uniform(1.1, 1.5), 0.7
    half = (width / 2 + 0.6, length / 2)  # desk + chair space in front
    for _ in range(30):
        try:
            pose = _wall_pose(rng, room, half)
        except ValueError:  # wall too short for the desk
            continue
        rect = _footprint(pose, half)
        if room.free(rect):
            break
    else:
        return False
    room.taken.append(rect)
    dpose = (*_local(pose, -0.6 + 0.0, 0), pose[2])  # desk centre: back part of the footprint
    dpose = (*_local(pose, -half[0] + width / 2, 0), pose[2])
    table(b, dpose, length, width, 0.74)  # table local y (its length) runs along the wall
    monitor(b, (*_local(dpose, -0.12, rng.uniform(-0.2, 0.2)), dpose[2]), 0.74)
    keyboard(b, (*_local(dpose, 0.18, rng.uniform(-0.1, 0.1)), dpose[2]), 0.74)
    cpos = _local(dpose, width / 2 + 0.2, rng.uniform(-0.2, 0.2))
    chair(b, (cpos[0], cpos[1], dpose[2] + math.pi + rng.uniform(-0.4, 0.4)))
    return True


def _furnish(b: MeshBuilder, room: Room, kind: str):
    rng = b.rng
    if kind == "dining":
        _dining_group(b, room)
        _try_place(b, room, (0.23, 0.5), lambda p: cabinet(b, p, 1.0, 0.45, rng.uniform(0.8, 1.6)))
        _try_place(b, room, (0.3, 0.3), lambda p: plant(b, p))
    elif kind == "living":
        r = _try_place(b, room, (0.45, 1.0), lambda p: sofa(b, p, 2.0))
        if r:
            pose = r[0]
            for k in range(int(rng.integers(1, 4))):
                cushion(b, (*_local(pose, -0.2, -0.6 + 0.6 * k + rng.uniform(-0.05, 0.05)),
                            pose[2] + rng.uniform(-0.2, 0.2)), 0.42)
            # Coffee table in front of the sofa (partly hides the sofa's seat).
            cpos = _local(pose, 1.0, 0)
            rect = _footprint((cpos[0], cpos[1], pose[2]), (0.3, 0.55))
            if room.free(rect, 0.0):
                room.taken.append(rect)
                table(b, (cpos[0], cpos[1], pose[2]), 1.1, 0.6, 0.45)
        r = _try_place(b, room, (0.23, 0.6), lambda p: cabinet(b, p, 1.2, 0.45, 0.55))
        if r:
            pose, (_, _, h) = r
            monitor(b, pose, h, big=True)
        _try_place(b, room, (0.45, 0.45), lambda p: armchair(b, p))
        _try_place(b, room, (0.3, 0.3), lambda p: plant(b, p))
    elif kind == "bedroom":
        r = _try_place(b, room, (1.03, 0.75), lambda p: bed(b, (*_local(p, 0, 0), p[2])))
        if r:
            pose = r[0]
            cushion(b, (*_local(pose, -0.65, rng.uniform(-0.3, 0.3)), pose[2] + rng.uniform(-0.3, 0.3)), 0.52)
        _try_place(b, room, (0.2, 0.25), lambda p: cabinet(b, p, 0.5, 0.4, 0.55))
        _try_place(b, room, (0.2, 0.45), lambda p: cabinet(b, p, 0.9, 0.4, rng.uniform(1.2, 2.0)))
        _try_place(b, room, (0.15, 0.17), lambda p: backpack(b, p))
        _try_place(b, room, (0.25, 0.25), lambda p: chair(b, p))
        _try_place(b, room, (0.3, 0.3), lambda p: plant(b, p))
    elif kind == "office":
        _desk_group(b, room)
        if rng.random() < 0.6:
            _desk_group(b, room)
        _try_place(b, room, (0.23, 0.45), lambda p: cabinet(b, p, 0.9, 0.45, rng.uniform(0.8, 1.9)))
        _try_place(b, room, (0.15, 0.17), lambda p: backpack(b, p))
        _try_place(b, room, (0.3, 0.3), lambda p: plant(b, p))
    elif kind == "studio":  # a single room holding a bit of everything
        _dining_group(b, room, n_chairs=4)
        r = _try_place(b, room, (0.45, 1.0), lambda p: sofa(b, p, 2.0))
        if r:
            cushion(b, (*_local(r[0], -0.2, 0.3), r[0][2]), 0.42)
        r = _try_place(b, room, (0.23, 0.5), lambda p: cabinet(b, p, 1.0, 0.45, 0.55))
        if r:
            monitor(b, r[0], r[1][2], big=True)
        _try_place(b, room, (0.15, 0.17), lambda p: backpack(b, p))
        _try_place(b, room, (0.3, 0.3), lambda p: plant(b, p))


def _wall_x(b, oid, color, y, x0, x1, h, openings=()):
    """Wall along x at y from x0 to x1 with door openings [(a, b), ...]."""
    cur = x0
    for a, c in sorted(openings):
        if a > cur:
            b.box_minmax(oid, color, (cur, y - WALL_T / 2, 0), (a, y + WALL_T / 2, h))
        b.box_minmax(oid, color, (a, y - WALL_T / 2, DOOR_H), (c, y + WALL_T / 2, h))
        cur = c
    if cur < x1:
        b.box_minmax(oid, color, (cur, y - WALL_T / 2, 0), (x1, y + WALL_T / 2, h))


def _wall_y(b, oid, color, x, y0, y1, h, openings=()):
    cur = y0
    for a, c in sorted(openings):
        if a > cur:
            b.box_minmax(oid, color, (x - WALL_T / 2, cur, 0), (x + WALL_T / 2, a, h))
        b.box_minmax(oid, color, (x - WALL_T / 2, a, DOOR_H), (x + WALL_T / 2, c, h))
        cur = c
    if cur < y1:
        b.box_minmax(oid, color, (x - WALL_T / 2, cur, 0), (x + WALL_T / 2, y1, h))


def _split(rng, length, min_w=3.0, max_w=5.5):
    """Splits [0, length] into room widths in [min_w, max_w] (one piece if too short)."""
    n = max(1, int(round(length / rng.uniform(min_w + 0.5, max_w))))
    while n > 1 and length / n < min_w:
        n -= 1
    cuts = np.sort(rng.uniform(0.35, 0.65, n - 1) + np.arange(1, n)) * length / n if n > 1 else np.array([])
    return [0.0] + list(cuts) + [length]


def _floor_and_ceiling(b: "MeshBuilder", rng, X: float, Y: float, H: float):
    """Floor and ceiling slabs over an X x Y footprint of height H; returns the wall object id and wall colour."""
    wall_col = vary_colour(rng, (225, 220, 205), 10)
    floor_id, ceil_id, wall_id = b.new_object("floor"), b.new_object("ceiling"), b.new_object("wall")
    b.box_minmax(floor_id, vary_colour(rng, (150, 120, 90), 15), (-WALL_T, -WALL_T, -0.05),
                 (X + WALL_T, Y + WALL_T, 0.0))
    b.box_minmax(ceil_id, (240, 240, 240), (-WALL_T, -WALL_T, H), (X + WALL_T, Y + WALL_T, H + 0.05))
    return wall_id, wall_col


def generate(seed: int = 0, size_m=(15.0, 12.0, 3.0), name: Optional[str] = None) -> Scene:
    """Generates a furnished house of ``size_m`` = (X, Y, H) m, deterministic in ``seed``."""
    X, Y, H = (float(s) for s in size_m)
    if X < 3 or Y < 3 or H < 2.2:
        raise ValueError("house must be at least 3 x 3 x 2.2 m (got %s)" % (size_m,))
    rng = np.random.default_rng(seed)
    b = MeshBuilder(rng)
    wall_id, wall_col = _floor_and_ceiling(b, rng, X, Y, H)
    rooms: List[Room] = []
    windows: List[Tuple[str, float, float, float]] = []  # (axis, fixed coord, lo, hi) on exterior walls
    if X < 6.0 or Y < 5.0:
        rooms.append(Room(0, 0, X, Y, "studio"))
        _wall_x(b, wall_id, wall_col, -WALL_T / 2, -WALL_T, X + WALL_T, H)
        _wall_x(b, wall_id, wall_col, Y + WALL_T / 2, -WALL_T, X + WALL_T, H)
        _wall_y(b, wall_id, wall_col, -WALL_T / 2, 0, Y, H)
        _wall_y(b, wall_id, wall_col, X + WALL_T / 2, 0, Y, H)
        start = (0.5, Y / 2, 1.2, 0.0)
        rooms[0].taken.append((0.0, Y / 2 - 0.4, 0.85, Y / 2 + 0.4))
        windows += [("x", 0.0, 0.5, X - 0.5), ("x", Y, 0.5, X - 0.5)]
    else:
        yc = Y / 2 - CORRIDOR_W / 2 + rng.uniform(-0.1, 0.1) * Y
        y_s, y_n = yc, yc + CORRIDOR_W
        # Exterior walls (the corridor ends get a window each).
        _wall_x(b, wall_id, wall_col, -WALL_T / 2, -WALL_T, X + WALL_T, H)
        _wall_x(b, wall_id, wall_col, Y + WALL_T / 2, -WALL_T, X + WALL_T, H)
        _wall_y(b, wall_id, wall_col, -WALL_T / 2, 0, Y, H)
        _wall_y(b, wall_id, wall_col, X + WALL_T / 2, 0, Y, H)
        kinds = ["dining", "living", "office", "bedroom"]
        rng.shuffle(kinds)
        k = 0
        corridor_doors = {"s": [], "n": []}
        for side, (ya, yb) in (("s", (0.0, y_s)), ("n", (y_n, Y))):
            xs = _split(rng, X)
            for i in range(len(xs) - 1):
                room = Room(xs[i], ya, xs[i + 1], yb, kinds[k % len(kinds)])
                k += 1
                rooms.append(room)
                lo, hi = xs[i] + 0.3 + WALL_T, xs[i + 1] - 0.3 - WALL_T - DOOR_W
                d0 = rng.uniform(lo, hi) if hi > lo else (xs[i] + xs[i + 1] - DOOR_W) / 2
                corridor_doors[side].append((d0, d0 + DOOR_W))
                # Keep the doorway clear on the room side.
                if side == "s":
                    room.taken.append((d0 - 0.2, yb - 1.1, d0 + DOOR_W + 0.2, yb))
                else:
                    room.taken.append((d0 - 0.2, ya, d0 + DOOR_W + 0.2, ya + 1.1))
                if i > 0:
                    # Partition wall, sometimes with a doorway to the neighbour.
                    openings = []
                    if rng.random() < 0.5 and yb - ya > DOOR_W + 1.0:
                        a = rng.uniform(ya + 0.4, yb - 0.4 - DOOR_W)
                        openings.append((a, a + DOOR_W))
                        for r in (rooms[-2], room):
                            r.taken.append((xs[i] - 1.0, a - 0.2, xs[i] + 1.0, a + DOOR_W + 0.2))
                    _wall_y(b, wall_id, wall_col, xs[i], ya, yb, H, openings)
                windows.append(("x", 0.0 if side == "s" else Y, xs[i] + 0.4, xs[i + 1] - 0.4))
        _wall_x(b, wall_id, wall_col, y_s, 0.0, X, H, corridor_doors["s"])
        _wall_x(b, wall_id, wall_col, y_n, 0.0, X, H, corridor_doors["n"])
        corridor = Room(0, y_s, X, y_n, "corridor")
        start = (0.8, (y_s + y_n) / 2, 1.2, 0.0)
        for x in (0.1, X - 0.9):  # plants at the corridor ends, out of the way
            if rng.random() < 0.7:
                plant(b, (x + 0.4, y_n - WALL_T / 2 - 0.32, 0.0))
                corridor.taken.append((x, y_n - 0.7, x + 0.8, y_n))
                if x < start[0]:  # the MAV starts clear of it: the map takes 0.5 m around the start as free
                    start = (1.5,) + start[1:]
    # A mirror on an interior wall of some rooms (partition or corridor side).
    for room in rooms:
        if room.kind in ("bedroom", "living", "studio") and rng.random() < 0.7:
            oid = b.new_object("mirror")
            x = room.x0 + (WALL_T / 2 if room.x0 > 0 else 0.0) + 0.003
            yc = (room.y0 + room.y1) / 2 + rng.uniform(-0.3, 0.3)
            b.box_minmax(oid, (200, 210, 215), (x, yc - 0.35, 0.8), (x + 0.01, yc + 0.35, 1.9))
            room.taken.append((room.x0, yc - 0.4, room.x0 + 0.3, yc + 0.4))
    for room in rooms:
        _furnish(b, room, room.kind)
    # Every house has chairs (the default class of interest): add some along walls if needed.
    for room in rooms * 3:
        if sum(1 for c in b.objects.values() if c == "chair") >= 2:
            break
        _try_place(b, room, (0.25, 0.25), lambda p: chair(b, p))
    # Windows: thin non-returning panels 1 cm in front of exterior walls.
    for axis, y, lo, hi in windows:
        if hi - lo < 1.0:
            continue
        w = min(1.6, hi - lo - 0.2)
        a = rng.uniform(lo, hi - w)
        oid = b.new_object("window")
        inset = 0.01 if y == 0.0 else -0.01
        b.box_minmax(oid, (170, 200, 230), (a, min(y, y + inset) - 0.005, 0.9), (a + w, max(y, y + inset) + 0.005,
                                                                                     min(H - 0.3, 2.2)))
    if name is None:
        name = "gen_s%d_%gx%g" % (seed, X, Y)
    return b.scene(name, start)


def three_chairs_room(seed: int = 0, name: str = "three_chairs") -> Scene:
    """A fixed 6 x 4.5 x 2.5 m room with exactly three chairs, for tests with known objects.

    Chair 1 stands alone in the south-west, chair 2 is pulled up to a table on
    the north side, chair 3 stands in the south-east next to a cabinet; the
    chairs are over 2 m apart, so a camera can hold one in view while another
    is outside it. Only the colours depend on ``seed``. Start: (0.6, 2.25, 1.4, 0).
    """
    X, Y, H = 6.0, 4.5, 2.5
    rng = np.random.default_rng(seed)
    b = MeshBuilder(rng)
    wall_id, wall_col = _floor_and_ceiling(b, rng, X, Y, H)
    _wall_x(b, wall_id, wall_col, -WALL_T / 2, -WALL_T, X + WALL_T, H)
    _wall_x(b, wall_id, wall_col, Y + WALL_T / 2, -WALL_T, X + WALL_T, H)
    _wall_y(b, wall_id, wall_col, -WALL_T / 2, 0, Y, H)
    _wall_y(b, wall_id, wall_col, X + WALL_T / 2, 0, Y, H)
    chair(b, (1.3, 1.0, 0.6))
    table(b, (3.0, 3.75, math.pi / 2), 1.2, 0.7)  # spans x 2.4..3.6, y 3.4..4.1
    chair(b, (3.0, 3.05, math.pi / 2))           # faces the table
    chair(b, (4.6, 1.0, 2.5))
    cabinet(b, (X - 0.25, 2.6, math.pi), 0.9, 0.45, 1.0)
    return b.scene(name, (0.6, Y / 2, 1.4, 0.0))

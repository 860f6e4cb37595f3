"""Kinematic MAV: follows a path of (position, yaw) waypoints within speed, yaw-rate and
acceleration limits, and checks a collision sphere against the scene.

Motion: the velocity is steered towards "straight at the current waypoint" at
a speed that lets the MAV stop (at a_max) at the next vertex where the path
turns, and changed by at most a_max * dt per step; so |v| <= v_max and
|dv/dt| <= a_max hold by construction and straight segments are tracked
exactly. Yaw works the same way with omega_max and alpha_max. The yaw target
of a segment is the yaw of the waypoint it leads to.

Instead of a path the MAV can track a moving setpoint (set_setpoint), as a
flight controller's position control does with a setpoint stream: the
velocity is steered towards the setpoint's own velocity (feed-forward,
estimated by the caller) plus a correction towards it that still lets the
MAV stop there, within the same limits; the setpoint moves on at its
velocity between updates, for at most SETPOINT_HOLD_S.
"""

import math
from typing import List, Optional, Sequence, Tuple

import numpy as np

from .config import MavConfig


def wrap_angle(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


class PathFollower:
    #: Vertices where the path turns by less than this are passed without stopping, rad.
    CORNER_ANGLE_RAD = math.radians(5.0)
    #: Gain of the correction towards a setpoint, 1/s.
    SETPOINT_GAIN = 2.0
    #: A setpoint not renewed for this long stops moving on (its velocity is taken as 0), s.
    SETPOINT_HOLD_S = 0.25

    def __init__(self, cfg: MavConfig, start: Sequence[float]):
        cfg.validate()
        self.cfg = cfg
        self.p = np.array(start[:3], float)
        self.v = np.zeros(3)
        self.yaw = float(start[3])
        self.omega = 0.0
        self.path: List[Tuple[np.ndarray, float]] = []
        self.i = 0
        self._stop_after: List[int] = []
        self._setpoint: Optional[list] = None  # [position, yaw, velocity, yaw rate, age s]

    @property
    def pose(self) -> Tuple[float, float, float, float]:
        return (float(self.p[0]), float(self.p[1]), float(self.p[2]), self.yaw)

    @property
    def active(self) -> bool:
        return bool(self.path)

    def set_setpoint(self, target: Sequence[float], velocity: Sequence[float] = (0.0, 0.0, 0.0),
                     yaw_rate: float = 0.0, age_s: float = 0.0, acceleration: Sequence[float] = (0.0, 0.0, 0.0),
                     yaw_accel: float = 0.0) -> None:
        """Tracks the setpoint (x, y, z, yaw), moving at `velocity` (m/s) and `yaw_rate` (rad/s)
        and changing them at `acceleration` (m/s^2) and `yaw_accel` (rad/s^2), instead of a path
        (which it replaces); `age_s`: how long ago it was sent (it has moved on since, for at most
        SETPOINT_HOLD_S). Never reports a goal reached."""
        self.path = []
        self._setpoint = [np.array(target[:3], float), float(target[3]), np.array(velocity[:3], float),
                          float(yaw_rate), 0.0, np.array(acceleration[:3], float), float(yaw_accel)]
        self._advance_setpoint(min(max(float(age_s), 0.0), self.SETPOINT_HOLD_S))

    def _advance_setpoint(self, dt: float) -> None:
        """Moves the setpoint on by dt at its velocity and acceleration; it slows down to rest
        but never turns back, and stops once SETPOINT_HOLD_S old."""
        sp = self._setpoint
        if sp[4] > self.SETPOINT_HOLD_S:
            sp[2], sp[3], sp[5], sp[6] = np.zeros(3), 0.0, np.zeros(3), 0.0
        v1 = sp[2] + sp[5] * dt
        if float(v1 @ sp[2]) < 0.0:  # braking to rest within dt
            v1, sp[5] = np.zeros(3), np.zeros(3)
        sp[0] = sp[0] + 0.5 * (sp[2] + v1) * dt
        sp[2] = v1
        w1 = sp[3] + sp[6] * dt
        if w1 * sp[3] < 0.0:
            w1, sp[6] = 0.0, 0.0
        sp[1] = wrap_angle(sp[1] + 0.5 * (sp[3] + w1) * dt)
        sp[3] = w1
        sp[4] += dt

    def _step_setpoint(self, dt: float) -> None:
        c = self.cfg
        self._advance_setpoint(dt)  # the setpoint moves on until the next one arrives
        sp = self._setpoint
        e = sp[0] - self.p
        dist = float(np.linalg.norm(e))
        corr = min(self.SETPOINT_GAIN * dist, math.sqrt(2.0 * 0.9 * c.a_max_mps2 * dist))
        self._accelerate(sp[2] + (e / dist * corr if dist > 1e-12 else 0.0), c.a_max_mps2 * dt)
        self.p = self.p + self.v * dt
        e_yaw = wrap_angle(sp[1] - self.yaw)
        w_corr = math.copysign(min(self.SETPOINT_GAIN * abs(e_yaw),
                                   math.sqrt(2.0 * 0.9 * c.alpha_max_radps2 * abs(e_yaw))), e_yaw)
        w_target = max(-c.omega_max_radps, min(c.omega_max_radps, sp[3] + w_corr))
        al_step = c.alpha_max_radps2 * dt
        self.omega += max(-al_step, min(al_step, w_target - self.omega))
        self.yaw = wrap_angle(self.yaw + self.omega * dt)

    def set_path(self, waypoints: Sequence[Sequence[float]]) -> None:
        """Replaces the path (and any setpoint); [] makes the MAV stop where it is (hover)."""
        self._setpoint = None
        self.path = [(np.array(w[:3], float), float(w[3])) for w in waypoints]
        self.i = 0
        n = len(self.path)
        # For each waypoint: index of the next vertex at which the MAV must stop.
        stops = [n - 1] * n
        nxt = n - 1
        for k in range(n - 2, -1, -1):
            a = self.path[k][0] - (self.path[k - 1][0] if k > 0 else self.p)
            b = self.path[k + 1][0] - self.path[k][0]
            na, nb = np.linalg.norm(a), np.linalg.norm(b)
            if na < 1e-9 or nb < 1e-9 or math.acos(np.clip(a @ b / (na * nb), -1, 1)) > self.CORNER_ANGLE_RAD:
                nxt = k
            stops[k] = nxt
        self._stop_after = stops

    def _remaining_to_stop(self) -> float:
        d = np.linalg.norm(self.path[self.i][0] - self.p)
        for k in range(self.i, self._stop_after[self.i]):
            d += np.linalg.norm(self.path[k + 1][0] - self.path[k][0])
        return d

    def step(self, dt: float) -> bool:
        """Advances by dt seconds; returns True once when the path's end is reached."""
        c = self.cfg
        if self._setpoint is not None:
            self._step_setpoint(dt)
            return False
        a_step = c.a_max_mps2 * dt
        # Translation.
        if self.path:
            while True:
                target, _ = self.path[self.i]
                e = target - self.p
                dist = float(np.linalg.norm(e))
                last = self.i == len(self.path) - 1
                pass_through = not last and self._stop_after[self.i] != self.i
                # Pass-through vertices are passed once within a step; stop vertices are left
                # only after the exact arrival below (v = 0), so corners are not cut.
                if not last and ((pass_through and dist <= max(0.5 * c.position_tolerance_m,
                                                               float(np.linalg.norm(self.v)) * dt))
                                 or (not pass_through and dist <= 1e-9 and not self.v.any())):
                    self.i += 1
                    continue
                break
            if dist > 1e-12:
                speed = min(c.v_max_mps, math.sqrt(2.0 * 0.9 * c.a_max_mps2 * self._remaining_to_stop()))
                v_target = e / dist * speed
            else:
                v_target = np.zeros(3)
            if self._stop_after[self.i] == self.i and dist <= np.linalg.norm(self.v) * dt + 1e-12 \
                    and np.linalg.norm(self.v) <= a_step:
                # Arrive exactly: the last bit of braking fits in one step.
                self.v = np.zeros(3)
                self.p = target.copy()
            else:
                self._accelerate(v_target, a_step)
                self.p = self.p + self.v * dt
        else:
            self._accelerate(np.zeros(3), a_step)
            self.p = self.p + self.v * dt
        # Yaw.
        yaw_target = self.path[self.i][1] if self.path else self.yaw
        e_yaw = wrap_angle(yaw_target - self.yaw)
        al_step = c.alpha_max_radps2 * dt
        if abs(e_yaw) <= abs(self.omega) * dt + 1e-12 and abs(self.omega) <= al_step:
            self.yaw = yaw_target if self.path else self.yaw
            self.omega = 0.0
        else:
            w_target = math.copysign(min(c.omega_max_radps, math.sqrt(2.0 * 0.9 * c.alpha_max_radps2 * abs(e_yaw))),
                                     e_yaw) if self.path else 0.0
            dw = max(-al_step, min(al_step, w_target - self.omega))
            self.omega = max(-c.omega_max_radps, min(c.omega_max_radps, self.omega + dw))
            self.yaw = wrap_angle(self.yaw + self.omega * dt)
        # Goal check.
        if self.path and self.i == len(self.path) - 1:
            target, yaw_t = self.path[-1]
            if (np.linalg.norm(target - self.p) <= c.position_tolerance_m
                    and abs(wrap_angle(yaw_t - self.yaw)) <= c.yaw_tolerance_rad
                    and np.linalg.norm(self.v) <= c.speed_tolerance_mps):
                self.path = []
                return True
        return False

    def _accelerate(self, v_target: np.ndarray, a_step: float) -> None:
        dv = v_target - self.v
        n = float(np.linalg.norm(dv))
        if n > a_step:
            dv *= a_step / n
        self.v = self.v + dv
        s = float(np.linalg.norm(self.v))
        if s > self.cfg.v_max_mps:
            self.v *= self.cfg.v_max_mps / s


class SetpointMotion:
    """Velocity and acceleration of a setpoint stream (position, yaw) from consecutive setpoints:
    a flight controller gets positions only. The velocity of the last interval is taken at its
    end by adding the acceleration between the last two intervals; a setpoint that did not move
    is at rest. Intervals longer than max_gap_s start afresh."""

    def __init__(self, max_gap_s: float = 0.5):
        self.max_gap_s = max_gap_s
        self._last = None    # (t, position, yaw)
        self._last_v = None  # (t at the interval's middle, velocity, yaw rate)

    def update(self, t: float, target: Sequence[float]):
        """(velocity, yaw rate, acceleration, yaw acceleration) of the setpoint `target` (x, y, z, yaw) sent at t (s)."""
        p, yaw = np.array(target[:3], float), float(target[3])
        last, last_v = self._last, self._last_v
        self._last = (t, p, yaw)
        zero = (np.zeros(3), 0.0, np.zeros(3), 0.0)
        if last is None or not 0.0 < t - last[0] <= self.max_gap_s:
            self._last_v = None
            return zero
        dt = t - last[0]
        v, w = (p - last[1]) / dt, wrap_angle(yaw - last[2]) / dt
        mid = t - 0.5 * dt
        self._last_v = (mid, v, w)
        if not v.any() and w == 0.0:
            return zero
        if last_v is None or not 0.0 < mid - last_v[0] <= self.max_gap_s:
            return v, w, np.zeros(3), 0.0
        a, alpha = (v - last_v[1]) / (mid - last_v[0]), (w - last_v[2]) / (mid - last_v[0])
        return v + a * 0.5 * dt, w + alpha * 0.5 * dt, a, alpha


def closest_points_on_triangles(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Closest point to p on each triangle (a, b, c are (n, 3)); Ericson's region tests, vectorised."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = vb / denom
        w = vc / denom
        out = a + ab * v[:, None] + ac * w[:, None]  # inside the face
        # Edge regions.
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    out[m] = a[m] + ab[m] * t_ab[m, None]
    m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    out[m] = a[m] + ac[m] * t_ac[m, None]
    m = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    out[m] = b[m] + (c[m] - b[m]) * t_bc[m, None]
    # Vertex regions.
    m = (d1 <= 0) & (d2 <= 0)
    out[m] = a[m]
    m = (d3 >= 0) & (d4 <= d3)
    out[m] = b[m]
    m = (d6 >= 0) & (d5 <= d6)
    out[m] = c[m]
    # Degenerate triangles: nearest vertex.
    bad = ~np.isfinite(out).all(1)
    if bad.any():
        cand = np.stack([a[bad], b[bad], c[bad]], 1)
        k = np.argmin(np.linalg.norm(cand - p, axis=2), 1)
        out[bad] = cand[np.arange(len(k)), k]
    return out


class CollisionChecker:
    """Exact sphere-vs-triangle-mesh test.

    Triangles are binned once into a uniform grid (by their bounding boxes),
    so a query touches only the few cells around the sphere: the cost does not
    grow with the scene (Matterport scenes have ~10^6 triangles).
    """

    def __init__(self, triangles: np.ndarray, radius_m: float, cell_m: float = 0.5):
        self.tri = np.asarray(triangles, float)
        self.radius = float(radius_m)
        self.cell = float(cell_m)
        lo, hi = self.tri.min(1), self.tri.max(1)
        self.origin = lo.min(0) - self.cell
        cmin = np.floor((lo - self.origin) / self.cell).astype(np.int64)
        cmax = np.floor((hi - self.origin) / self.cell).astype(np.int64)
        self.dims = cmax.max(0) + 2
        ext = cmax - cmin + 1
        count = ext.prod(1)
        tri_of = np.repeat(np.arange(len(self.tri)), count)
        k = np.arange(len(tri_of)) - np.repeat(np.cumsum(count) - count, count)  # entry within its triangle
        e = ext[tri_of]
        cells = cmin[tri_of] + np.stack([k % e[:, 0], (k // e[:, 0]) % e[:, 1], k // (e[:, 0] * e[:, 1])], 1)
        keys = (cells[:, 0] * self.dims[1] + cells[:, 1]) * self.dims[2] + cells[:, 2]
        order = np.argsort(keys, kind="stable")
        self._tris = tri_of[order]
        self._keys, self._start, self._count = np.unique(keys[order], return_index=True, return_counts=True)
        self._last = (b"", np.empty(0, np.int64))  # (cell range, its triangles): reused for many steps
        self.clear_margin_m = 0.25  # contact(): how far past the radius a search looks, m
        self._clear_at: Optional[np.ndarray] = None  # contact(): where the last search found the sphere clear
        self._clearance_m = 0.0  # ... and the distance to the mesh there (at least this)
        self.searches = 0  # contact()'s searches

    def _candidates(self, p: np.ndarray, r: float) -> np.ndarray:
        c0 = np.floor((p - r - self.origin) / self.cell).astype(np.int64)
        c1 = np.floor((p + r - self.origin) / self.cell).astype(np.int64)
        c0, c1 = np.maximum(c0, 0), np.minimum(c1, self.dims - 1)
        key = c0.tobytes() + c1.tobytes()
        if key != self._last[0]:
            self._last = (key, self._cells_candidates(c0, c1))
        return self._last[1]

    def _cells_candidates(self, c0: np.ndarray, c1: np.ndarray) -> np.ndarray:
        """Triangles binned into the cells c0..c1 (inclusive, clipped to the grid)."""
        if np.any(c1 < c0):
            return np.empty(0, np.int64)
        g = np.stack(np.meshgrid(*[np.arange(a, b + 1) for a, b in zip(c0, c1)], indexing="ij"), -1).reshape(-1, 3)
        keys = (g[:, 0] * self.dims[1] + g[:, 1]) * self.dims[2] + g[:, 2]
        pos = np.searchsorted(self._keys, keys)
        ok = pos < len(self._keys)
        pos, keys = pos[ok], keys[ok]
        pos = pos[self._keys[pos] == keys]
        if len(pos) == 0:
            return np.empty(0, np.int64)
        return np.unique(np.concatenate([self._tris[self._start[i]:self._start[i] + self._count[i]] for i in pos]))

    def nearest(self, p: Sequence[float], radius: Optional[float] = None) -> Tuple[float, int]:
        """(distance, triangle index) of the nearest triangle within ``radius`` of p; (inf, -1) if none."""
        r = self.radius if radius is None else radius
        p = np.asarray(p, float)
        cand = self._candidates(p, r)
        if len(cand) == 0:
            return math.inf, -1
        t = self.tri[cand]
        q = closest_points_on_triangles(p, t[:, 0], t[:, 1], t[:, 2])
        d = np.linalg.norm(q - p, axis=1)
        k = int(np.argmin(d))
        if d[k] > r:
            return math.inf, -1
        return float(d[k]), int(cand[k])

    def collides(self, p: Sequence[float]) -> bool:
        return self.nearest(p)[1] >= 0

    def contact(self, p: Sequence[float]) -> Tuple[float, int]:
        """nearest(p) with the sphere's own radius, for a point that moves in small steps (the
        physics loop): the same answer, searched for only when the sphere may touch something.

        A search looks ``clear_margin_m`` beyond the radius. Distance to the mesh changes by at
        most as much as the point moves, so a point found at clearance c (>= that reach when
        nothing was found) cannot touch anything until it has moved c - radius away."""
        p = np.asarray(p, float)
        if self._clear_at is not None and \
                float(np.linalg.norm(p - self._clear_at)) < self._clearance_m - self.radius - 1e-9:
            return math.inf, -1  # (1 nm below the bound: rounding in the distances cannot tip it)
        self.searches += 1
        reach_m = self.radius + self.clear_margin_m
        d, k = self.nearest(p, reach_m)
        if k >= 0 and d <= self.radius:
            self._clear_at = None
            return self.nearest(p)  # the radius's own search: the same triangle where several are as near
        self._clear_at, self._clearance_m = p.copy(), (d if k >= 0 else reach_m)
        return math.inf, -1

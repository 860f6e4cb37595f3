"""Kinematic MAV: limits, goal reaching, path tracking and collision detection."""
import math

import numpy as np
import pytest

from semantic_exploration.sim.config import MavConfig  # noqa: E402
from semantic_exploration.sim.generator import generate  # noqa: E402
from semantic_exploration.sim.mav import (CollisionChecker, PathFollower, closest_points_on_triangles,  # noqa: E402
                                          wrap_angle)


def fly(cfg, start, path, t_max=120.0):
    f = PathFollower(cfg, start)
    f.set_path(path)
    dt = 1.0 / cfg.physics_rate_hz
    log = [(f.p.copy(), f.v.copy(), f.yaw, f.omega)]
    for k in range(int(t_max / dt)):
        done = f.step(dt)
        log.append((f.p.copy(), f.v.copy(), f.yaw, f.omega))
        if done:
            return f, log, (k + 1) * dt
    return f, log, None


PATHS = [
    [(0, 0, 1, 0), (4, 0, 1, 0)],
    [(0, 0, 1, 0), (2, 0, 1, 1.0), (2, 3, 1.5, 2.5), (-1, 3, 1.5, -2.8)],
    [(0, 0, 1, 0), (1, 0.02, 1, 0), (2, 0, 1, 0), (3, 0.01, 1, 0.5)],   # nearly straight: no stops
    [(0, 0, 1, 0), (0.3, 0, 1, 3.0)],                                    # short hop, large yaw change
]


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("cfg", [MavConfig(), MavConfig(v_max_mps=0.5, a_max_mps2=0.3, omega_max_radps=0.4,
                                                         alpha_max_radps2=0.5, physics_rate_hz=50.0)])
def test_follower_respects_limits_and_reaches_goal(path, cfg):
    f, log, t = fly(cfg, (0, 0, 1, 0), path)
    assert t is not None, "goal not reached"
    dt = 1.0 / cfg.physics_rate_hz
    p = np.array([e[0] for e in log])
    v = np.array([e[1] for e in log])
    yaw = np.array([e[2] for e in log])
    om = np.array([e[3] for e in log])
    eps = 1e-9
    assert np.max(np.linalg.norm(v, axis=1)) <= cfg.v_max_mps + eps
    assert np.max(np.linalg.norm(np.diff(v, axis=0), axis=1)) / dt <= cfg.a_max_mps2 + 1e-6
    # Position moves consistently with the velocity (no teleporting), except the final snap of < 1 step.
    steps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    assert np.max(steps) <= cfg.v_max_mps * dt + 1e-9
    assert np.max(np.abs(om)) <= cfg.omega_max_radps + eps
    assert np.max(np.abs(np.diff(om))) / dt <= cfg.alpha_max_radps2 + 1e-6
    dyaw = np.abs([wrap_angle(b - a) for a, b in zip(yaw[:-1], yaw[1:])])
    assert np.max(dyaw) <= cfg.omega_max_radps * dt + 1e-9
    end = np.array(path[-1][:3], float)
    assert np.linalg.norm(p[-1] - end) <= cfg.position_tolerance_m
    assert abs(wrap_angle(yaw[-1] - path[-1][3])) <= cfg.yaw_tolerance_rad
    assert not f.active
    # Lower bound on the time: path length at v_max.
    length = sum(np.linalg.norm(np.subtract(b[:3], a[:3])) for a, b in zip(path[:-1], path[1:]))
    assert t >= length / cfg.v_max_mps - 1e-9


def test_follower_tracks_straight_segments_and_stops_at_corners():
    path = [(0, 0, 1, 0), (3, 0, 1, 0), (3, 2, 1, 0)]
    f, log, t = fly(MavConfig(), (0, 0, 1, 0), path)
    p = np.array([e[0] for e in log])
    first = p[:, 0] < 3.0 - 1e-6
    assert np.max(np.abs(p[first, 1])) < 1e-6  # stays on the first segment's line
    after = p[:, 1] > 1e-6
    assert np.max(np.abs(p[after, 0] - 3.0)) < 1e-6  # and on the second's
    # A straight 4 m hop at v_max 1.5, a_max 1: accelerate 1.5 s, cruise, brake ~1.5 s: ~4.2 s.
    _, _, t = fly(MavConfig(), (0, 0, 1, 0), [(4, 0, 1, 0)])
    assert 4.1 < t < 5.0


def test_follower_hovers_without_a_path_and_stops_on_empty_path():
    f = PathFollower(MavConfig(), (1, 2, 3, 0.5))
    for _ in range(100):
        assert not f.step(0.01)
    assert f.pose == (1, 2, 3, 0.5)
    f.set_path([(5, 2, 3, 0.5)])
    for _ in range(100):
        f.step(0.01)
    assert np.linalg.norm(f.v) > 0.5
    f.set_path([])
    for _ in range(300):
        f.step(0.01)
    assert np.linalg.norm(f.v) == 0.0


def test_closest_points_match_brute_force():
    rng = np.random.default_rng(0)
    tri = rng.normal(size=(200, 3, 3))
    for _ in range(20):
        p = rng.normal(size=3) * 2
        q = closest_points_on_triangles(p, tri[:, 0], tri[:, 1], tri[:, 2])
        # Brute force: dense barycentric sampling must never beat the closed form.
        u, v = np.meshgrid(np.linspace(0, 1, 41), np.linspace(0, 1, 41))
        keep = u + v <= 1
        pts = tri[:, 0, None] + u[keep][None, :, None] * (tri[:, 1] - tri[:, 0])[:, None] \
            + v[keep][None, :, None] * (tri[:, 2] - tri[:, 0])[:, None]
        brute = np.linalg.norm(pts - p, axis=2).min(1)
        exact = np.linalg.norm(q - p, axis=1)
        assert np.all(exact <= brute + 1e-12)
        assert np.all(brute - exact < 0.05)


def test_collision_distance_to_a_box_is_analytic():
    s = generate(0, (4, 4, 2.7))
    cc = CollisionChecker(s.triangles(), 0.125)
    # 0.1 m below the ceiling (z = 2.7), far from the walls: collision with the ceiling.
    d, k = cc.nearest((2.0, 2.0, 2.6))
    assert k >= 0 and d == pytest.approx(0.1, abs=1e-9)
    assert s.objects[int(s.face_object[k])] == "ceiling"
    assert cc.nearest((2.0, 2.0, 2.5)) == (math.inf, -1)
    assert not cc.collides((0.5, 2.0, 1.2))  # the start pose is free


def test_collision_grid_matches_brute_force():
    s = generate(2, (8, 6, 3))
    tri = s.triangles()
    cc = CollisionChecker(tri, 0.3, cell_m=0.4)
    rng = np.random.default_rng(1)
    hits = 0
    for p in rng.uniform([-0.5, -0.5, -0.3], [8.5, 6.5, 3.3], (300, 3)):
        q = closest_points_on_triangles(p, tri[:, 0], tri[:, 1], tri[:, 2])
        d = np.linalg.norm(q - p, axis=1)
        got_d, got_k = cc.nearest(p)
        if d.min() <= 0.3:
            hits += 1
            assert got_k >= 0 and got_d == pytest.approx(d.min(), abs=1e-12)
        else:
            assert got_k == -1
    assert 30 < hits < 270



def test_collision_grid_matches_brute_force_along_a_walk():
    """Small steps reuse the last cell range's triangles; a query with another radius in between
    (another range) must not leave a stale set behind."""
    s = generate(2, (8, 6, 3))
    tri = s.triangles()
    cc = CollisionChecker(tri, 0.3, cell_m=0.4)
    hits = 0
    for k, x in enumerate(np.arange(0.2, 7.8, 0.013)):
        p = np.array([x, 3.0 + 0.8 * math.sin(x), 1.0])
        q = closest_points_on_triangles(p, tri[:, 0], tri[:, 1], tri[:, 2])
        d = np.linalg.norm(q - p, axis=1)
        for r in ((0.3, 2.0) if k % 37 == 0 else (0.3,)):
            got_d, got_k = cc.nearest(p, r)
            if d.min() <= r:
                hits += r == 0.3
                assert got_k >= 0 and got_d == pytest.approx(d.min(), abs=1e-12)
            else:
                assert got_k == -1
    assert 20 < hits < 500


def test_contact_is_nearest_along_a_walk_with_fewer_searches():
    """contact() skips the search while the sphere provably stays clear; along a walk that grazes
    walls and a jump across the house it must give exactly nearest()'s answer at every step, with
    searches that found something within the reach and searches that found nothing."""
    s = generate(2, (8, 6, 3))
    cc = CollisionChecker(s.triangles(), 0.3, cell_m=0.4)
    ref = CollisionChecker(s.triangles(), 0.3, cell_m=0.4)
    points = [np.array([x, 3.0 + 2.9 * math.sin(x), 1.0 + 1.1 * math.cos(0.7 * x)])
              for x in np.arange(0.2, 7.8, 0.01)]
    points.insert(len(points) // 2, np.array([7.5, 0.5, 2.5]))  # a teleport across the house
    hits, near, nothing = 0, 0, 0
    for p in points:
        searches = cc.searches
        got = cc.contact(p)
        assert got == ref.nearest(p), p
        hits += got[1] >= 0
        if got[1] < 0 and cc.searches > searches:  # a search that found the sphere clear
            reach_m = cc.radius + cc.clear_margin_m
            near += cc._clearance_m < reach_m
            nothing += cc._clearance_m == reach_m
    assert near > 10 and nothing > 0
    clear = len(points) - hits
    assert hits > 10 and clear > 100
    # Every step in contact searches; of the clear ones (1 cm steps), only a few.
    assert cc.searches - hits < clear // 4


def test_path_through_a_wall_is_reported_as_collision():
    s = generate(0, (8, 6, 3))
    cfg = MavConfig()
    cc = CollisionChecker(s.triangles(), cfg.radius_m)
    start = s.start
    assert not cc.collides(start[:3])
    # Straight south from the corridor, through the corridor wall into a room and on through the outer wall.
    f = PathFollower(cfg, start)
    f.set_path([(start[0], -0.5, start[2], 0.0)])
    hits, inside = [], False
    for _ in range(2000):
        f.step(1.0 / cfg.physics_rate_hz)
        c = cc.collides(f.p)
        if c and not inside:
            hits.append(f.p.copy())
        inside = c
    walls = [y for y in (0.0,) + tuple(np.unique([round(p[1], 0) for p in hits]))]
    assert len(hits) >= 2, walls  # corridor wall and exterior wall
    assert min(abs(h[1] - 0.0) for h in hits) < cfg.radius_m + 0.06

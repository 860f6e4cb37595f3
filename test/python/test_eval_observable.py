"""Observable ground truth (eval.observable) on analytic scenes: a closed room
with one box standing on the floor and one pressed against a wall."""
import os

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")
pytest.importorskip("embreex")

from semantic_exploration.eval import metrics, observable  # noqa: E402
from semantic_exploration.sim.scene import Scene, export_ground_truth  # noqa: E402

ROOM = (4.0, 4.0, 3.0)
BOX_FLOOR = ((1.5, 1.5, 0.0), (2.0, 2.0, 0.5))   # 0.5 m cube on the floor, mid-room
BOX_WALL = ((3.6, 1.8, 0.0), (4.0, 2.2, 0.8))    # 0.4 x 0.4 x 0.8 m, its +x face on the wall x = 4
BOX_SLOT = ((0.8, 3.45, 0.0), (1.2, 3.85, 0.8))  # the same, its +y face 0.15 m from the wall y = 4
START = (1.0, 3.0, 1.2, 0.0)


def _box(lo, hi):
    m = trimesh.creation.box(extents=np.subtract(hi, lo))
    m.apply_translation(np.add(lo, hi) / 2.0)
    return np.asarray(m.vertices), np.asarray(m.faces)


def _room_scene():
    """Floor, ceiling and four 0.1 m walls (boxes) around ROOM, the two boxes as chairs."""
    x, y, h = ROOM
    t = 0.1
    parts = [((-t, -t, -0.05), (x + t, y + t, 0.0), 1), ((-t, -t, h), (x + t, y + t, h + 0.05), 2),
             ((-t, -t, 0.0), (0.0, y + t, h), 3), ((x, -t, 0.0), (x + t, y + t, h), 3),
             ((0.0, -t, 0.0), (x, 0.0, h), 3), ((0.0, y, 0.0), (x, y + t, h), 3),
             (BOX_FLOOR[0], BOX_FLOOR[1], 4), (BOX_WALL[0], BOX_WALL[1], 5), (BOX_SLOT[0], BOX_SLOT[1], 6)]
    verts, faces, ids, n = [], [], [], 0
    for lo, hi, oid in parts:
        v, f = _box(lo, hi)
        verts.append(v)
        faces.append(f + n)
        ids.append(np.full(len(f), oid))
        n += len(v)
    return Scene(np.vstack(verts), np.vstack(faces), np.concatenate(ids),
                 objects={1: "floor", 2: "ceiling", 3: "wall", 4: "chair", 5: "chair", 6: "chair"}, start=START, name="room")


def _face_grid(lo, hi, axis, side, step=0.02, inset=0.005):
    """Points on one face of box [lo, hi] (axis 0/1/2, side 0 = min, 1 = max), inset from its edges."""
    a, b = [i for i in range(3) if i != axis]
    u = np.arange(lo[a] + inset, hi[a] - inset + 1e-9, step)
    v = np.arange(lo[b] + inset, hi[b] - inset + 1e-9, step)
    uu, vv = np.meshgrid(u, v)
    p = np.zeros((uu.size, 3))
    p[:, a], p[:, b] = uu.ravel(), vv.ravel()
    p[:, axis] = (lo, hi)[side][axis]
    return p


@pytest.fixture(scope="module")
def gt(tmp_path_factory):
    d = str(tmp_path_factory.mktemp("gt"))
    export_ground_truth(_room_scene(), d, ["chair"])
    return metrics.load_ground_truth(d)


@pytest.fixture(scope="module")
def obs(gt):
    return observable.for_ground_truth(gt)


def test_box_on_the_floor_hides_only_its_bottom(obs):
    lo, hi = BOX_FLOOR
    assert not obs.mask(_face_grid(lo, hi, 2, 0)).any()  # bottom, on the floor
    for axis, side in ((2, 1), (0, 0), (0, 1), (1, 0), (1, 1)):  # top and the four sides
        assert obs.mask(_face_grid(lo, hi, axis, side)).all(), (axis, side)


def test_face_against_a_wall_is_hidden(obs):
    lo, hi = BOX_WALL
    assert not obs.mask(_face_grid(lo, hi, 0, 1)).any()  # +x face on the wall x = 4
    assert not obs.mask(_face_grid(lo, hi, 2, 0)).any()  # bottom
    for axis, side in ((2, 1), (0, 0), (1, 0), (1, 1)):
        assert obs.mask(_face_grid(lo, hi, axis, side)).all(), (axis, side)
    # The wall behind the box is hidden where the box covers it, seen around it.
    wall = _face_grid((4.0, 1.0, 0.0), (4.0, 3.0, 2.0), 0, 0, step=0.05)
    behind = (wall[:, 1] > 1.8) & (wall[:, 1] < 2.2) & (wall[:, 2] < 0.8)
    seen = obs.mask(wall)
    assert not seen[behind].any() and seen[~behind].all()


def test_a_face_seen_only_at_grazing_incidence_is_hidden(obs):
    # A camera centre R = 0.125 m from the wall is at most 2.5 cm behind the
    # plane of the face 0.15 m in front of it, and at least R beside the box:
    # it could only see the face within atan(0.025 / 0.125) = 11 deg of
    # grazing, beyond the 75 deg incidence limit. The other faces are seen.
    lo, hi = BOX_SLOT
    normal = {0: [1.0, 0, 0], 1: [0, 1.0, 0], 2: [0, 0, 1.0]}
    for axis, side, seen in ((1, 1, False), (2, 1, True), (0, 0, True), (0, 1, True), (1, 0, True)):
        p = _face_grid(lo, hi, axis, side)
        m = obs.mask(p, np.tile(normal[axis], (len(p), 1)))
        assert (m.all() if seen else not m.any()), (axis, side)


def test_the_outside_of_the_room_is_hidden(obs):
    # Outer faces of the walls and the floor's underside: no camera gets there.
    assert not obs.mask(_face_grid((-0.1, 0.0, 0.0), (-0.1, 4.0, 3.0), 0, 0, step=0.1)).any()
    assert not obs.mask(_face_grid((-0.1, -0.1, -0.05), (4.1, 4.1, -0.05), 2, 0, step=0.1)).any()


def test_vertical_field_of_view_limits_what_is_seen():
    # A 0.6 x 0.6 m well with 1 m high walls: its floor's centre is seen from
    # above the rim at elevations of at least atan(1.0 / 0.3) = 73 deg, and
    # from inside (camera >= R = 0.125 m from walls and floor, so within
    # 0.175 m horizontally and at least 0.125 m up) at least 35 deg; a level
    # camera sees +-24.5 deg, one pitched 60 deg down sees 35.5..84.5 deg.
    sc = _room_scene()
    (x0, y0), (x1, y1), t, h = (2.6, 0.4), (3.2, 1.0), 0.05, 1.0
    walls = [((x0 - t, y0 - t, 0), (x0, y1 + t, h)), ((x1, y0 - t, 0), (x1 + t, y1 + t, h)),
             ((x0, y0 - t, 0), (x1, y0, h)), ((x0, y1, 0), (x1, y1 + t, h))]
    verts, faces, n = [sc.vertices], [sc.faces], len(sc.vertices)
    for lo, hi in walls:
        v, f = _box(lo, hi)
        verts.append(v)
        faces.append(f + n)
        n += len(v)
    v, f = np.vstack(verts), np.vstack(faces)
    floor = np.array([[2.9, 0.7, 0.0], [2.85, 0.75, 0.0]])
    assert not observable.Observability(v, f, START).mask(floor).any()
    down = observable.ViewModel(pitch_rad=np.radians(60.0))
    assert observable.Observability(v, f, START, down).mask(floor).all()


def test_view_model_defaults_are_the_simulators(tmp_path):
    import yaml
    root = os.path.join(os.path.dirname(__file__), "..", "..")
    with open(os.path.join(root, "config", "sim.yaml")) as f:
        sim = yaml.safe_load(f)
    assert observable.ViewModel.from_sim_config(sim) == observable.ViewModel()
    lo, hi = observable.ViewModel().elevation_band_rad()
    assert lo == pytest.approx(-np.arctan(119.5 / 262.5)) and hi == pytest.approx(np.arctan(119.5 / 262.5))


def test_completeness_counts_the_observable_surface_only(gt, tmp_path):
    # A reconstruction of exactly what can be seen of the floor box (its top
    # and sides) is complete; against the whole surface it would miss the
    # bottom: 0.25 of 1.5 m^2, completeness 5/6.
    lo, hi = BOX_FLOOR
    pts = np.vstack([_face_grid(lo, hi, a, s, step=0.01) for a, s in ((2, 1), (0, 0), (0, 1), (1, 0), (1, 1))])
    trimesh.PointCloud(pts).export(str(tmp_path / "4.ply"))
    rec = {"dir": str(tmp_path), "objects": [{"id": 4, "class_name": "chair", "mesh": "4.ply"}]}
    ev = metrics.evaluate_objects(gt, rec, ["chair"])
    (m,) = ev.matches
    assert m.gt_id == 4 and m.score.completeness == pytest.approx(1.0, abs=0.01)
    assert ev.observable_fraction[4] == pytest.approx(5.0 / 6.0, abs=0.01)
    assert ev.observable_fraction[5] == pytest.approx(1.0 - (0.16 + 0.32) / 1.6, abs=0.01)  # bottom, wall side
    whole = metrics.evaluate_objects(gt, rec, ["chair"], observable_only=False)
    # The bottom's rim within 5 cm of the side samples (0.5 cm up) counts too.
    assert whole.matches[0].score.completeness == pytest.approx(5.0 / 6.0 + (0.25 - 0.4 ** 2) / 1.5, abs=0.01)


def test_background_completeness_counts_the_inside_of_the_room(gt):
    # Occupied points on every inner surface of the room and on the faces of
    # the three boxes a camera sees: complete against the observable surface of the scene
    # (floor top, ceiling underside, the walls' inner faces less what the boxes
    # cover, the boxes' faces but their bottoms, BOX_WALL's face on the wall
    # and BOX_SLOT's face seen only at grazing incidence), which is that share
    # of the whole surface (the walls' outer faces and the slabs' far sides hidden).
    x, y, h = ROOM
    inner = [_face_grid((0, 0, 0), (x, y, 0), 2, 0, step=0.02, inset=0.0),
             _face_grid((0, 0, h), (x, y, h), 2, 0, step=0.02, inset=0.0),
             _face_grid((0, 0, 0), (0, y, h), 0, 0, step=0.02, inset=0.0),
             _face_grid((x, 0, 0), (x, y, h), 0, 0, step=0.02, inset=0.0),
             _face_grid((0, 0, 0), (x, 0, h), 1, 0, step=0.02, inset=0.0),
             _face_grid((0, y, 0), (x, y, h), 1, 0, step=0.02, inset=0.0)]
    seen_faces = {BOX_FLOOR: ((2, 1), (0, 0), (0, 1), (1, 0), (1, 1)), BOX_WALL: ((2, 1), (0, 0), (1, 0), (1, 1)),
                  BOX_SLOT: ((2, 1), (0, 0), (0, 1), (1, 0))}
    inner += [_face_grid(lo, hi, a, side, step=0.02, inset=0.0) for (lo, hi), faces in seen_faces.items()
              for a, side in faces]
    s = metrics.evaluate_background(gt, np.vstack(inner))
    assert s.completeness == pytest.approx(1.0, abs=0.005)
    total = sum(trimesh.load(os.path.join(gt["dir"], m), force="mesh").area
                for m in [gt["background_mesh"]] + [o["mesh"] for o in gt["objects"]])
    boxes = 0.5 * 0.5 + 2 * 0.4 * 0.4 + 0.4 * 0.8  # footprints on the floor, BOX_WALL's face on the wall
    box_faces = 5 * 0.25 + 2 * (0.16 + 3 * 0.32)   # top and 4 sides; top and 3 sides of BOX_WALL and BOX_SLOT
    assert s.observable_fraction == pytest.approx((2 * x * y + 2 * (x + y) * h - boxes + box_faces) / total,
                                                  abs=0.01)
    whole = metrics.evaluate_background(gt, np.vstack(inner), observable_only=False)
    # Against the whole surface, hidden samples count as missing unless a point
    # lies within 5 cm: the floor under the boxes and their bottoms, the wall
    # behind BOX_WALL and its face against it (1.8 m^2, 1% of the surface) and
    # 5 cm rims of other hidden faces.
    assert s.observable_fraction <= whole.completeness <= s.observable_fraction + 0.04
    assert whole.completeness < 0.5

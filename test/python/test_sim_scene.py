"""Scene generator, Habitat/JSON loaders and ground-truth export (known answers, temp dirs only)."""
import collections
import json
import math
import os

import numpy as np
import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))

from semantic_exploration.sim.classes import DEFAULT_CLASS_NAMES  # noqa: E402
from semantic_exploration.sim.generator import generate, three_chairs_room  # noqa: E402
from semantic_exploration.sim.mav import CollisionChecker  # noqa: E402
from semantic_exploration.sim.scene import (Scene, SceneError, export_ground_truth, load_habitat,  # noqa: E402
                                            load_scene, read_house, save_habitat,
                                            write_semantic_ply)

EXAMPLE = os.path.join(ROOT, "test", "data", "example_semantic.ply")


def test_generator_is_deterministic_in_seed():
    a, b, c = generate(5, (8, 6, 3)), generate(5, (8, 6, 3)), generate(6, (8, 6, 3))
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.face_object, b.face_object)
    assert a.objects == b.objects
    assert len(a.vertices) != len(c.vertices) or not np.allclose(a.vertices, c.vertices)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_house_has_rooms_furniture_and_non_returning_surfaces(seed):
    s = generate(seed, (15, 12, 3))
    lo, hi = s.bounds
    assert np.allclose(lo, [-0.1, -0.1, -0.05]) and np.allclose(hi, [15.1, 12.1, 3.05])
    counts = collections.Counter(s.objects.values())
    things = {c for c in counts if c in DEFAULT_CLASS_NAMES}
    assert len(things) >= 6, counts
    assert counts["chair"] >= 2 and counts["window"] >= 1
    assert set(counts) - set(DEFAULT_CLASS_NAMES) <= {"wall", "floor", "ceiling", "window", "mirror"}
    # Every labelled object owns faces, and every face belongs to a labelled object.
    assert set(np.unique(s.face_object)) == set(s.objects)
    assert s.non_returning_faces(["window", "mirror"]).any()


@pytest.mark.parametrize("size", [(8, 6, 3), (6, 5, 3), (6, 7, 3), (10, 8, 3), (15, 12, 3)])
def test_start_pose_is_clear_of_the_space_the_map_takes_as_free(size):
    """background_map/start_free_radius_m (0.5 m) of unknown space around the start is taken as free: nothing
    may lie there (a plant at the corridor's end once stood 0.23-0.45 m from the start)."""
    import yaml
    with open(os.path.join(os.path.dirname(__file__), "..", "..", "config", "semantic.yaml")) as f:
        r_free = yaml.safe_load(f)["background_map"]["start_free_radius_m"]
    for seed in range(8):
        s = generate(seed, size)
        # The simulator's own collision check (nearest triangle within a radius), the one that saw the MAV graze it.
        d, _ = CollisionChecker(s.triangles(), radius_m=r_free + 0.1).nearest(s.start[:3])
        assert d == math.inf, "seed %d: start %s is %.2f m from the scene" % (seed, s.start, d)


def test_chairs_stand_close_to_tables():
    s = generate(1, (4, 4, 2.7))  # studio with a dining group
    cents = {}
    for oid, c in s.objects.items():
        v = s.vertices[s.faces[s.face_object == oid].reshape(-1)]
        cents[oid] = (c, v.mean(0))
    tables = [p for c, p in cents.values() if c == "table"]
    chairs = [p for c, p in cents.values() if c == "chair"]
    assert tables and len(chairs) >= 4
    near = [min(np.linalg.norm((ch - t)[:2]) for t in tables) for ch in chairs]
    assert sum(d < 1.2 for d in near) >= 4


def test_example_scene_loads_with_its_house_table():
    assert os.path.getsize(EXAMPLE) < 300_000
    s = load_scene(EXAMPLE)
    house = read_house(EXAMPLE.replace("_semantic.ply", ".house"))
    assert s.objects == house
    assert s.name == "example"
    counts = collections.Counter(s.objects.values())
    assert counts["chair"] == 4 and counts["table"] == 1 and counts["window"] == 2
    assert set(np.unique(s.face_object)) == set(house)
    assert s.start == (0.5, 1.5, 1.2, 0.0)
    # Same scene as the generator makes (float32 vertices in the file).
    g = generate(0, (3.5, 3, 2.5), "example")
    assert np.allclose(s.triangles(), g.triangles(), atol=1e-5)
    assert np.array_equal(s.face_object, g.face_object)
    assert np.array_equal(s.face_colors, g.face_colors)


def test_three_chairs_scene_is_the_generators_and_has_three_separate_chairs():
    path = os.path.join(os.path.dirname(EXAMPLE), "three_chairs_semantic.ply")
    s = load_scene(path)
    assert s.name == "three_chairs" and s.start == (0.6, 2.25, 1.4, 0.0)
    counts = collections.Counter(s.objects.values())
    assert counts["chair"] == 3 and counts["table"] == 1 and counts["cabinet"] == 1
    g = three_chairs_room()
    assert np.allclose(s.triangles(), g.triangles(), atol=1e-5)
    assert np.array_equal(s.face_object, g.face_object) and np.array_equal(s.face_colors, g.face_colors)
    chairs = [s.vertices[np.unique(s.faces[s.face_object == i])] for i, c in s.objects.items() if c == "chair"]
    centres = [(v.min(0) + v.max(0)) / 2 for v in chairs]
    for i in range(3):
        for j in range(i):
            assert np.linalg.norm((centres[i] - centres[j])[:2]) > 2.0


def test_matterport_object_indices_start_at_zero(tmp_path):
    """Habitat's files: face object_id = .house object index (0-based), -1 = no object."""
    import struct
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    body = b"".join(struct.pack("<fffBBB", *p, 10, 20, 30) for p in v)
    faces = [(0, 1, 2, 0), (0, 2, 1, 1), (1, 2, 0, -1)]
    body += b"".join(struct.pack("<Biiii", 3, a, b, c, o) for a, b, c, o in faces)
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 3\n"
              "property list uchar int vertex_indices\nproperty int object_id\nend_header\n")
    (tmp_path / "m_semantic.ply").write_bytes(header.encode() + body)
    (tmp_path / "m.house").write_text("ASCII 1.1\nC 0 3 chair 3 chair 0 0 0 0 0\nC 1 1 wall 1 wall 0 0 0 0 0\n"
                                      "O 0 0 0 0 0 0\nO 1 0 1 0 0 0\n")
    s = load_scene(str(tmp_path / "m_semantic.ply"))
    assert s.objects == {1: "chair", 2: "wall"}
    assert s.face_object.tolist() == [1, 2, 0]
    assert s.face_colors.tolist() == [[10, 20, 30]] * 3


def test_habitat_round_trip(tmp_path):
    g = generate(3, (8, 6, 3))
    ply = save_habitat(g, str(tmp_path))
    s = load_scene(ply)
    assert s.objects == g.objects and s.start == g.start
    assert np.allclose(s.triangles(), g.triangles(), atol=1e-5)
    assert np.array_equal(s.face_object, g.face_object)
    assert np.array_equal(s.face_colors, g.face_colors)


def test_unknown_face_ids_become_background(tmp_path):
    g = generate(0, (3.5, 3, 2.5), "x")
    ply = save_habitat(g, str(tmp_path))
    lines = open(str(tmp_path / "x.house")).read().splitlines()
    chair_ids = [k for k, v in g.objects.items() if v == "chair"]
    lines = [ln for ln in lines if not (ln.startswith("O %d " % (chair_ids[0] - 1)))]
    open(str(tmp_path / "x.house"), "w").write("\n".join(lines) + "\n")
    s = load_habitat(ply)
    assert chair_ids[0] not in s.objects and not np.any(s.face_object == chair_ids[0])
    assert s.unlabelled_ids == [chair_ids[0]]


def _two_box_scene_files(tmp_path, fmt):
    import trimesh
    sc = trimesh.Scene()
    sc.add_geometry(trimesh.creation.box(extents=[4, 4, 0.1]), node_name="floor_0", geom_name="floor_0")
    chair = trimesh.creation.box(extents=[0.5, 0.5, 0.9])
    chair.apply_translation([1, 0, 0.5])
    sc.add_geometry(chair, node_name="chair_7", geom_name="chair_7")
    path = str(tmp_path / ("hand." + fmt))
    sc.export(path)
    return path


@pytest.mark.parametrize("fmt", ["glb", "obj"])
def test_mesh_with_json_labels(tmp_path, fmt):
    path = _two_box_scene_files(tmp_path, fmt)
    labels = tmp_path / "hand.json"
    labels.write_text(json.dumps({"objects": [{"id": 7, "class": "chair", "geometry": "chair_7"},
                                              {"id": 2, "class": "floor", "geometry": "floor_0"}],
                                  "start": [0, 0, 1, 0]}))
    s = load_scene(path, str(labels))
    assert len(s.faces) == 24
    v = s.vertices[s.faces[s.face_object == 7].reshape(-1)]
    assert np.allclose(v.min(0), [0.75, -0.25, 0.05], atol=1e-6)
    assert np.allclose(v.max(0), [1.25, 0.25, 0.95], atol=1e-6)
    assert s.objects == {7: "chair", 2: "floor"} and s.start == (0.0, 0.0, 1.0, 0.0)


def test_ply_with_flat_json_labels(tmp_path):
    g = generate(0, (3.5, 3, 2.5), "flat")
    write_semantic_ply(str(tmp_path / "flat.ply"), g, matterport_ids=False)
    (tmp_path / "flat.json").write_text(json.dumps({str(k): v for k, v in g.objects.items()}))
    s = load_scene(str(tmp_path / "flat.ply"))
    assert s.objects == g.objects and np.array_equal(s.face_object, g.face_object)


@pytest.mark.parametrize("table, why", [
    ("{not json", "not valid JSON"),
    ('[1, 2]', "must be a JSON object"),
    ('{"objects": [{"id": "x", "class": "chair"}]}', "not an integer"),
    ('{"objects": [{"id": 0, "class": "chair"}]}', "[1, 65535]"),
    ('{"objects": [{"id": 3}]}', "'id' and 'class'"),
    ('{"objects": [{"id": 3, "class": ""}]}', "non-empty class"),
    ('{"objects": [{"id": 3, "class": "a"}, {"id": 3, "class": "b"}]}', "listed twice"),
    ('{"objects": [{"id": 3, "class": "chair", "geometry": "nope"}]}', "names geometry not in"),
    ('{"objects": [], "start": [1, 2]}', "start"),
])
def test_malformed_label_tables_are_rejected_with_reason(tmp_path, table, why):
    path = _two_box_scene_files(tmp_path, "glb")
    (tmp_path / "bad.json").write_text(table)
    with pytest.raises(SceneError) as e:
        load_scene(path, str(tmp_path / "bad.json"))
    assert why in str(e.value)


def test_bad_scene_files_are_rejected_with_reason(tmp_path):
    with pytest.raises(SceneError, match="does not exist"):
        load_scene(str(tmp_path / "missing_semantic.ply"))
    with pytest.raises(SceneError, match="no scene file"):
        load_scene("")
    g = generate(0, (3.5, 3, 2.5), "b")
    ply = save_habitat(g, str(tmp_path))
    house = tmp_path / "b.house"
    good = house.read_text()
    house.write_text(good.replace("ASCII 1.1", "ASCII 9"))
    with pytest.raises(SceneError, match="ASCII 1.1"):
        load_scene(ply)
    house.write_text(good + "O 99 0 1234 0 0 0\n")
    with pytest.raises(SceneError, match="unknown category 1234"):
        load_scene(ply)
    house.write_text(good + "O 70000 0 1 0 0 0\n")
    with pytest.raises(SceneError, match="outside"):
        load_scene(ply)
    house.write_text(good + "O 99 0 1234 0 0 0\n")
    with pytest.raises(SceneError, match="unknown category 1234"):
        load_scene(ply)
    house.write_text(good + "C x y\n")
    with pytest.raises(SceneError, match=r"b.house:\d+: malformed"):
        load_scene(ply)
    house.write_text(good)
    data = open(ply, "rb").read()
    open(ply, "wb").write(data[: len(data) // 2])
    with pytest.raises(SceneError, match="truncated"):
        load_scene(ply)
    (tmp_path / "c_semantic.ply").write_bytes(b"not a ply at all")
    (tmp_path / "c.house").write_text(good)
    with pytest.raises(SceneError, match="not a PLY"):
        load_scene(str(tmp_path / "c_semantic.ply"))


def test_ground_truth_export(tmp_path):
    s = load_scene(EXAMPLE)
    doc = export_ground_truth(s, str(tmp_path), DEFAULT_CLASS_NAMES, free_resolution_m=0.1)
    objs = json.loads((tmp_path / "objects.json").read_text())
    assert objs == json.loads(json.dumps(doc))
    assert {o["class"] for o in objs["objects"]} == {"chair", "table", "cabinet", "tv_monitor", "backpack", "plant"}
    for o in objs["objects"]:
        v = s.vertices[s.faces[s.face_object == o["id"]].reshape(-1)]
        assert np.allclose(o["bbox_min"], v.min(0), atol=1e-4) and np.allclose(o["bbox_max"], v.max(0), atol=1e-4)
        assert (tmp_path / o["mesh"]).is_file()
        assert o["class_id"] == DEFAULT_CLASS_NAMES.index(o["class"]) + 1
    from semantic_exploration.sim.scene import read_ply
    bg = read_ply(str(tmp_path / "background.ply"))
    n_things = sum(o["faces"] for o in objs["objects"])
    assert len(bg["face"]["vertex_indices"]) + n_things == len(s.faces)
    free = json.loads((tmp_path / "free_space.json").read_text())
    grid = np.load(str(tmp_path / "free_space.npz"))
    # Interior 3.5 x 3 x 2.5 m = 26.25 m^3, minus furniture and the voxels touching surfaces.
    assert 17.0 < free["explorable_free_volume_m3"] < 26.25
    assert grid["free"].sum() * 0.001 == pytest.approx(free["explorable_free_volume_m3"])
    # Nothing outside the walls is explorable.
    idx = np.argwhere(grid["free"])
    pts = grid["origin"] + (idx + 0.5) * 0.1
    assert pts.min(0)[0] > 0 and pts.max(0)[0] < 3.5 and pts.min(0)[2] > 0 and pts.max(0)[2] < 2.5


def test_free_space_from_a_given_start_and_outside_start_rejected(tmp_path):
    s = load_scene(EXAMPLE)
    s.start = None
    doc = export_ground_truth(s, str(tmp_path / "a"), DEFAULT_CLASS_NAMES)
    assert doc["start"] is None and not (tmp_path / "a" / "free_space.json").exists()
    export_ground_truth(s, str(tmp_path / "b"), DEFAULT_CLASS_NAMES, start=(0.5, 1.5, 1.2))
    free = json.loads((tmp_path / "b" / "free_space.json").read_text())
    assert 17.0 < free["explorable_free_volume_m3"] < 26.25
    with pytest.raises(SceneError, match="not in free space"):
        export_ground_truth(s, str(tmp_path / "c"), DEFAULT_CLASS_NAMES, start=(-0.05, 1.5, 1.2))


def test_scene_rejects_inconsistent_arrays():
    with pytest.raises(SceneError, match="out of range"):
        Scene(np.zeros((3, 3)), [[0, 1, 5]], [0])
    with pytest.raises(SceneError, match="non-finite"):
        Scene([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]], [[0, 1, 2]], [0])
    with pytest.raises(SceneError, match="object id"):
        Scene(np.eye(3), [[0, 1, 2]], [0], objects={70000: "chair"})

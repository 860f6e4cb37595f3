"""Meshes extracted again offline: remesh_objects reads object TSDFs in the
documented file format (include/semantic_exploration/core/tsdf_io.hpp,
written here by hand) and meshes them under the gate its flags give, and
score_objects.py scores a saved object map as the mission report does."""
import json
import os
import struct
import subprocess
import sys

import pytest

from installed import installed_tool  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
ROS_SOURCED = bool(os.environ.get("CMAKE_PREFIX_PATH"))


def tool():
    return installed_tool("remesh_objects")


def write_plane_tsdf(path):
    """One 8^3 block of 2 cm voxels (8 cm truncation) holding a horizontal plane between voxel layers z 3 and 4,
    foreground 140/254 for x < 4 and 203/254 for x >= 4, weight 1: the map of
    TsdfMesh.TheMeshKeepsCubesOverTheForegroundBound. 49 cubes cross it, 2 triangles each; their mean
    foreground is 0.551 (x 0-2), 0.675 (x 3) and 0.799 (x 4-6)."""
    header = ("semexp_tsdf 1\nresolution_m 0.02\ntruncation_m 0.08\nbehind_surface_m 0.04\n"
              "behind_surface_quadratic_per_m 0\nfull_weight_depth_m 0\nforeground_prior 0.5\n"
              "foreground_prior_weight 0\nblock_size 8\nmax_weight 100\nblocks 1\n").encode()
    body = struct.pack("<iiiB", 0, 0, 0, 1)
    for z in range(8):
        for y in range(8):
            for x in range(8):
                sdf_q = round((z + 0.5 - 4) * 0.02 / 0.08 * 32767)
                body += struct.pack("<hHHB3B", sdf_q, 16, 65535, 140 if x < 4 else 203, 90, 120, 150)
    with open(path, "wb") as f:
        f.write(header + body)


def ply_faces(path):
    with open(path, "rb") as f:
        head = f.read(400).split(b"end_header")[0].decode()
    return int(next(line.split()[2] for line in head.splitlines() if line.startswith("element face")))


@pytest.mark.skipif(not ROS_SOURCED, reason="the install space (remesh_objects) is not sourced")
def test_remesh_objects_applies_the_foreground_bound(tmp_path):
    src = tmp_path / "objects"
    src.mkdir()
    write_plane_tsdf(str(src / "object_4_chair.tsdf"))
    # The gate the saved mesh was extracted under, as ObjectMap::save records it: a bound of 0.56.
    gate = {"mesh_min_weight": 0, "mesh_max_sdf_std_m": 0, "mesh_min_foreground": 0.56, "mesh_fragment_gap_m": 0.3,
            "depth_noise": {"sigma_min_m": 0.005, "s_per_m": 0.002, "sigma_max_m": 0.2}}
    index = {"objects": [{"id": 4, "class_name": "chair", "mesh": "object_4_chair.ply",
                          "tsdf": "object_4_chair.tsdf"}], "d_obj_m": 1.0, "mesh_gate": gate}
    (src / "objects.json").write_text(json.dumps(index))
    for bound, faces in ((None, 56), ("0.5", 98), ("0.7", 42)):  # no flag: the saved gate
        out = tmp_path / ("fg%s" % bound)
        flags = ["--mesh_min_foreground", bound] if bound else []
        r = subprocess.run([tool(), str(src), str(out)] + flags, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, universal_newlines=True, timeout=60)
        assert r.returncode == 0, r.stdout
        assert "1 meshes written" in r.stdout
        assert "starting from the saved gate" in r.stdout and "mesh_min_foreground 0.56" in r.stdout
        assert ply_faces(str(out / "object_4_chair.ply")) == faces, bound
        written = json.loads((out / "objects.json").read_text())
        assert written["objects"] == index["objects"]
        assert written["mesh_gate"] == dict(gate, mesh_min_foreground=float(bound or 0.56))  # the gate used
    # Invalid configuration names the parameter; unknown flags and a directory without TSDFs say why.
    r = subprocess.run([tool(), str(src), str(tmp_path / "x"), "--mesh_min_foreground", "0.4"],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=60)
    assert r.returncode == 2 and "object_map/mesh_min_foreground" in r.stdout, r.stdout
    r = subprocess.run([tool(), str(src), str(tmp_path / "x"), "--mesh_min_fg", "0.6"],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=60)
    assert r.returncode == 2 and "unknown flag --mesh_min_fg" in r.stdout, r.stdout
    (src / "object_4_chair.tsdf").unlink()
    r = subprocess.run([tool(), str(src), str(tmp_path / "x")], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       universal_newlines=True, timeout=60)
    assert r.returncode == 1 and "save_tsdf true" in r.stdout, r.stdout


def test_score_objects_scores_a_saved_map_as_the_report_does(tmp_path, gt):  # noqa: F811
    pytest.importorskip("trimesh")
    from test_eval_found import bled_mask_mesh, chair_mesh, write_objects
    d = str(tmp_path / "objects")
    write_objects(d, {3: chair_mesh(gt), 5: bled_mask_mesh(), 8: chair_mesh(gt)})
    broken = tmp_path / "broken"  # an index naming a mesh that is not there
    broken.mkdir()
    (broken / "objects.json").write_text(json.dumps(
        {"objects": [{"id": 1, "class_name": "chair", "mesh": "object_1_chair.ply"}]}))
    r = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "score_objects.py"), "--gt-dir", gt["dir"],
                        str(broken), str(tmp_path / "none"), d], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       universal_newlines=True, timeout=300)
    assert r.returncode == 1 and "holds no objects.json" in r.stderr, r.stderr  # the second directory
    lines = [json.loads(line) for line in r.stdout.splitlines()]
    assert len(lines) == 2 and "error" in lines[0] and "evaluation" not in lines[0]  # the first: said, not lost
    ev = lines[1]["evaluation"]  # the third, scored after both
    chair = next(o["id"] for o in gt["objects"] if o["class"] == "chair")
    assert ev["found"] == 1 and ev["spurious"] == [5]
    assert ev["duplicates"] == [{"gt_id": chair, "map_ids": [3, 8]}]
    # The chair's own mesh lies on it: what is left is the spacing of the ground truth's surface samples
    # (a few mm), far under a 2 cm voxel.
    rmse = {o["map_id"]: o["rmse_m"] for o in ev["objects"]}
    assert rmse[3] < 0.005 and rmse[8] < 0.005


from test_eval_found import gt  # noqa: E402,F401 (the ground-truth fixture)

"""The report and summary.json name spurious map objects (on no ground-truth
object) and duplicated ground-truth objects (more than one map object on
them), on a hand-built object map: two meshes of the one chair and a mask
bled onto the floor."""
import argparse
import json
import os

import pytest

pytest.importorskip("trimesh")

from semantic_exploration.eval import experiments, final, metrics  # noqa: E402
from semantic_exploration.eval import report as run_report  # noqa: E402
from semantic_exploration.eval.runlog import RunLog  # noqa: E402
from semantic_exploration.eval.truth import GroundTruthIndex  # noqa: E402

from test_eval_found import bled_mask_mesh, chair_mesh, gt, write_objects  # noqa: E402,F401 (gt: fixture)


@pytest.fixture(scope="module")
def objects_dir(gt, tmp_path_factory):  # noqa: F811
    d = str(tmp_path_factory.mktemp("objects"))
    write_objects(d, {3: chair_mesh(gt), 5: bled_mask_mesh(), 8: chair_mesh(gt)})
    return d


def chair_id(gt):  # noqa: F811
    return next(o["id"] for o in gt["objects"] if o["class"] == "chair")


def test_spurious_and_duplicates_of_a_hand_built_map(gt, objects_dir):  # noqa: F811
    ev = GroundTruthIndex(gt, ["chair"]).evaluate_objects(metrics.load_reconstruction(objects_dir), score=False)
    assert ev.found_gt_ids == [chair_id(gt)]
    assert ev.spurious_map_ids == [5]                 # the floor patch lies on no chair
    assert ev.duplicates == {chair_id(gt): [3, 8]}    # two map objects on the one chair
    clean = metrics.ObjectEvaluation(matches=[metrics.ObjectMatch(1, "chair", 7, 0.9)], n_ground_truth=1)
    assert clean.spurious_map_ids == [] and clean.duplicates == {}


def test_report_summary_and_experiment_report_name_them(gt, objects_dir, tmp_path):  # noqa: F811
    out = tmp_path / "run"
    out.mkdir()
    saved = {"object_map": {"success": True, "dir": objects_dir, "message": "saved", "files": []}}
    gt_run = {"scene": "house", "objects": [{"id": chair_id(gt), "class": "chair"}], "gt_dir": gt["dir"]}
    args = argparse.Namespace(mode="semantic", seed=0, classes=["chair"])
    run_report.write_report(str(out), args, gt_run, RunLog(), saved, 10.0, 5.0, "explored")
    summary = json.loads((out / "summary.json").read_text())
    ev = summary["evaluation"]
    assert "error" not in ev, ev.get("error")
    assert ev["found"] == 1 and ev["spurious"] == [5]
    assert ev["duplicates"] == [{"gt_id": chair_id(gt), "map_ids": [3, 8]}]
    report = (out / "report.md").read_text().splitlines()
    assert "| spurious map objects (on no ground-truth object) | 1 (map ids 5) |" in report
    assert ("| duplicated ground-truth objects (more than one map object on them) | 1 (ground truth %d: map ids 3, 8) |"
            % chair_id(gt)) in report
    # Without an evaluation the rows say so.
    assert final.map_object_rows(0, {"skipped": "--no-eval"})[1:] == [
        "| spurious map objects (on no ground-truth object) | - |",
        "| duplicated ground-truth objects (more than one map object on them) | - |"]
    # The experiment report sums them over a mode's runs.
    (out / "timeseries.csv").write_text("sim_s,explored_volume_m3,ground_truth_found,path_length_m\n"
                                        "0,0,0,0\n10,5,1,3\n")
    run = experiments.read_run(str(out))
    res = experiments.write_outputs(str(tmp_path / "campaign"), {"semantic": [run, run]}, grid_step_s=10)
    assert res["rows"][0]["spurious"] == 2 and res["rows"][0]["duplicated"] == 2
    assert "| semantic | 2 | 100% | 2 | 2 |" in (tmp_path / "campaign" / "report.md").read_text()


def test_object_with_an_empty_mesh_is_neither_matched_nor_spurious(gt, tmp_path):  # noqa: F811
    # Under the foreground prior an object made from one detection near its mask's border has a tracked
    # surface but no mesh yet; object_map/save writes its PLY with no vertex.
    d = str(tmp_path / "objects")
    write_objects(d, {3: chair_mesh(gt), 5: bled_mask_mesh()})
    with open(os.path.join(d, "object_9_chair.ply"), "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
                "element face 0\nproperty list uchar int vertex_indices\nend_header\n")
    with open(os.path.join(d, "objects.json")) as f:
        doc = json.load(f)
    doc["objects"].append({"id": 9, "class_name": "chair", "mesh": "object_9_chair.ply"})
    with open(os.path.join(d, "objects.json"), "w") as f:
        json.dump(doc, f)
    ev = GroundTruthIndex(gt, ["chair"]).evaluate_objects(metrics.load_reconstruction(d), score=False)
    assert ev.found_gt_ids == [chair_id(gt)]
    assert ev.spurious_map_ids == [5]
    assert ev.without_surface_map_ids == [9]
    assert ev.duplicates == {}
    rows = final.map_object_rows(3, {"spurious": [5], "duplicates": [], "without_surface": [9]})
    assert rows[-1] == "| map objects without a mesh yet (neither matched nor spurious) | 1 (map ids 9) |"
    assert len(final.map_object_rows(2, {"spurious": [5], "duplicates": [], "without_surface": []})) == 3

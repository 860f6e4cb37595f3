"""One name per setting for the detector: every DetectorConfig field is in
config/detector.yaml and loaded by src/ros/params.cpp under its name; the
YAML's scalar defaults and COCO class list are the struct's; every class-map
value is a project class (config/semantic.yaml classes/names)."""
import os
import re

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HEADER = os.path.join(ROOT, "include", "semantic_exploration", "core", "detector", "detector_config.hpp")


def struct_fields():
    text = open(HEADER).read()
    body = text[text.index("struct DetectorConfig {"):text.index("void validate")]
    fields = {}
    for name, init in re.findall(r"^\s+[\w:<>, ]+?\s(\w+)((?:\{.*\}|\s*=\s*[^;]*)?);", body, re.M):
        fields[name] = init.strip().lstrip("=").strip()
    return fields


def test_every_field_is_in_the_yaml_and_loaded_under_its_name():
    fields = struct_fields()
    assert set(fields) == {"model_path", "input_size", "conf_threshold", "nms_iou", "mask_threshold",
                           "model_classes", "class_map", "backend", "target"}, fields
    cfg = yaml.safe_load(open(os.path.join(ROOT, "config", "detector.yaml")))["detector"]
    params = open(os.path.join(ROOT, "src", "ros", "params.cpp")).read()
    assert set(cfg) == set(fields)
    for name in fields:
        assert 'n + "%s"' % name in params, name
    for name in ("conf_threshold", "nms_iou", "mask_threshold"):
        assert float(cfg[name]) == float(fields[name]), name
    assert cfg["backend"] == fields["backend"].strip('"') and cfg["target"] == fields["target"].strip('"')
    assert cfg["input_size"] == [640, 640] and "{{640, 640}}" in open(HEADER).read()


def test_yaml_class_list_is_coco_and_the_map_names_project_classes():
    cfg = yaml.safe_load(open(os.path.join(ROOT, "config", "detector.yaml")))["detector"]
    src = open(os.path.join(ROOT, "src", "core", "detector", "detector_config.cpp")).read()
    coco = re.findall(r'"(\w+)"', src[src.index("cocoClassNames()"):src.index("return names")])
    assert len(coco) == 80 and cfg["model_classes"] == coco
    project = yaml.safe_load(open(os.path.join(ROOT, "config", "semantic.yaml")))["classes"]["names"]
    assert cfg["class_map"] and all(k in coco and v in project for k, v in cfg["class_map"].items()), cfg["class_map"]

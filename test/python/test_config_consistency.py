"""One name per setting: every field of a core Config struct is loaded by
src/ros/params.cpp under the name it has in config/semantic.yaml, with the
same default; every key of semantic.yaml is read by some node."""
import os
import re

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORE = os.path.join(ROOT, "include", "semantic_exploration", "core")

# struct -> (header, YAML section)
STRUCTS = {
    "PinholeCamera": ("camera.hpp", "camera"),
    "ExplorationConfig": ("exploration_config.hpp", "exploration"),
    "BackgroundMapConfig": ("background_map_config.hpp", "background_map"),
    "ObjectMapConfig": ("object_map_config.hpp", "object_map"),
    "MatchingConfig": ("object_map_config.hpp", "matching"),
    "DepthHistoryConfig": ("planner_config.hpp", "depth_history"),
    "PlannerConfig": ("planner_config.hpp", "planner"),
    "TrajectoryConfig": ("planning/trajectory.hpp", "planner"),
}
FIELD = re.compile(r"^\s+(?:double|float|int|bool|std::uint32_t|std::size_t|std::string)\s+(\w+)\s*=\s*([^;]+);",
                   re.M)


def struct_fields(header, struct):
    text = open(os.path.join(CORE, header)).read()
    start = text.index("struct %s {" % struct)
    body = text[start:text.index("\n};", start)]
    body = body.split("void validate")[0]
    return {name: default.strip() for name, default in FIELD.findall(body)}


def literal(s):
    s = s.strip().rstrip("fF")
    if s in ("true", "false"):
        return s == "true"
    try:
        return float(s)
    except ValueError:
        return None


def sources():
    text = ""
    for d in ("src/ros",):
        for f in sorted(os.listdir(os.path.join(ROOT, d))):
            text += open(os.path.join(ROOT, d, f)).read()
    return text


def test_every_config_field_is_loaded_under_its_yaml_name_with_the_same_default():
    cfg = yaml.safe_load(open(os.path.join(ROOT, "config", "semantic.yaml")))
    params = open(os.path.join(ROOT, "src", "ros", "params.cpp")).read()
    problems = []
    for struct, (header, section) in STRUCTS.items():
        for name, default in struct_fields(header, struct).items():
            key = "%s/%s" % (section, name)
            if not re.search(r'"%s"|n \+ "%s"' % (re.escape(key), re.escape(name)), params):
                problems.append("%s.%s is not loaded as %s in params.cpp" % (struct, name, key))
            if name not in (cfg.get(section) or {}):
                problems.append("%s is missing from config/semantic.yaml" % key)
                continue
            want = literal(default)
            got = cfg[section][name]
            if want is not None and not isinstance(got, (list, dict)) and float(got) != float(want):
                problems.append("%s: semantic.yaml has %r, %s defaults to %s" % (key, got, struct, default))
    assert problems == [], "\n".join(problems)


def test_every_yaml_key_is_read_by_a_node():
    cfg = yaml.safe_load(open(os.path.join(ROOT, "config", "semantic.yaml")))
    src = sources()
    unread = []
    for section, values in cfg.items():
        keys = values.keys() if isinstance(values, dict) else [None]
        for k in keys:
            key = section if k is None else "%s/%s" % (section, k)
            name = key.split("/")[-1]
            if '"%s"' % key not in src and '"%s"' % name not in src and '+ "%s"' % name not in src:
                unread.append(key)
    assert unread == [], "keys in semantic.yaml that no node reads: %s" % unread


def test_every_parameter_a_node_reads_is_in_semantic_yaml():
    cfg = yaml.safe_load(open(os.path.join(ROOT, "config", "semantic.yaml")))
    missing = []
    for key in sorted(set(re.findall(r'p\.(?:get|require)\("([\w/]+)"', sources()))):
        if key.endswith("/"):  # a map read entry by entry, e.g. classes/resolution_m/<class>
            continue
        node = cfg
        for part in key.split("/"):
            node = node.get(part) if isinstance(node, dict) else None
        if node is None:
            missing.append(key)
    assert missing == [], "parameters read by nodes but absent from config/semantic.yaml: %s" % missing

"""One name per setting. The parameters the nodes read are listed by the
loaders themselves (test/tools/list_params runs every loader of
src/ros/params.cpp on a YAML file and prints each parameter it asked for,
with its default in code), so this cannot drift from the code:
- every loader of params.hpp is run by list_params;
- every key of the nodes' YAML files is read by some loader;
- every parameter a loader reads is in config/semantic.yaml (detector/* in
  config/detector.yaml), with the default the code has;
- no node reads a parameter outside params.cpp."""
import os
import re
import subprocess
import xmlrpc.client

import pytest
import yaml

from installed import installed_tool  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CONFIG = os.path.join(ROOT, "config")
# The nodes' YAML files (sim.yaml and its override detector_long_range.yaml are the simulator's, read by
# sim/config.py).
NODE_YAMLS = ("semantic.yaml", "detector.yaml", "classic.yaml", "onboard.yaml")


def load(name):
    with open(os.path.join(CONFIG, name)) as f:
        return yaml.safe_load(f) or {}


def merged(*names):
    """The parameter tree of several YAML files loaded in order (rosparam load: maps merge, values replace)."""
    def merge(a, b):
        out = dict(a)
        for k, v in b.items():
            out[k] = merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
        return out
    tree = {}
    for n in names:
        tree = merge(tree, load(n))
    return tree


def leaves(tree, prefix=""):
    for k, v in tree.items():
        key = prefix + str(k)
        if isinstance(v, dict):
            yield from leaves(v, key + "/")
        else:
            yield key, v


def lookup(tree, key):
    node = tree
    for part in key.split("/"):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return node


def list_params_tool():
    return installed_tool("list_params")


def run_loaders(tree):
    """(names of the loaders run, {parameter path: default text}) for a parameter tree."""
    out = subprocess.run([list_params_tool()], input=xmlrpc.client.dumps((tree,)), stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True, timeout=60)
    assert out.returncode == 0, out.stderr
    loaders, params = [], {}
    for line in out.stdout.splitlines():
        kind, _, rest = line.partition("\t")
        if kind == "loader":
            loaders.append(rest)
        elif kind == "param":
            path, _, default = rest.partition("\t")
            params[path] = default
    return loaders, params


@pytest.fixture(scope="module")
def read():
    return run_loaders(merged("semantic.yaml", "detector.yaml"))


def is_map_entry(tree, key):
    """classes/resolution_m/<class>, detector/class_map/<name>: keys of a map the loader reads entry by entry."""
    parent = key.rsplit("/", 1)[0] if "/" in key else None
    node = lookup(tree, parent) if parent else None
    return isinstance(node, dict) and parent in ("classes/resolution_m", "detector/class_map")


def test_list_params_runs_every_loader_of_params_hpp(read):
    with open(os.path.join(ROOT, "include", "semantic_exploration", "ros", "params.hpp")) as f:
        declared = set(re.findall(r"^\S[^\n(]*\b(load\w+)\(const ParamReader& p", f.read(), re.M))
    loaders, _ = read
    assert declared and declared == set(loaders), "declared %s, run %s" % (sorted(declared), sorted(loaders))


def test_every_yaml_key_is_read_by_a_loader():
    unread = []
    for name in NODE_YAMLS:
        tree = merged("semantic.yaml", "detector.yaml", name)
        _, params = run_loaders(tree)
        unread += ["%s: %s" % (name, key) for key, _ in leaves(load(name)) if key not in params]
    assert unread == [], "keys no loader reads: %s" % unread


def test_every_parameter_read_is_in_the_yaml_with_the_default_of_the_code(read):
    tree = merged("semantic.yaml", "detector.yaml")
    _, params = read
    missing, differ = [], []
    for key, default in sorted(params.items()):
        if is_map_entry(tree, key):
            continue
        value = lookup(tree, key)
        if value is None:
            missing.append(key)
        elif default != "required" and yaml.safe_load(default) != value:
            differ.append("%s: YAML %r, code %s" % (key, value, default))
    assert missing == [], "parameters read but absent from semantic.yaml / detector.yaml: %s" % missing
    assert differ == [], "YAML values that differ from the defaults in code:\n" + "\n".join(differ)


def test_parameters_are_read_only_in_params_cpp():
    offenders = []
    src = os.path.join(ROOT, "src", "ros")
    for f in sorted(os.listdir(src)):
        if f in ("params.cpp", "param_reader.cpp"):  # the loaders and the reader they use
            continue
        with open(os.path.join(src, f)) as fh:
            text = fh.read()
        if re.search(r"\b(getAtLeast|require|getParam|param)\s*\(|\bp\.get\(", text):
            offenders.append(f)
    assert offenders == [], "parameters read outside src/ros/params.cpp in %s" % offenders

#!/usr/bin/env python3
"""rostest: the C++ nodes come up with the default config, and refuse bad ones."""
import os
import subprocess
import sys
import time
import unittest

import rosgraph
import roslib.packages
import rospkg
import rospy
import rosservice
import yaml

PKG = "semantic_exploration"

# node -> (published topics, services), as in the README's node table.
EXPECTED = {
    "background_map": (
        ["/background_map/occupied", "/background_map/frontiers", "/background_map/map_update",
         "/background_map/stats", "/frame_integrated"],
        ["/background_map/compute_gains", "/background_map/get_map", "/background_map/save"]),
    "instance_matching": (["/matched_detections"], []),
    "object_map": (
        ["/object_map/objects", "/object_map/meshes", "/frame_integrated"],
        ["/object_map/render_instances", "/object_map/compute_gains", "/object_map/save"]),
    "depth_history": (["/depth_history/markers"], ["/depth_history/get_masks"]),
    "planner": (
        ["/planner/path", "/planner/candidates", "/planner/candidate_markers", "/planner/status",
         "/planner/gain_images/entropy", "/planner/gain_images/combined"],
        ["/planner/plan_once"]),
}

# node -> (parameter overrides on top of semantic.yaml, parameter the error must name)
BAD = {
    "background_map": ({"background_map": {"resolution_m": -0.04}}, "background_map/resolution_m"),
    "planner": ({"planner": {"a_ent": 0.5}}, "planner/a_ent"),
    "object_map": ({"exploration": {"d_obj_m": 3.0}}, "exploration/d_obj_m"),
    "instance_matching": ({"classes": {"of_interest": ["unicorn"]}}, "classes/of_interest"),
    "depth_history": ({"camera": {"fx": "none"}}, "camera/fx"),
}


def deep_update(base, extra):
    for k, v in extra.items():
        if isinstance(v, dict) and isinstance(base.get(k), dict):
            deep_update(base[k], v)
        else:
            base[k] = v
    return base


class NodesUp(unittest.TestCase):
    def test_nodes_advertise_their_interface(self):
        master = rosgraph.Master("/test_nodes_up")
        deadline = time.time() + 60.0
        missing = None
        while time.time() < deadline:
            pubs, _, srvs = master.getSystemState()
            missing = []
            for node, (topics, services) in EXPECTED.items():
                for t in topics:
                    if not any(t == name and ("/" + node) in nodes for name, nodes in pubs):
                        missing.append("%s publishes %s" % (node, t))
                for s in services:
                    if not any(s == name and ("/" + node) in nodes for name, nodes in srvs):
                        missing.append("%s serves %s" % (node, s))
            if not missing:
                break
            time.sleep(0.5)
        self.assertEqual(missing, [], "not advertised after 60 s: %s" % missing)
        for node, (_, services) in EXPECTED.items():
            for s in services:
                rospy.wait_for_service(s, timeout=10.0)
                self.assertIn(node, rosservice.get_service_node(s))

    def test_bad_parameter_stops_node_naming_it(self):
        config = os.path.join(rospkg.RosPack().get_path(PKG), "config", "semantic.yaml")
        with open(config) as f:
            defaults = yaml.safe_load(f)
        for node, (override, param) in BAD.items():
            name = "bad_" + node
            rospy.set_param("/" + name, deep_update(yaml.safe_load(yaml.safe_dump(defaults)), override))
            exe = roslib.packages.find_node(PKG, node + "_node")[0]
            proc = subprocess.run([exe, "__name:=" + name], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                  timeout=60, universal_newlines=True)
            self.assertEqual(proc.returncode, 2, "%s exited %d:\n%s" % (node, proc.returncode, proc.stdout))
            self.assertIn(param, proc.stdout, "%s did not name %s:\n%s" % (node, param, proc.stdout))
            self.assertIn("invalid parameter", proc.stdout)

    def test_depth_history_image_size_must_be_the_planners(self):
        config = os.path.join(rospkg.RosPack().get_path(PKG), "config", "semantic.yaml")
        with open(config) as f:
            params = yaml.safe_load(f)
        for key, param, other in (("width", "depth_history/width", "planner/raycast_width"),
                                  ("height", "depth_history/height", "planner/raycast_height")):
            bad = yaml.safe_load(yaml.safe_dump(params))
            bad["depth_history"][key] += 2
            rospy.set_param("/bad_depth_history_size", bad)
            exe = roslib.packages.find_node(PKG, "depth_history_node")[0]
            proc = subprocess.run([exe, "__name:=bad_depth_history_size"], stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, timeout=60, universal_newlines=True)
            self.assertEqual(proc.returncode, 2, proc.stdout)
            self.assertIn("invalid parameter '%s'" % param, proc.stdout)
            self.assertIn(other, proc.stdout)

    def test_missing_intrinsics_stop_node(self):
        exe = roslib.packages.find_node(PKG, "planner_node")[0]
        proc = subprocess.run([exe, "__name:=bare_planner"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              timeout=60, universal_newlines=True)
        self.assertEqual(proc.returncode, 2, proc.stdout)
        self.assertIn("camera/width", proc.stdout)


if __name__ == "__main__":
    import rostest
    rospy.init_node("test_nodes_up")
    rostest.rosrun(PKG, "nodes_up", NodesUp, sys.argv)

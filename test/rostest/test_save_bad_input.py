#!/usr/bin/env python3
"""rostest: SaveMap refusals and failed writes (see save_bad_input.test)."""
import os
import shutil
import tempfile
import unittest

import rospy
import rostest

from semantic_exploration.srv import SaveMap

PKG = "semantic_exploration"
NODES = {"background_map": "background_map.semexpmap", "object_map": "objects.json"}


class SaveBadInput(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("save_bad_input_test")
        for node in NODES:
            rospy.wait_for_service("/%s/save" % node, timeout=30)
        cls.tmp = tempfile.mkdtemp(prefix="semexp_save_")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def save(self, node, directory):
        return rospy.ServiceProxy("/%s/save" % node, SaveMap)(directory)

    def test_relative_and_dotdot_paths_are_refused(self):
        for node in NODES:
            for bad, why in (("maps/run1", "must be an absolute path"), ("", "must be an absolute path"),
                             (os.path.join(self.tmp, "a", "..", "..", "etc"), "must not contain '..'")):
                r = self.save(node, bad)
                self.assertFalse(r.success, "%s saved into '%s'" % (node, bad))
                self.assertIn(why, r.message)
                self.assertEqual(list(r.files), [])
            self.assertFalse(os.path.exists(os.path.join(self.tmp, "etc")))

    def test_a_failed_write_answers_false_and_a_good_save_works(self):
        for node, name in NODES.items():
            d = os.path.join(self.tmp, node + "_full")
            os.makedirs(d)
            os.symlink("/dev/full", os.path.join(d, name))
            r = self.save(node, d)
            self.assertFalse(r.success, "%s reported success writing %s to /dev/full: %s" % (node, name, r.message))
            self.assertIn(name, r.message)
            self.assertTrue(os.path.islink(os.path.join(d, name)))  # left as it was
            good = os.path.join(self.tmp, node + "_good")
            r = self.save(node, good)
            self.assertTrue(r.success, r.message)
            self.assertIn(os.path.join(good, name), list(r.files))
            for f in r.files:
                self.assertTrue(os.path.isfile(f), f)
            self.assertEqual(sorted(n for n in os.listdir(good) if n.startswith(".")), [])  # no temporary file left


if __name__ == "__main__":
    rostest.rosrun(PKG, "save_bad_input", SaveBadInput)

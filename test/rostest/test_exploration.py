#!/usr/bin/env python3
"""rostest: the suite explores a small generated house until the planner stops."""
import json
import os
import sys
import time
import unittest

import rospy
from std_msgs.msg import UInt32

from semantic_exploration.msg import ExplorationStatus, MapStats

PKG = "semantic_exploration"
REASONS = ("explored", "no_progress", "time_limit", "no_reachable_candidate")


def wait_finished(test, status, collisions, timeout_s):
    """Waits (wall time) for the planner's STATE_FINISHED on /planner/status
    (`status`: the messages received so far) and asserts what any whole
    exploration must end with: a known termination reason, more than one
    iteration, no collision (`collisions[0]`: the latest /mav/collisions).
    Returns the final status and the iteration count."""
    deadline = time.time() + timeout_s
    finished = None
    while time.time() < deadline and finished is None and not rospy.is_shutdown():
        done = [s for s in status if s.state == ExplorationStatus.STATE_FINISHED]
        finished = done[-1] if done else None
        time.sleep(1.0)
    test.assertIsNotNone(finished, "the planner did not terminate; last status: %s" %
                         (status[-1].message if status else "none"))
    test.assertIn(finished.termination_reason, REASONS)
    iterations = max(s.iteration for s in status)
    test.assertGreater(iterations, 1)
    test.assertEqual(collisions[0], 0, "the MAV collided %d times" % collisions[0])
    return finished, iterations


class Exploration(unittest.TestCase):
    def test_explores_until_termination(self):
        status, stats, collisions = [], [], [0]
        rospy.Subscriber("/planner/status", ExplorationStatus, status.append)
        rospy.Subscriber("/background_map/stats", MapStats, stats.append)
        rospy.Subscriber("/mav/collisions", UInt32, lambda m: collisions.__setitem__(0, m.data))
        finished, iterations = wait_finished(self, status, collisions, 500.0)
        gt = os.path.join(rospy.get_param("/exploration_test/gt_dir"), "free_space.json")
        with open(gt) as f:
            free_m3 = json.load(f)["explorable_free_volume_m3"]
        self.assertTrue(stats, "no MapStats received")
        explored_m3 = stats[-1].explored_volume_m3
        rospy.loginfo("exploration: %s after %d iterations, explored %.1f m^3 of %.1f m^3 explorable free space",
                      finished.termination_reason, iterations, explored_m3, free_m3)
        self.assertGreaterEqual(explored_m3, 0.9 * free_m3)


if __name__ == "__main__":
    import rostest
    rospy.init_node("test_exploration")
    rostest.rosrun(PKG, "exploration", Exploration, sys.argv)

#!/usr/bin/env python3
"""rostest: setpoint_streamer on a clock this test owns (/use_sim_time).

The clock only moves when the test moves it, and after each step the test
waits (wall time, bounded) for what the node must have published by then, so
no assertion depends on the machine's speed. The node's topics are remapped
as for MAVROS (/fcu/setpoint_position/local, /fcu/local_position/pose), so
the remapping is tested too.

Expected (rate 20 Hz, pose_timeout_s 0.52 s (not 0.5: no tick falls on the limit), max_start_offset_m 0.5 m):
- one setpoint per 0.05 s of ROS time, stamped at the tick;
- before any trajectory: the current pose (a flight controller switched to
  offboard stays where it is);
- along a trajectory (0,0,1) -> (1,0,1) -> (1,1,1) over 2 s, yaw 0 -> pi/2
  -> pi/2: the linear interpolation at each setpoint's stamp; after its end,
  (1,1,1) at yaw pi/2, held while the pose is elsewhere, and
  mav/goal_reached once the pose is there;
- a trajectory yawing from 3.0 to -3.0 rad: setpoint yaws pass through pi;
- poses older than 0.52 s: no more setpoints and a log line "stopped streaming";
  poses again: setpoints resume at the new pose;
- a trajectory starting 3 m from the MAV, in another frame, or with decreasing
  times: refused on mav/path_rejected saying why, setpoints unchanged.
"""
import math
import threading
import time
import unittest

import rospy
from geometry_msgs.msg import PoseStamped, Transform, Twist
from rosgraph_msgs.msg import Clock, Log
from std_msgs.msg import String
from trajectory_msgs.msg import MultiDOFJointTrajectory, MultiDOFJointTrajectoryPoint

PKG = "semantic_exploration"
PERIOD = 0.05  # 1 / rate_hz
WAIT_S = 10.0  # wall s to wait for a message the node must publish


def yaw_of(q):
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def quat(yaw):
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def trajectory(points, stamp, frame="world"):
    """points: (t, x, y, z, yaw)."""
    m = MultiDOFJointTrajectory()
    m.header.stamp = stamp
    m.header.frame_id = frame
    m.joint_names = ["body"]
    for t, x, y, z, yaw in points:
        p = MultiDOFJointTrajectoryPoint()
        tf = Transform()
        tf.translation.x, tf.translation.y, tf.translation.z = x, y, z
        tf.rotation.x, tf.rotation.y, tf.rotation.z, tf.rotation.w = quat(yaw)
        p.transforms.append(tf)
        p.velocities.append(Twist())
        p.accelerations.append(Twist())
        p.time_from_start = rospy.Duration.from_sec(t)
        m.points.append(p)
    return m


class SetpointStreamerTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_setpoint_streamer")
        cls.clock_pub = rospy.Publisher("/clock", Clock, queue_size=10, latch=True)
        cls.pose_pub = rospy.Publisher("/fcu/local_position/pose", PoseStamped, queue_size=10)
        cls.traj_pub = rospy.Publisher("/planner/trajectory", MultiDOFJointTrajectory, queue_size=10)
        cls.lock = threading.Lock()
        cls.setpoints, cls.goals, cls.rejected, cls.logs = [], [], [], []
        rospy.Subscriber("/fcu/setpoint_position/local", PoseStamped, cls._keep(cls.setpoints), queue_size=1000)
        rospy.Subscriber("/mav/goal_reached", PoseStamped, cls._keep(cls.goals), queue_size=10)
        rospy.Subscriber("/mav/path_rejected", String, cls._keep(cls.rejected), queue_size=10)
        rospy.Subscriber("/rosout", Log, cls._keep(cls.logs), queue_size=100)
        cls.now = 100.0
        cls.clock_pub.publish(Clock(clock=rospy.Time.from_sec(cls.now)))
        deadline = time.monotonic() + 30
        for pub in (cls.pose_pub, cls.traj_pub):
            while pub.get_num_connections() == 0 and time.monotonic() < deadline:
                time.sleep(0.05)
        time.sleep(0.5)

    @classmethod
    def _keep(cls, store):
        def cb(msg):
            with cls.lock:
                store.append(msg)
        return cb

    # ------------------------------------------------------------ helpers
    def pose(self, x, y, z, yaw=0.0, stamp=None):
        m = PoseStamped()
        m.header.stamp = rospy.Time.from_sec(self.now if stamp is None else stamp)
        m.header.frame_id = "world"
        m.pose.position.x, m.pose.position.y, m.pose.position.z = x, y, z
        q = quat(yaw)
        m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w = q
        self.pose_pub.publish(m)
        self.last_pose_stamp = m.header.stamp.to_sec()

    def wait_for(self, what, cond):
        deadline = time.monotonic() + WAIT_S
        while time.monotonic() < deadline:
            with self.lock:
                if cond():
                    return
            time.sleep(0.005)
        self.fail("timed out waiting for " + what)

    def tick(self, pose=None, expect_setpoint=True):
        """Moves the clock to the next tick (+1 ms) after publishing `pose` (x, y, z, yaw) stamped now;
        returns the setpoint published at that tick (None if expect_setpoint is False: then waits a while
        and checks that none came)."""
        if pose is not None:
            self.pose(*pose)
            time.sleep(0.1)  # the pose arrives before the clock moves
        with self.lock:
            n = len(self.setpoints)
        self.now = (math.floor(self.now / PERIOD + 1e-6) + 1) * PERIOD + 0.001
        self.clock_pub.publish(Clock(clock=rospy.Time.from_sec(self.now)))
        if not expect_setpoint:
            time.sleep(0.3)
            with self.lock:
                self.assertEqual(len(self.setpoints), n, "a setpoint at %.3f s" % self.now)
            return None
        self.wait_for("the setpoint of t = %.3f s" % self.now,
                      lambda: any(abs(s.header.stamp.to_sec() - self.now) < 1e-6 for s in self.setpoints[n:]))
        with self.lock:
            return [s for s in self.setpoints[n:] if abs(s.header.stamp.to_sec() - self.now) < 1e-6][-1]

    def assertSetpoint(self, sp, x, y, z, yaw, tol=1e-6):
        p = sp.pose.position
        self.assertAlmostEqual(p.x, x, delta=tol)
        self.assertAlmostEqual(p.y, y, delta=tol)
        self.assertAlmostEqual(p.z, z, delta=tol)
        self.assertAlmostEqual(math.remainder(yaw_of(sp.pose.orientation) - yaw, 2 * math.pi), 0.0, delta=tol)
        self.assertEqual(sp.header.frame_id, "world")

    # -------------------------------------------------------------- tests
    def test_streamer(self):
        # Before any trajectory: the current pose.
        sp = self.tick(pose=(0.0, 0.0, 1.0, 0.0))
        self.assertSetpoint(sp, 0.0, 0.0, 1.0, 0.0)
        for k in range(1, 5):
            self.assertSetpoint(self.tick(pose=(0.02 * k, 0.0, 1.0, 0.1 * k)), 0.02 * k, 0.0, 1.0, 0.1 * k)

        # Rate: one setpoint per period, stamped at the tick, none in between.
        with self.lock:
            n0 = len(self.setpoints)
        t0 = self.now
        for _ in range(20):
            self.tick(pose=(0.0, 0.0, 1.0, 0.0))
        with self.lock:
            stamps = [s.header.stamp.to_sec() for s in self.setpoints[n0:]]
        self.assertEqual(len(stamps), 20, stamps)
        for a, b in zip([t0] + stamps[:-1], stamps):
            self.assertAlmostEqual(b - a, PERIOD, delta=1e-6)

        # Content: along a trajectory starting now.
        start = self.now
        self.traj_pub.publish(trajectory([(0.0, 0.0, 0.0, 1.0, 0.0), (1.0, 1.0, 0.0, 1.0, math.pi / 2),
                                          (2.0, 1.0, 1.0, 1.0, math.pi / 2)], rospy.Time.from_sec(start)))
        time.sleep(0.3)
        checked = 0
        while self.now < start + 2.0 - 1e-6:
            sp = self.tick(pose=(0.0, 0.0, 1.0, 0.0))
            t = self.now - start
            if t <= 1.0:
                self.assertSetpoint(sp, t, 0.0, 1.0, t * math.pi / 2)
            else:
                self.assertSetpoint(sp, 1.0, t - 1.0, 1.0, math.pi / 2)
            checked += 1
        self.assertGreaterEqual(checked, 39)
        # After the end: the end, held; goal reached only once the pose is there.
        self.assertSetpoint(self.tick(pose=(0.5, 0.5, 1.0, 0.0)), 1.0, 1.0, 1.0, math.pi / 2)
        self.assertSetpoint(self.tick(pose=(0.5, 0.5, 1.0, 0.0)), 1.0, 1.0, 1.0, math.pi / 2)
        with self.lock:
            self.assertEqual(self.goals, [])
        for _ in range(3):  # the goal is checked at the tick after the pose arrived
            self.assertSetpoint(self.tick(pose=(1.0, 1.02, 1.0, math.pi / 2)), 1.0, 1.0, 1.0, math.pi / 2)
        self.wait_for("goal_reached", lambda: len(self.goals) == 1)
        self.assertAlmostEqual(self.goals[0].pose.position.y, 1.02)

        # Yaw across +-pi: 3.0 -> -3.0 rad turns the short way, through pi.
        start = self.now
        self.traj_pub.publish(trajectory([(0.0, 1.0, 1.0, 1.0, 3.0), (1.0, 1.0, 1.0, 1.0, -3.0)],
                                         rospy.Time.from_sec(start)))
        time.sleep(0.3)
        yaws = []
        while self.now < start + 1.0 - 1e-6:
            yaws.append(yaw_of(self.tick(pose=(1.0, 1.0, 1.0, 3.0)).pose.orientation))
        for a, b in zip(yaws, yaws[1:]):
            self.assertLess(abs(math.remainder(b - a, 2 * math.pi)), 0.02, yaws)  # 0.283 rad over 20 ticks
        self.assertTrue(any(y > 3.1 for y in yaws) and any(y < -3.1 for y in yaws), yaws)

        # Refused: 3 m away, another frame, times not increasing; the setpoint stays the held one.
        held = self.tick(pose=(1.0, 1.0, 1.0, -3.0))
        for msg, why in ((trajectory([(0.0, 4.0, 1.0, 1.0, 0.0), (1.0, 5.0, 1.0, 1.0, 0.0)],
                                     rospy.Time.from_sec(self.now)), "max_start_offset_m"),
                         (trajectory([(0.0, 1.0, 1.0, 1.0, 0.0)], rospy.Time.from_sec(self.now), "odom"),
                          "frame 'odom'"),
                         (trajectory([(0.0, 1.0, 1.0, 1.0, 0.0), (0.0, 1.0, 1.2, 1.0, 0.0)],
                                     rospy.Time.from_sec(self.now)), "does not increase")):
            with self.lock:
                n = len(self.rejected)
            self.traj_pub.publish(msg)
            self.wait_for("a rejection naming " + why, lambda: len(self.rejected) > n)
            self.assertIn(why, self.rejected[-1].data)
            sp = self.tick(pose=(1.0, 1.0, 1.0, -3.0))
            self.assertSetpoint(sp, held.pose.position.x, held.pose.position.y, held.pose.position.z,
                                yaw_of(held.pose.orientation))

        # Stale pose: no pose for more than 0.52 s -> setpoints stop, with a log line.
        last_pose = self.last_pose_stamp
        start = self.now
        self.traj_pub.publish(trajectory([(0.0, 1.0, 1.0, 1.0, -3.0), (5.0, 2.0, 1.0, 1.0, -3.0)],
                                         rospy.Time.from_sec(start)))
        time.sleep(0.3)
        while self.now + PERIOD - last_pose < 0.51:
            self.tick()  # still fresh (ticks 0.05 ... 0.5 s after the last pose)
        self.tick(expect_setpoint=False)
        self.tick(expect_setpoint=False)
        self.wait_for("the log line", lambda: any("stopped streaming" in m.msg for m in self.logs))
        # Poses again: streaming resumes at the pose (the trajectory was dropped).
        self.assertSetpoint(self.tick(pose=(1.5, 0.5, 1.2, 0.3)), 1.5, 0.5, 1.2, 0.3)
        self.assertSetpoint(self.tick(pose=(1.6, 0.5, 1.2, 0.3)), 1.6, 0.5, 1.2, 0.3)


if __name__ == "__main__":
    import rostest
    rostest.rosrun(PKG, "setpoint_streamer", SetpointStreamerTest)

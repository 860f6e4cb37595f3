#!/usr/bin/env python3
"""Broadcasts a PoseStamped stream (e.g. motion capture) as the tf
header.frame_id -> ~child_frame (default "body"), for sources that publish a
pose but no tf. Poses with non-finite values are dropped and counted."""
import math

import rospy
from geometry_msgs.msg import PoseStamped, TransformStamped
from tf2_ros import TransformBroadcaster


def main():
    rospy.init_node("pose_to_tf")
    child = rospy.get_param("~child_frame", "body")
    br = TransformBroadcaster()
    dropped = [0]

    def cb(msg):
        p, q = msg.pose.position, msg.pose.orientation
        vals = (p.x, p.y, p.z, q.x, q.y, q.z, q.w)
        if not all(math.isfinite(v) for v in vals) or abs(math.sqrt(q.x**2 + q.y**2 + q.z**2 + q.w**2) - 1) > 1e-2:
            dropped[0] += 1
            rospy.logwarn_throttle(5.0, "pose_to_tf: dropped %d poses with non-finite values or a non-unit quaternion"
                                   % dropped[0])
            return
        t = TransformStamped()
        t.header = msg.header
        t.child_frame_id = child
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = p.x, p.y, p.z
        t.transform.rotation = q
        br.sendTransform(t)

    rospy.Subscriber("pose", PoseStamped, cb, queue_size=10)
    rospy.spin()


if __name__ == "__main__":
    main()

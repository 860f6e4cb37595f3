"""Publishers that write in the caller's thread, for mav_sim's small high-rate messages
(/clock at the physics rate, the world->body tf at tf_rate_hz).

rospy's queued publishing (queue_size=N) hands each message to one writer thread per
subscriber and then yields the GIL (``time.sleep(0)`` in its QueuedConnection): at 100 Hz
to some ten subscribers that was 10^5 thread hand-offs per 100 s of sim time, spent in
context switches (docs/BENCHMARKS.md, "mav_sim's hidden second core"). Written directly,
a message costs one socket write per subscriber.

The trade: a subscriber that is alive but does not read would, once its socket buffer is
full, block the simulator's loop. A roscpp node reads its sockets in its own I/O thread;
a rospy node runs each callback in the receiving thread, so a rospy callback that blocks
for long holds its socket. These messages are tens of bytes, so a socket buffer holds
seconds of them, and /clock and /tf go to rospy's own quick handlers (its clock, tf2's
buffer). mav/pose and the images stay queued: their subscribers run callbacks of their own.
"""
import warnings

import rospy
from tf2_msgs.msg import TFMessage


def direct_publisher(topic: str, msg_type, latch: bool = False) -> rospy.Publisher:
    """rospy.Publisher without a queue (queue_size=None), minus the warning rospy gives for it."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*queue_size.*")
        return rospy.Publisher(topic, msg_type, queue_size=None, latch=latch)


class DirectTransformBroadcaster:
    """tf2_ros.TransformBroadcaster's interface on a direct /tf publisher (see the module doc)."""

    def __init__(self):
        self.pub_tf = direct_publisher("/tf", TFMessage)

    def sendTransform(self, transform) -> None:  # noqa: N802 (tf2_ros's name)
        transforms = transform if isinstance(transform, list) else [transform]
        self.pub_tf.publish(TFMessage(transforms))

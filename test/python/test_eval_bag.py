"""eval.bag.read_bag on small hand-written bags: one time-series row per
second of bag time with the state before that time, the last one at the last
message with the state after it, and a live RunLog's freeze()."""
import pytest

rosbag = pytest.importorskip("rosbag")
std_msgs = pytest.importorskip("std_msgs.msg")

import rospy  # noqa: E402

from semantic_exploration.eval.bag import read_bag  # noqa: E402
from semantic_exploration.eval.runlog import RunLog  # noqa: E402


def _write(path, collisions_at):
    """A bag of /mav/collisions (UInt32) messages: (time s, count) pairs."""
    with rosbag.Bag(str(path), "w") as bag:
        for t_s, n in collisions_at:
            bag.write("/mav/collisions", std_msgs.UInt32(n), rospy.Time.from_sec(t_s))


def test_rows_every_second_and_one_at_the_end(tmp_path):
    _write(tmp_path / "a.bag", [(1.0, 5), (1.5, 6), (2.2, 7), (3.4, 8)])
    log, rows, info = read_bag(str(tmp_path / "a.bag"), [])
    assert [r["sim_s"] for r in rows] == [1.0, 2.0, 3.0, 3.4]
    # a row holds the state before the messages at its time; the last one all of them
    assert [r["collisions"] for r in rows] == [0, 6, 7, 8]
    assert info["start_s"] == 1.0 and info["end_s"] == pytest.approx(3.4, abs=1e-6)
    assert info["topics"] == {"/mav/collisions": 4} and "/mav/collisions" not in info["missing_topics"]
    assert log.collisions == 8


def test_no_second_row_when_the_last_message_falls_on_a_row(tmp_path):
    _write(tmp_path / "b.bag", [(1.0, 5), (1.5, 6), (3.0, 7)])
    log, rows, _ = read_bag(str(tmp_path / "b.bag"), [])
    assert [r["sim_s"] for r in rows] == [1.0, 2.0, 3.0]  # not 3.0 twice
    assert [r["collisions"] for r in rows] == [0, 6, 7]  # the last row after the message at 3.0
    assert log.collisions == 7


def test_freeze_keeps_every_figure():
    log = RunLog()
    log.handle("/mav/collisions", std_msgs.UInt32(2))
    log.freeze()
    log.handle("/mav/collisions", std_msgs.UInt32(5))
    assert log.collisions == 2


def _counts(node, stamp_s, **counts):
    from semantic_exploration.msg import DropCounts
    from std_msgs.msg import Header
    return DropCounts(header=Header(stamp=rospy.Time.from_sec(stamp_s)), node=node, reasons=list(counts),
                      counts=list(counts.values()))


def test_freeze_lets_the_faults_catch_up_with_the_drop_counts():
    """At the stop, a node's count of frame 1.2 s is in, the simulator's count
    of the fault it injected into that frame (sent first, over another
    connection) is not: it is still taken, and later faults are not."""
    pytest.importorskip("semantic_exploration.msg")
    log = RunLog()
    log.handle("/mav_sim/faults", _counts("/mav_sim", 1.0, detections_rescaled=10))
    log.handle("/dropped_input", _counts("/instance_matching", 1.1, size_mismatch=10))
    log.handle("/dropped_input", _counts("/instance_matching", 1.25, size_mismatch=11))
    log.freeze()
    log.handle("/mav_sim/faults", _counts("/mav_sim", 1.1, detections_rescaled=11))
    log.handle("/mav_sim/faults", _counts("/mav_sim", 1.2, detections_rescaled=12))
    log.handle("/mav_sim/faults", _counts("/mav_sim", 1.3, detections_rescaled=13))  # after the stop
    log.handle("/dropped_input", _counts("/instance_matching", 1.35, size_mismatch=12))
    assert log.faults == {"detections_rescaled": 12}
    assert log.drops == {"instance_matching": {"size_mismatch": 11}}

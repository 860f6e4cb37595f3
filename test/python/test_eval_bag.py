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

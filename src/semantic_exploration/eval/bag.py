"""A recorded run (launch/record.launch) read back for evaluation: the bag's
planner status, map statistics, objects, poses, collisions and drop counts go
through the same RunLog as a live run, with one time-series row per second of
the bag's time (sim time when recorded with /use_sim_time).

Needs the rosbag Python API (ROS on Debian: python3-rosbag) and the package's
messages (a sourced workspace).
"""
from typing import Dict, List, Optional, Tuple

from .runlog import TOPICS, RunLog


def read_bag(path: str, gt_objs: List[Dict], period_s: float = 1.0,
             log: Optional[RunLog] = None) -> Tuple[RunLog, List[Dict], Dict]:
    """Feeds every evaluation topic of the bag into a RunLog in recording order.

    Returns (log, rows, info): rows are RunLog.row() every period_s of bag
    time, the last one at the last message with the state after it (wall_s
    empty); info holds start_s, end_s (bag
    time of the first and last message, s), the topics found with their
    message counts, and the evaluation topics the bag lacks.
    """
    import rosbag
    log = log or RunLog()
    rows: List[Dict] = []
    counts: Dict[str, int] = {}
    start = end = None
    next_row = last_row = None
    with rosbag.Bag(path) as bag:
        present = set(bag.get_type_and_topic_info().topics)
        for topic, msg, t in bag.read_messages(topics=[k for k in TOPICS if k in present]):
            t_s = t.to_sec()
            if start is None:
                start, next_row = t_s, t_s
            while t_s >= next_row:  # rows describe the state before this message
                rows.append(log.row(next_row, None, gt_objs))
                last_row = next_row
                next_row += period_s
            log.handle(topic, msg)
            counts[topic] = counts.get(topic, 0) + 1
            end = t_s
    if end is not None:  # the state after every message; it replaces a row that fell on the last message's time
        if end <= last_row:
            rows.pop()
        rows.append(log.row(end, None, gt_objs))
    info = {"start_s": start, "end_s": end, "topics": counts,
            "missing_topics": sorted(k for k in TOPICS if k not in counts)}
    return log, rows, info

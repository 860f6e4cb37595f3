"""Dropped input of mav_sim, counted per reason as the C++ nodes' DropCounter
(node_common.hpp) does: the node publishes the counts latched on /dropped_input
(semantic_exploration/DropCounts) at start and after each drop, and logs each
reason at most once every period_s seconds, so a bad stream never floods the log.

ROS-free: the node passes `publish` (takes {reason: count}) and `log`
(takes reason, count so far, detail). Thread-safe: mav_sim drops input from
its subscriber threads and from its physics loop."""

import threading
import time
from typing import Callable, Dict, Optional


class DropCounter:
    def __init__(self, publish: Optional[Callable[[Dict[str, int]], None]] = None,
                 log: Optional[Callable[[str, int, str], None]] = None, period_s: float = 5.0,
                 clock: Callable[[], float] = time.monotonic):
        self._publish, self._log, self.period_s, self._clock = publish, log, period_s, clock
        self._counts: Dict[str, int] = {}
        self._last_log: Dict[str, float] = {}
        self._lock = threading.Lock()
        if publish is not None:
            publish({})

    def drop(self, reason: str, detail: str, n: int = 1) -> None:
        """Counts n drops for `reason`, publishes the counts, and logs `detail` (throttled per reason)."""
        if n <= 0:
            return
        with self._lock:  # publish under the lock: counts go out in the order they were made
            self._counts[reason] = self._counts.get(reason, 0) + n
            count = self._counts[reason]
            if self._publish is not None:
                self._publish(dict(self._counts))
            now = self._clock()
            last = self._last_log.get(reason)
            due = last is None or now - last >= self.period_s
            if due:
                self._last_log[reason] = now
        if due and self._log is not None:
            self._log(reason, count, detail)

    def count(self, reason: str) -> int:
        with self._lock:
            return self._counts.get(reason, 0)

    def total(self) -> int:
        with self._lock:
            return sum(self._counts.values())

    def counts(self) -> Dict[str, int]:
        with self._lock:
            return dict(self._counts)

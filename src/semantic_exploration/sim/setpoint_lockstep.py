"""Setpoint lockstep (mav_sim's ``lockstep_setpoints``, with lockstep and ~follow setpoints):
sim time stops where the streamer's next setpoint is due until that setpoint has arrived.

Without it, the physics loop runs a frame's worth of sim time in a few wall milliseconds
while setpoint_streamer's timer fires whenever the machine lets it: setpoints then arrive
late by an amount set by the machine's load, and the tracker flies an extrapolated,
stale setpoint through the turns of the trajectory (10-11 cm off the path on a loaded
2-core machine, against 4.5 cm on a quiet one). A flight controller gets its setpoints in
real time; this restores that in lockstep.

The streamer's period is taken from its stamps: two equal consecutive intervals of at most
``max_gap_s`` (a timer that fired late, while sim time still ran free, gives unequal ones).
The next setpoint is then due at the last stamp plus that period; a streamer's timer on sim
time fires at exactly that clock value once sim time stops there. The wait ends when a
setpoint stamped at or after it arrives, or after ``timeout_s`` of wall time; then it is
logged and no wait happens until the stream resumes and its period is learnt again (a
streamer that stopped streaming, e.g. on a stale pose, never stalls the simulator).
ROS-free: the node passes its shutdown check and log function in.
"""
import threading
import time
from typing import Callable, Optional

NS = 1_000_000_000


class SetpointLockstep:
    """timeout_s: wall s to wait for one setpoint; max_gap_s: stamp intervals longer than this
    (sim s) are no period (the stream paused); is_shutdown() ends a wait; warn(text) logs."""

    def __init__(self, timeout_s: float, max_gap_s: float, is_shutdown: Callable[[], bool],
                 warn: Callable[[str], None]):
        self.timeout_s, self.max_gap_ns = timeout_s, int(round(max_gap_s * NS))
        self._is_shutdown, self._warn = is_shutdown, warn
        self._cv = threading.Condition()
        self._last_ns: Optional[int] = None      # newest setpoint stamp, ns
        self._interval_ns: Optional[int] = None  # interval between the two newest stamps, ns
        self._period_ns: Optional[int] = None    # the streamer's period, once two intervals agree, ns
        self._paused = False                     # a wait timed out: none until the period is learnt again
        self.waits = self.timeouts = 0

    def on_setpoint(self, stamp_ns: int) -> None:
        """Called for every setpoint mav_sim receives (stamp in sim time)."""
        with self._cv:
            if self._last_ns is not None and stamp_ns <= self._last_ns:
                return  # not newer: nothing is learnt about the period
            interval = stamp_ns - self._last_ns if self._last_ns is not None else None
            if interval is None or interval > self.max_gap_ns:
                interval = None  # the first, or after a pause in the stream
            if interval is not None and interval == self._interval_ns:
                self._period_ns, self._paused = interval, False
            elif self._paused or interval is None:
                self._period_ns = None
            self._last_ns, self._interval_ns = stamp_ns, interval
            self._cv.notify_all()

    def _due_ns(self) -> Optional[int]:
        if self._paused or self._period_ns is None:
            return None
        return self._last_ns + self._period_ns

    def next_due_ns(self) -> Optional[int]:
        """Sim time (ns) at which the next setpoint is due; None while no wait is due (no period known yet, or paused)."""
        with self._cv:
            return self._due_ns()

    def due(self, t_ns: int) -> bool:
        due = self.next_due_ns()
        return due is not None and t_ns >= due

    def wait(self, t_ns: int) -> bool:
        """Blocks (wall time) while a setpoint is due at sim time t_ns; True once it arrived
        (or none was due), False after timeout_s (then pauses until the stream's period is
        learnt again) or on shutdown."""
        deadline = time.monotonic() + self.timeout_s
        with self._cv:
            self.waits += 1
            while True:
                due = self._due_ns()
                if due is None or t_ns < due:
                    return True
                if self._is_shutdown():
                    return False
                left = deadline - time.monotonic()
                if left <= 0:
                    self.timeouts += 1
                    self._paused = True
                    self._warn("lockstep_setpoints: the setpoint due at %.3f s did not arrive within %.1f s of wall "
                               "time; sim time runs on without waiting until the stream's period is learnt again "
                               "(%d timeouts so far)" % (due / NS, self.timeout_s, self.timeouts))
                    return False
                self._cv.wait(min(left, 0.1))

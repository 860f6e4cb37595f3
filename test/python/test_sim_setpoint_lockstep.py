"""mav_sim's setpoint lockstep (sim/setpoint_lockstep.py): where the next setpoint is due
(from the streamer's own stamps), that the wait ends when it arrives, and that a stream that
stopped costs one timeout, not one per period."""
import threading

from semantic_exploration.sim.setpoint_lockstep import NS, SetpointLockstep

MS = NS // 1000


def make(timeout_s=5.0, warnings=None, stamps_ms=()):
    sl = SetpointLockstep(timeout_s, 0.5, lambda: False, (warnings if warnings is not None else []).append)
    for s in stamps_ms:
        sl.on_setpoint(s * MS)
    return sl


def test_the_next_setpoint_is_due_one_period_after_the_last():
    sl = make()
    assert not sl.due(10 * NS)  # nothing received: no period, no wait
    sl.on_setpoint(1000 * MS)
    sl.on_setpoint(1050 * MS)
    assert sl.next_due_ns() is None  # one interval is no period yet
    sl.on_setpoint(1100 * MS)
    assert sl.next_due_ns() == 1150 * MS
    assert not sl.due(1140 * MS) and sl.due(1150 * MS) and sl.due(1160 * MS)
    sl.on_setpoint(1100 * MS)  # a repeated stamp teaches nothing
    assert sl.next_due_ns() == 1150 * MS


def test_a_late_timer_gives_no_period_until_two_intervals_agree():
    # A timer on a 50 ms grid that fired 30 ms late while sim time ran free: 80 ms, then 20 ms.
    sl = make(stamps_ms=(1000, 1080, 1100))
    assert sl.next_due_ns() is None
    sl.on_setpoint(1150 * MS)
    assert sl.next_due_ns() is None
    sl.on_setpoint(1200 * MS)
    assert sl.next_due_ns() == 1250 * MS


def test_a_gap_longer_than_max_gap_is_no_interval():
    sl = make(stamps_ms=(1000, 2000, 3000))  # 1 s apart > 0.5 s: the stream paused between them
    assert sl.next_due_ns() is None


def test_the_wait_ends_when_the_due_setpoint_arrives():
    sl = make(timeout_s=30.0, stamps_ms=(1000, 1050, 1100))
    timer = threading.Timer(0.2, sl.on_setpoint, (1150 * MS,))
    timer.start()
    assert sl.wait(1150 * MS) is True
    timer.join()
    assert (sl.waits, sl.timeouts) == (1, 0)
    assert sl.next_due_ns() == 1200 * MS


def test_a_setpoint_that_arrived_before_the_wait_ends_it_at_once():
    sl = make(timeout_s=30.0, stamps_ms=(1000, 1050, 1100))
    assert sl.due(1150 * MS)
    sl.on_setpoint(1150 * MS)  # between the loop's check and its wait
    assert sl.wait(1150 * MS) is True and sl.timeouts == 0


def test_a_stopped_stream_costs_one_timeout_then_no_waits_until_it_resumes():
    warnings = []
    sl = make(timeout_s=0.05, warnings=warnings, stamps_ms=(1000, 1050, 1100))
    assert sl.wait(1150 * MS) is False
    assert sl.timeouts == 1 and len(warnings) == 1 and "1.150 s" in warnings[0]
    assert not sl.due(5 * NS)  # paused: sim time runs on
    sl.on_setpoint(5000 * MS)  # the stream resumes; its period is learnt again
    sl.on_setpoint(5050 * MS)
    assert not sl.due(6 * NS)
    sl.on_setpoint(5100 * MS)
    assert sl.due(5150 * MS)


def test_shutdown_ends_a_wait():
    sl = SetpointLockstep(30.0, 0.5, lambda: True, print)
    for s in (1000, 1050, 1100):
        sl.on_setpoint(s * MS)
    assert sl.wait(1150 * MS) is False and sl.timeouts == 0

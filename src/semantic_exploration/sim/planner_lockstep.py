"""Planner lockstep (mav_sim's ``lockstep_planner``): the simulator asks the planner for
each path itself, with sim time stopped, so that a run does not depend on how long
planning takes in wall time.

Without it, the MAV hovers while the planner plans and sim time runs on at the
pace the mapping nodes allow: the path arrives at a sim time set by the
machine's load, and everything after it differs between two runs. With it,
whenever the MAV has no path (at the start, after reaching a goal, after a
refused or failed plan) the simulator, at a frame boundary and once every
lockstep node has integrated the last frame, calls ``planner/plan_once``
(semantic_exploration/PlanOnce) and, if a path was published, waits for it before sim time
moves on. A call that gives no path is repeated every ``retry_s`` of sim time.

The call (semantic_exploration/PlanOnce) names the sim time, the last frame
every lockstep node has handled and the stamp of the last MAV pose sent. The
mapping nodes publish that frame's map update, frontiers, statistics and
objects before they report it, but those reach the planner on connections of
their own, later than the report under load: the planner answers ``pending``
until they are all there, and is asked again (sim time still stopped), for up
to ``timeout_s`` of wall time; after that it plans on what has arrived and
the run is no longer repeatable (logged).
mav/goal_reached is not published then (the planner would plan a second time
on it); the planner's own retries should be off (planner/retry_period_s long).
"""
import threading
import time

NS = 1_000_000_000


class PlannerLockstep:
    def __init__(self, service: str, retry_s: float, timeout_s: float, startup_timeout_s: float):
        self.service, self.timeout_s, self.startup_timeout_s = service, timeout_s, startup_timeout_s
        self.retry_ns = int(round(retry_s * NS))
        self.next_ns = 0              # sim time of the next call, ns (0: at the next boundary)
        self.calls = self.paths = 0
        self.pending = 0              # calls answered "pending": the planner's inputs were still on their way
        self._handled = 0             # paths received so far (followed or refused)
        self._cv = threading.Condition()
        self._proxy = None

    def path_handled(self) -> None:
        """Called by the path subscriber after each path message, accepted or refused."""
        with self._cv:
            self._handled += 1
            self._cv.notify_all()

    def goal_reached(self, t_ns: int) -> None:
        self.next_ns = t_ns  # plan at the next frame boundary

    def due(self, t_ns: int, idle: bool) -> bool:
        return idle and t_ns >= self.next_ns

    def plan(self, t_ns: int, log, frame_ns: int = 0, pose_ns: int = 0) -> bool:
        """Calls plan_once at sim time t_ns (which stands still meanwhile) on the
        inputs of frame frame_ns and the pose sent at pose_ns (0: whatever has
        arrived); True once its path has arrived. `log(level, text)` reports failures."""
        import rospy
        from semantic_exploration.srv import PlanOnce
        self.calls += 1
        self.next_ns = t_ns + self.retry_ns
        with self._cv:
            before = self._handled

        def stamp(ns):
            return rospy.Time(ns // NS, ns % NS)
        try:
            if self._proxy is None:
                rospy.wait_for_service(self.service, timeout=self.startup_timeout_s)
                self._proxy = rospy.ServiceProxy(self.service, PlanOnce, persistent=False)
            deadline = time.monotonic() + self.timeout_s
            res = self._proxy(stamp(t_ns), stamp(frame_ns), stamp(pose_ns))
            waited = 0
            first_missing = res.message
            while res.pending:
                self.pending += 1
                waited += 1
                if time.monotonic() > deadline:
                    log("warn", "lockstep_planner: the planner's inputs did not arrive within %.1f s (%s); "
                        "planning on what has arrived (this run is no longer repeatable)" % (self.timeout_s, res.message))
                    res = self._proxy(stamp(t_ns), stamp(0), stamp(0))
                    waited = 0  # not "came": logged above
                    break
                time.sleep(0.005)
                res = self._proxy(stamp(t_ns), stamp(frame_ns), stamp(pose_ns))
            if waited and not res.pending:
                log("info", "plan_once at %.3f s: the planner's inputs of the frame at %.3f s came after %d "
                    "pending answer(s) (first: %s)" % (t_ns / NS, frame_ns / NS, waited, first_missing))
        except Exception as e:  # a planner that is not up yet or died: hover, ask again later
            log("warn", "lockstep_planner: %s failed (%s); asking again in %.1f s of sim time"
                % (self.service, e, self.retry_ns / NS))
            return False
        if not res.success:
            return False
        deadline = time.monotonic() + self.timeout_s
        with self._cv:
            while self._handled == before:
                left = deadline - time.monotonic()
                if left <= 0:
                    log("warn", "lockstep_planner: the planner published a path but none arrived within %.1f s; "
                        "going on (this run is no longer repeatable)" % self.timeout_s)
                    return False
                self._cv.wait(left)
        self.paths += 1
        return True

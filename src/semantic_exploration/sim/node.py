"""The ``mav_sim`` ROS node: owns sim time and publishes what a MAV with an RGB-D camera and a
detector would, for a scene rendered by :class:`Simulator`.

Topics (relative names, resolved in the node's namespace):
  sub  planner/path (nav_msgs/Path, yaw in orientation), or with ~follow "setpoints"
       setpoint_position/local (geometry_msgs/PoseStamped in world, from setpoint_streamer; the MAV
       tracks it with the setpoints' velocity as feed-forward and reports no goal: the streamer
       does; refused setpoints are counted, see setpoints.py), frame_integrated (FrameIntegrated, lockstep),
       ~load_scene (std_msgs/String: "mesh" or "mesh;labels" of a scene to switch to),
       ~hide_detections (std_msgs/UInt32MultiArray: scene object ids the detector stops reporting
       from the next frame on, replacing detector/hidden_object_ids; [] = hide none)
  pub  camera/depth/image_raw (32FC1 m), camera/rgb/image_raw (rgb8), camera/camera_info (also as
       camera/depth/camera_info and camera/rgb/camera_info),
       camera/instance_gt (16UC1 object id), camera/class_gt (16UC1 class id), detections,
       mav/pose, mav/goal_reached (PoseStamped), mav/collisions (UInt32, latched),
       mav/path_rejected (String: why a path was refused), /clock (latched), tf,
       ~faults (DropCounts, latched: what the fault injection withheld, see faults.py),
       /dropped_input (DropCounts, latched: input mav_sim dropped, per reason, as every node; drops.py)

Time: the node advances sim time in physics steps and publishes /clock; it
never reads ROS time itself (stamps come from its own counter), so it works
with use_sim_time on or off. Frames are rendered every 1/camera/rate_hz sim
seconds; the world->body transform is published at every frame stamp (before
the images) and at tf_rate_hz. In lockstep mode, sim time stops before each
new frame until every node named in lockstep_nodes has reported the previous
frame's stamp on frame_integrated (or lockstep_timeout_s wall seconds pass,
which is logged). With ~follow setpoints and lockstep_setpoints, it also stops
where setpoint_streamer's next setpoint is due until it has arrived
(setpoint_lockstep.py).

Start-up: before the first frame the node publishes the (latched) camera_info,
so that a node that connects gets the intrinsics before any depth image, then
waits (up to lockstep_startup_timeout_s in lockstep mode) until every subscriber the master lists for its camera, tf and
/clock topics is connected, publishes /clock at the frame's time, and only then
the frame, so that neither a mapping node nor rosbag record misses frame 0.
A lockstep node that exists on the master but had no connection to the depth
topic when a frame went out cannot report that frame and is not waited for on
it (logged), so a node that connects late never stalls the simulator.
Both waits are in frame_lockstep.py.

Faults (FaultsConfig, off by default): a sim-time window without world->body
tf and mav/pose, detection instance images at another resolution, and camera
frames that are not sent (no images, camera_info or detections; lockstep does
not wait for a frame that was not sent).
"""

import queue
import threading
import time
from typing import Optional

import numpy as np

import rospy
import tf2_ros
from geometry_msgs.msg import PoseStamped, TransformStamped
from nav_msgs.msg import Path
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import Header, String, UInt32, UInt32MultiArray

from semantic_exploration.msg import Detection, Detections, DropCounts, FrameIntegrated

from . import blas
from .config import ConfigError, SimConfig, from_dict
from .direct_publish import DirectTransformBroadcaster, direct_publisher
from .drops import DropCounter
from .faults import FaultInjector
from .frame_lockstep import FrameLockstep
from .planner_lockstep import PlannerLockstep
from .setpoint_lockstep import SetpointLockstep
from .scene import SceneError, export_ground_truth
from .setpoints import SetpointRefused, check_in_bounds, check_setpoint
from .mav import PathFollower, SetpointMotion
from .simulator import (PathError, Simulator, load_simulator, path_pose_count, quaternion_from_matrix,
                        waypoints_from_poses)

NS = 1_000_000_000


def _stamp(t_ns: int) -> rospy.Time:
    return rospy.Time(t_ns // NS, t_ns % NS)


def _image(arr: np.ndarray, encoding: str, header) -> Image:
    m = Image()
    m.header = header
    m.height, m.width = arr.shape[:2]
    m.encoding = encoding
    m.is_bigendian = 0
    arr = np.ascontiguousarray(arr)
    m.step = arr.strides[0]
    m.data = arr.tobytes()
    return m


class MavSimNode:
    def __init__(self):
        unknown = []
        params = rospy.get_param("~", {})
        try:
            self.cfg: SimConfig = from_dict(params, unknown=unknown).validate()
        except ConfigError as e:
            rospy.logfatal("mav_sim: %s", e)
            raise
        for u in unknown:
            rospy.logdebug("mav_sim: ignoring parameter ~%s (not a simulator setting)", u)
        c = self.cfg
        self.sim: Optional[Simulator] = None
        try:
            self._install(load_simulator(c))
        except (SceneError, ConfigError) as e:
            rospy.logerr("mav_sim: cannot load scene: %s. Waiting for a valid scene on %s.", e,
                         rospy.resolve_name("~load_scene"))

        latch = dict(queue_size=5)  # frames a slow subscriber (rosbag, rviz) may lag behind
        self.pub_depth = rospy.Publisher("camera/depth/image_raw", Image, **latch)
        self.pub_rgb = rospy.Publisher("camera/rgb/image_raw", Image, **latch)
        # Latched: a node gets the intrinsics when it connects, before frame 0's depth image, which
        # travels on its own connection and could otherwise arrive first (the node refuses depth
        # before any camera_info, and a deterministic run then starts one frame later).
        self.pub_info = rospy.Publisher("camera/camera_info", CameraInfo, latch=True, **latch)
        # Per-image copies where image_transport tools (rviz DepthCloud, image_view) look for them.
        self.pub_info_depth = rospy.Publisher("camera/depth/camera_info", CameraInfo, latch=True, **latch)
        self.pub_info_rgb = rospy.Publisher("camera/rgb/camera_info", CameraInfo, latch=True, **latch)
        self.pub_inst = rospy.Publisher("camera/instance_gt", Image, **latch)
        self.pub_cls = rospy.Publisher("camera/class_gt", Image, **latch)
        self.pub_det = rospy.Publisher("detections", Detections, **latch)
        self.pub_pose = rospy.Publisher("mav/pose", PoseStamped, queue_size=10)
        self.pub_goal = rospy.Publisher("mav/goal_reached", PoseStamped, queue_size=10)
        self.pub_coll = rospy.Publisher("mav/collisions", UInt32, queue_size=1, latch=True)
        self.pub_rejected = rospy.Publisher("mav/path_rejected", String, queue_size=5)
        # Latched: a node or recorder that connects late gets the current sim time at once. At the physics
        # rate to every node: written in this thread, not through rospy's writer threads (direct_publish.py).
        self.pub_clock = direct_publisher("/clock", Clock, latch=True)
        self.pub_faults = rospy.Publisher("~faults", DropCounts, queue_size=1, latch=True)
        self.faults = FaultInjector(c.faults)
        self._fault_counts_sent = None
        self.pub_drops = rospy.Publisher("/dropped_input", DropCounts, queue_size=50, latch=True)
        self.drops = DropCounter(self._publish_drops, lambda reason, n, detail: rospy.logwarn(
            "mav_sim: dropped input (%s, %d so far): %s", reason, n, detail))
        self.tf = DirectTransformBroadcaster()
        self.tf_static = tf2_ros.StaticTransformBroadcaster()

        self._lock = threading.Lock()  # the pending path and setpoint, between callbacks and the loop
        self._pending_path = None
        self._pending_setpoint = None
        self._requests: "queue.Queue" = queue.Queue()
        # ~follow: what the MAV flies: "path" (planner/path) or "setpoints" (setpoint_position/local).
        self.follow = rospy.get_param("~follow", "path")
        if self.follow not in ("path", "setpoints"):
            rospy.logfatal("mav_sim: ~follow must be \"path\" or \"setpoints\" (is %r)", self.follow)
            raise ConfigError("follow: must be \"path\" or \"setpoints\"")
        self._setpoint_motion = SetpointMotion(2 * PathFollower.SETPOINT_HOLD_S)  # the setpoints' velocity
        self._setpoint_lockstep = SetpointLockstep(
            c.lockstep_timeout_s, 2 * PathFollower.SETPOINT_HOLD_S, rospy.is_shutdown, lambda text: rospy.logwarn(
                "mav_sim: " + text)) if c.lockstep and c.lockstep_setpoints and self.follow == "setpoints" else None
        if self.follow == "setpoints":
            # Raw, as planner/path: bytes that are no PoseStamped would make rospy drop the connection.
            rospy.Subscriber("setpoint_position/local", rospy.AnyMsg, self._on_setpoint, queue_size=5)
        else:
            # Raw: a path's length is checked before it is deserialised (1e6 poses would hold the GIL for seconds).
            rospy.Subscriber("planner/path", rospy.AnyMsg, self._on_path, queue_size=5)
        # Every request is applied in order: a queue of 2 lost some of a burst that rospy read at once (loaded machine).
        rospy.Subscriber("~load_scene", String, lambda m: self._requests.put(m.data), queue_size=50)
        self._hidden = list(c.detector.hidden_object_ids)
        rospy.Subscriber("~hide_detections", UInt32MultiArray, self._on_hide, queue_size=5)
        self._last_body_ns = 0  # stamp of the last MAV pose sent (tf world <- body), ns
        self._planner_lockstep = PlannerLockstep(
            rospy.resolve_name("planner/plan_once"), c.lockstep_planner_retry_s, c.lockstep_timeout_s,
            c.lockstep_startup_timeout_s) if c.lockstep and c.lockstep_planner else None
        # With lockstep_planner (deterministic runs) every lockstep node must be there before frame 0.
        self._frames = FrameLockstep(c.lockstep_nodes, c.lockstep_timeout_s, c.lockstep_startup_timeout_s,
                                     self.pub_depth, self._frame_publishers, strict=self._planner_lockstep is not None)
        rospy.Subscriber("frame_integrated", FrameIntegrated, self._frames.on_integrated, queue_size=50)
        self.pub_coll.publish(UInt32(0))
        self._publish_fault_counts(0)

    # ------------------------------------------------------------- callbacks
    def _on_path(self, raw: rospy.AnyMsg) -> None:
        try:
            self._take_path(raw)
        finally:
            if self._planner_lockstep is not None:
                self._planner_lockstep.path_handled()

    def _take_path(self, raw: rospy.AnyMsg) -> None:
        """Checks a path once, here: the physics loop only swaps it in."""
        limit = self.cfg.mav.max_path_poses
        try:
            n = path_pose_count(raw._buff)
        except PathError as e:
            self._reject("path: %s" % e)
            return
        if n > limit:
            self._reject("path of %d poses: more than mav/max_path_poses = %d" % (n, limit))
            return
        try:
            msg = Path().deserialize(raw._buff)
        except Exception as e:  # genpy raises several types for a malformed buffer
            self._reject("path of %d poses: cannot deserialise it (%s)" % (n, e))
            return
        frame = msg.header.frame_id.lstrip("/")
        if frame and frame != self.cfg.frames.world:
            self._reject("path in frame '%s' (expected '%s')" % (frame, self.cfg.frames.world))
            return
        sim = self.sim
        try:
            wps = waypoints_from_poses([((p.pose.position.x, p.pose.position.y, p.pose.position.z),
                                         (p.pose.orientation.x, p.pose.orientation.y, p.pose.orientation.z,
                                          p.pose.orientation.w)) for p in msg.poses])
            if sim is not None:
                wps = sim.check_path(wps)
        except PathError as e:
            self._reject("path of %d poses: %s" % (len(msg.poses), e))
            return
        with self._lock:
            self._pending_path = (wps, sim)  # checked against `sim`

    def _on_setpoint(self, raw: rospy.AnyMsg) -> None:
        """A setpoint and its velocity from the previous one (the streamer samples a trajectory).
        A refused one is counted per reason (setpoints.py); the previous one stays."""
        try:
            self._take_setpoint(raw)
        except SetpointRefused as e:
            self.drops.drop(e.reason, "setpoint %s; keeping the previous one" % e)
        except Exception as e:  # a defect here must not cost a setpoint silently
            self.drops.drop("setpoint_error", "setpoint: unexpected %s: %s; keeping the previous one"
                            % (type(e).__name__, e))

    def _take_setpoint(self, raw: rospy.AnyMsg) -> None:
        try:
            msg = PoseStamped().deserialize(raw._buff)
        except Exception as e:  # genpy raises several types for a malformed buffer
            raise SetpointRefused("setpoint_unreadable", "of %d bytes: cannot deserialise it (%s: %s)"
                                  % (len(raw._buff), type(e).__name__, e))
        try:
            sim = self.sim
            p, q = msg.pose.position, msg.pose.orientation
            wp = check_setpoint(msg.header.frame_id, self.cfg.frames.world, (p.x, p.y, p.z), (q.x, q.y, q.z, q.w),
                                sim.bounds if sim is not None else None)
            t = msg.header.stamp.to_sec()
            velocity, yaw_rate, accel, yaw_accel = self._setpoint_motion.update(t, wp)
            with self._lock:
                self._pending_setpoint = (wp, velocity, yaw_rate, t, accel, yaw_accel, sim)  # checked against `sim`
        finally:  # a refused setpoint arrived too (the previous one stays): the waiting loop goes on
            if self._setpoint_lockstep is not None:  # after the swap-in above: the loop finds it there
                self._setpoint_lockstep.on_setpoint(msg.header.stamp.to_nsec())

    def _on_hide(self, msg: UInt32MultiArray) -> None:
        self._hidden = [int(i) for i in msg.data]
        if self.sim is not None:
            self.sim.detector.set_hidden(self._hidden)  # one attribute swap: safe against the frame loop
        rospy.loginfo("mav_sim: detector hides objects %s", self._hidden)

    def _publish_drops(self, counts) -> None:
        self.pub_drops.publish(DropCounts(header=Header(stamp=rospy.Time.now()), node=rospy.get_name(),
                                          reasons=list(counts), counts=list(counts.values())))

    def _reject(self, why: str) -> None:
        rospy.logerr("mav_sim: rejected %s; keeping the previous path", why)
        self.pub_rejected.publish(String(why))

    # ---------------------------------------------------------------- helpers
    def _install(self, sim: Simulator) -> None:
        c = self.cfg
        sim.detector.set_hidden(getattr(self, "_hidden", c.detector.hidden_object_ids))
        self.sim = sim
        lo, hi = sim.bounds
        rospy.loginfo("mav_sim: scene '%s': %d triangles, %d objects (%d of known classes), bounds [%s] - [%s], "
                      "start (%.2f, %.2f, %.2f, yaw %.2f), rays through %s%s, OpenBLAS kernels %s",
                      sim.scene.name, len(sim.scene.faces),
                      len(sim.scene.objects), len(sim.scene.thing_ids(c.classes.names)),
                      ", ".join("%.2f" % v for v in lo), ", ".join("%.2f" % v for v in hi), *sim.start,
                      sim.renderer.backend,
                      " (%s)" % sim.renderer.device_config if sim.renderer.device_config else "",
                      blas.openblas_corename() or "(numpy's BLAS is not OpenBLAS)")
        unl = getattr(sim.scene, "unlabelled_ids", [])
        if unl:
            rospy.logwarn("mav_sim: %d face object ids have no entry in the label table; treated as background",
                          len(unl))
        if sim.start_collides():
            rospy.logwarn("mav_sim: the start pose (%.2f, %.2f, %.2f) is within R = %.3f m of the scene",
                          *sim.start[:3], c.mav.radius_m)
        if c.scene.gt_dir:
            try:
                export_ground_truth(sim.scene, c.scene.gt_dir, c.classes.names, start=sim.start)
                rospy.loginfo("mav_sim: ground truth written to %s", c.scene.gt_dir)
            except (OSError, SceneError) as e:
                rospy.logerr("mav_sim: ground-truth export to '%s' failed: %s", c.scene.gt_dir, e)

    def _transform(self, T: np.ndarray, parent: str, child: str, t_ns: int) -> TransformStamped:
        m = TransformStamped()
        m.header.stamp = _stamp(t_ns)
        m.header.frame_id = parent
        m.child_frame_id = child
        m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = T[:3, 3]
        q = quaternion_from_matrix(T[:3, :3])
        m.transform.rotation.x, m.transform.rotation.y, m.transform.rotation.z, m.transform.rotation.w = q
        return m

    def _pose_msg(self, t_ns: int) -> PoseStamped:
        T = self.sim.T_WB()
        m = PoseStamped()
        m.header.stamp = _stamp(t_ns)
        m.header.frame_id = self.cfg.frames.world
        m.pose.position.x, m.pose.position.y, m.pose.position.z = T[:3, 3]
        q = quaternion_from_matrix(T[:3, :3])
        m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w = q
        return m

    def _publish_fault_counts(self, t_ns: int) -> None:
        counts = dict(self.faults.counts)
        if counts == self._fault_counts_sent:
            return
        self._fault_counts_sent = counts
        self.pub_faults.publish(DropCounts(header=Header(stamp=_stamp(t_ns)), node=rospy.get_name(),
                                           reasons=list(counts), counts=list(counts.values())))

    def _publish_body(self, t_ns: int) -> None:
        if self.faults.withhold_pose(t_ns):
            return
        f = self.cfg.frames
        self.tf.sendTransform(self._transform(self.sim.T_WB(), f.world, f.body, t_ns))
        self.pub_pose.publish(self._pose_msg(t_ns))
        self._last_body_ns = t_ns

    def _publish_frame(self, t_ns: int) -> None:
        c = self.cfg
        out = self.sim.render()
        hdr = Header(stamp=_stamp(t_ns), frame_id=c.frames.camera)
        dets = Detections(header=hdr, instance_image=_image(self.faults.detection_image(out["detection_mask"]),
                                                            "16UC1", hdr))
        dets.detections = [Detection(instance_id=d["instance_id"], class_id=d["class_id"],
                                     class_name=d["class_name"], confidence=d["confidence"])
                           for d in out["detections"]]
        # The counts of what this frame injects go out before the frame itself:
        # a node's drop count (published after it got the frame) never runs ahead
        # of the simulator's count of the fault behind it in the run's report.
        self._publish_fault_counts(t_ns)
        self._publish_camera_info(t_ns)
        self.pub_depth.publish(_image(out["depth"], "32FC1", hdr))
        self.pub_rgb.publish(_image(out["rgb"], "rgb8", hdr))
        self.pub_inst.publish(_image(out["instance"], "16UC1", hdr))
        self.pub_cls.publish(_image(out["class"], "16UC1", hdr))
        self.pub_det.publish(dets)

    def _publish_camera_info(self, t_ns: int) -> None:
        info = CameraInfo(header=Header(stamp=_stamp(t_ns), frame_id=self.cfg.frames.camera),
                          **self.sim.renderer.camera_info())
        self.pub_info.publish(info)
        self.pub_info_depth.publish(info)
        self.pub_info_rgb.publish(info)

    def _frame_publishers(self):
        return [self.pub_depth, self.pub_rgb, self.pub_info, self.pub_info_depth, self.pub_info_rgb, self.pub_inst,
                self.pub_cls, self.pub_det, self.pub_clock, self.tf.pub_tf, self.tf_static.pub_tf]

    def _handle_requests(self) -> bool:
        """Applies queued scene switches; returns True if the scene changed."""
        changed = False
        while not self._requests.empty():
            request = self._requests.get()
            path, _, labels = request.partition(";")
            try:
                cfg = from_dict(rospy.get_param("~", {}), unknown=[]).validate()
                sim = load_simulator(cfg, path.strip(), labels.strip())
            except (SceneError, ConfigError) as e:
                rospy.logerr("mav_sim: rejected scene '%s': %s; keeping the current scene", path, e)
                continue
            except Exception as e:  # a reader's defect must not end the simulator's loop either
                rospy.logerr("mav_sim: rejected scene '%s': unexpected %s: %s; keeping the current scene",
                             path, type(e).__name__, e)
                continue
            self._install(sim)
            changed = True
        return changed

    # ------------------------------------------------------------------ loop
    def spin(self) -> None:
        c = self.cfg
        dt_ns = int(round(NS / c.mav.physics_rate_hz))
        frame_ns = int(round(NS / c.camera.rate_hz))
        tf_ns = int(round(NS / c.tf_rate_hz))
        t_ns = int(round(c.start_time_s * NS))
        next_frame, next_tf = t_ns, t_ns
        last_frame: Optional[int] = None
        anchor_wall, anchor_ns = time.monotonic(), t_ns
        self.pub_clock.publish(Clock(clock=_stamp(t_ns)))
        while not rospy.is_shutdown():
            if self._handle_requests():
                last_frame = None
            if self.sim is None:
                time.sleep(0.1)
                anchor_wall, anchor_ns = time.monotonic(), t_ns
                continue
            sim = self.sim
            if last_frame is None:
                f = c.frames
                self.tf_static.sendTransform(self._transform(sim.T_BC, f.body, f.camera, t_ns))
            with self._lock:
                pending, self._pending_path = self._pending_path, None
                setpoint, self._pending_setpoint = self._pending_setpoint, None
            if setpoint is not None:  # sent at its stamp; sim time may have run on since (no lockstep wait for it)
                target, velocity, yaw_rate, stamp_s, accel, yaw_accel, checked_by = setpoint
                try:
                    if checked_by is not sim:  # checked against no scene, or one replaced since
                        check_in_bounds(target[:3], sim.bounds)
                    sim.follower.set_setpoint(target, velocity, yaw_rate, t_ns / NS - stamp_s, accel, yaw_accel)
                except SetpointRefused as e:
                    self.drops.drop(e.reason, "setpoint %s (scene changed); keeping the previous one" % e)
            if pending is not None:
                path, checked_by = pending
                try:
                    sim.set_path(path, checked=checked_by is sim)
                except PathError as e:  # checked against a scene that was replaced since
                    self._reject("path: %s" % e)
                else:
                    if path:
                        rospy.loginfo("mav_sim: following a path of %d waypoints to (%.2f, %.2f, %.2f, yaw %.2f)",
                                      len(path), *path[-1])
                    else:
                        rospy.loginfo("mav_sim: empty path: stopping")
            if self._setpoint_lockstep is not None and self._setpoint_lockstep.due(t_ns):
                self._setpoint_lockstep.wait(t_ns)
                continue  # the setpoint (if any) is swapped in at the top, at its own stamp
            if t_ns >= next_frame:
                first = last_frame is None
                if c.lockstep:
                    if first:
                        self._publish_camera_info(t_ns)  # latched: delivered as each subscriber connects
                        self._frames.wait_for_subscribers()
                    else:
                        self._frames.wait_frame(last_frame)
                    pl = self._planner_lockstep
                    if not first and pl is not None and pl.due(t_ns, not sim.follower.active):
                        pl.plan(t_ns, lambda level, text: getattr(rospy, "log" + level)("mav_sim: " + text),
                                frame_ns=last_frame, pose_ns=self._last_body_ns)
                        continue  # the path (if any) is swapped in at the top; then this frame
                    anchor_wall, anchor_ns = time.monotonic(), t_ns
                if first:
                    # The frame's time first, so that its stamp is not "before the first /clock" anywhere.
                    self.pub_clock.publish(Clock(clock=_stamp(t_ns)))
                    time.sleep(0.1)
                self._publish_body(t_ns)
                if not self.faults.drop_frame(t_ns):
                    if c.lockstep:
                        self._frames.note_absent(t_ns)
                    self._publish_frame(t_ns)
                    last_frame = t_ns
                self._publish_fault_counts(t_ns)
                next_frame += frame_ns
                next_tf = t_ns + tf_ns
            elif t_ns >= next_tf:
                self._publish_body(t_ns)
                next_tf += tf_ns
            # Physics.
            ev = sim.step(dt_ns / NS)
            t_ns += dt_ns
            self.pub_clock.publish(Clock(clock=_stamp(t_ns)))
            if ev["goal_reached"] and self._planner_lockstep is not None:
                self._planner_lockstep.goal_reached(t_ns)
                rospy.loginfo("mav_sim: goal reached at (%.2f, %.2f, %.2f, yaw %.2f)", *sim.pose)
            elif ev["goal_reached"]:
                self.pub_goal.publish(self._pose_msg(t_ns))
                rospy.loginfo("mav_sim: goal reached at (%.2f, %.2f, %.2f, yaw %.2f)", *sim.pose)
            col = ev["collision"]
            if col is not None:
                self.pub_coll.publish(UInt32(col["count"]))
                rospy.logwarn("mav_sim: collision #%d at (%.2f, %.2f, %.2f): the R = %.3f m sphere touches '%s' "
                              "(object %d) at %.3f m", col["count"], *col["position"], c.mav.radius_m, col["label"],
                              col["object_id"], col["distance_m"])
            # Real-time pacing.
            if c.real_time_factor > 0:
                ahead = anchor_wall + (t_ns - anchor_ns) / NS / c.real_time_factor - time.monotonic()
                if ahead > 0:
                    time.sleep(ahead)
                elif ahead < -1.0:  # cannot keep up: do not try to catch up later
                    anchor_wall, anchor_ns = time.monotonic(), t_ns


def main() -> None:
    rospy.init_node("mav_sim")
    try:
        node = MavSimNode()
    except ConfigError:
        raise SystemExit(2)
    node.spin()

"""Simulator settings with defaults from the paper's Table I, validated with the parameter's name."""

import math
from dataclasses import dataclass, field, fields, is_dataclass
from typing import Any, Dict, List, Optional


class ConfigError(ValueError):
    """A setting is invalid; ``param`` names it."""

    def __init__(self, param: str, why: str):
        super().__init__("parameter '%s': %s" % (param, why))
        self.param = param


def _finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _req(cond: bool, param: str, why: str) -> None:
    if not cond:
        raise ConfigError(param, why)


@dataclass
class CameraConfig:
    width: int = 320                 # px
    height: int = 240                # px
    fx: float = 262.5                # px
    fy: float = 262.5                # px
    cx: Optional[float] = None       # px; None = (width - 1) / 2
    cy: Optional[float] = None       # px; None = (height - 1) / 2
    d_min_m: float = 0.1             # m; nearer returns are invalid (0)
    d_max_m: float = 10.0            # m; farther returns are invalid (0)
    rate_hz: float = 10.0            # frames per sim second
    T_BC_xyz_m: List[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # camera in body, m
    mount_rpy_rad: List[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # mount roll/pitch/yaw, rad

    def validate(self, ns="camera/"):
        _req(isinstance(self.width, int) and self.width > 0, ns + "width", "must be an integer > 0 px")
        _req(isinstance(self.height, int) and self.height > 0, ns + "height", "must be an integer > 0 px")
        _req(_finite(self.fx) and self.fx > 0, ns + "fx", "must be a finite focal length > 0 px")
        _req(_finite(self.fy) and self.fy > 0, ns + "fy", "must be a finite focal length > 0 px")
        if self.cx is None:
            self.cx = (self.width - 1) / 2.0
        if self.cy is None:
            self.cy = (self.height - 1) / 2.0
        _req(_finite(self.cx) and 0 <= self.cx < self.width, ns + "cx", "must lie inside the image")
        _req(_finite(self.cy) and 0 <= self.cy < self.height, ns + "cy", "must lie inside the image")
        _req(_finite(self.d_min_m) and self.d_min_m >= 0, ns + "d_min_m", "must be >= 0 m")
        _req(_finite(self.d_max_m) and self.d_max_m > self.d_min_m, ns + "d_max_m", "must be > d_min_m")
        _req(_finite(self.rate_hz) and self.rate_hz > 0, ns + "rate_hz", "must be > 0 Hz")
        _req(isinstance(self.T_BC_xyz_m, list) and len(self.T_BC_xyz_m) == 3 and all(map(_finite, self.T_BC_xyz_m)),
             ns + "T_BC_xyz_m", "must be 3 finite numbers (m)")
        _req(isinstance(self.mount_rpy_rad, list) and len(self.mount_rpy_rad) == 3
             and all(map(_finite, self.mount_rpy_rad)), ns + "mount_rpy_rad", "must be 3 finite numbers (rad)")


@dataclass
class NoiseConfig:
    enabled: bool = True
    sigma_min_m: float = 0.005       # m (Table I)
    sigma_max_m: float = 0.2         # m (Table I)
    s_per_m: float = 0.002           # 1/m; sigma = s d^2 (Table I)
    seed: int = 1

    def validate(self, ns="noise/"):
        _req(_finite(self.sigma_min_m) and self.sigma_min_m >= 0, ns + "sigma_min_m", "must be >= 0 m")
        _req(_finite(self.sigma_max_m) and self.sigma_max_m >= self.sigma_min_m, ns + "sigma_max_m",
             "must be >= sigma_min_m")
        _req(_finite(self.s_per_m) and self.s_per_m >= 0, ns + "s_per_m", "must be >= 0 1/m")
        _req(isinstance(self.seed, int) and self.seed >= 0, ns + "seed", "must be an integer >= 0")


@dataclass
class DetectorConfig:
    min_mask_pixels: int = 1200      # px; smaller masks are missed (config/sim.yaml: a whole chair from about 4 m)
    drop_fraction: float = 0.0       # probability that a detection is missed
    bleed_probability: float = 0.0   # probability that a mask bleeds onto its neighbours
    bleed_pixels: int = 3            # px; dilation of a bleeding mask
    confidence_min: float = 0.6      # reported confidence range
    confidence_max: float = 1.0
    seed: int = 2
    # Scene object ids never reported (they stay in depth and the ground-truth images): an object that is
    # in view but undetected. mav_sim's ~hide_detections topic replaces the list at run time.
    hidden_object_ids: List[int] = field(default_factory=list)

    def validate(self, ns="detector/"):
        _req(isinstance(self.min_mask_pixels, int) and self.min_mask_pixels >= 0, ns + "min_mask_pixels",
             "must be an integer >= 0 px")
        _req(_finite(self.drop_fraction) and 0 <= self.drop_fraction <= 1, ns + "drop_fraction", "must be in [0, 1]")
        _req(_finite(self.bleed_probability) and 0 <= self.bleed_probability <= 1, ns + "bleed_probability",
             "must be in [0, 1]")
        _req(isinstance(self.bleed_pixels, int) and self.bleed_pixels >= 0, ns + "bleed_pixels",
             "must be an integer >= 0 px")
        _req(_finite(self.confidence_min) and 0 <= self.confidence_min <= 1, ns + "confidence_min", "must be in [0, 1]")
        _req(_finite(self.confidence_max) and self.confidence_min <= self.confidence_max <= 1, ns + "confidence_max",
             "must be in [confidence_min, 1]")
        _req(isinstance(self.seed, int) and self.seed >= 0, ns + "seed", "must be an integer >= 0")
        _req(isinstance(self.hidden_object_ids, list)
             and all(isinstance(i, int) and not isinstance(i, bool) and i > 0 for i in self.hidden_object_ids),
             ns + "hidden_object_ids", "must be a list of scene object ids (integers > 0)")


@dataclass
class MavConfig:
    v_max_mps: float = 1.5           # m/s (Table I)
    omega_max_radps: float = 0.75    # rad/s (Table I)
    a_max_mps2: float = 1.0          # m/s^2
    alpha_max_radps2: float = 1.0    # rad/s^2
    radius_m: float = 0.125          # collision sphere R, m (Table I)
    physics_rate_hz: float = 100.0   # Hz (sim time)
    position_tolerance_m: float = 0.05   # goal reached when this close, m
    yaw_tolerance_rad: float = 0.05      # and yaw this close, rad
    speed_tolerance_mps: float = 0.05    # and this slow, m/s
    max_path_poses: int = 1000       # longest accepted planner/path (planner paths have tens); longer: rejected unread

    def validate(self, ns="mav/"):
        for name, unit in (("v_max_mps", "m/s"), ("omega_max_radps", "rad/s"), ("a_max_mps2", "m/s^2"),
                           ("alpha_max_radps2", "rad/s^2"), ("radius_m", "m"), ("physics_rate_hz", "Hz"),
                           ("position_tolerance_m", "m"), ("yaw_tolerance_rad", "rad"),
                           ("speed_tolerance_mps", "m/s")):
            v = getattr(self, name)
            _req(_finite(v) and v > 0, ns + name, "must be a finite value > 0 %s" % unit)
        _req(isinstance(self.max_path_poses, int) and 1 <= self.max_path_poses <= 1000000, ns + "max_path_poses",
             "must be an integer in [1, 1000000]")


@dataclass
class SceneConfig:
    file: str = ""                   # scene mesh; "" = generate
    labels: str = ""                 # .house / .json label table; "" = next to the mesh
    up_axis: str = "z"               # "z" or "y" (glTF/Habitat y-up)
    seed: int = 0                    # generator seed
    size_m: List[float] = field(default_factory=lambda: [15.0, 12.0, 3.0])  # generated house x, y, z, m
    non_returning: List[str] = field(default_factory=lambda: ["window", "mirror"])  # labels without depth
    gt_dir: str = ""                 # export ground truth here at start ("" = no export)

    def validate(self, ns="scene/"):
        _req(isinstance(self.file, str), ns + "file", "must be a path string")
        _req(self.up_axis in ("z", "y"), ns + "up_axis", "must be 'z' or 'y'")
        _req(isinstance(self.seed, int) and self.seed >= 0, ns + "seed", "must be an integer >= 0")
        _req(isinstance(self.size_m, list) and len(self.size_m) == 3 and all(map(_finite, self.size_m)),
             ns + "size_m", "must be [x, y, z] in m")
        _req(3.0 <= self.size_m[0] <= 40 and 3.0 <= self.size_m[1] <= 40 and 2.2 <= self.size_m[2] <= 6,
             ns + "size_m", "must be within [3, 40] x [3, 40] x [2.2, 6] m")


@dataclass
class ClassesConfig:
    names: List[str] = field(default_factory=lambda: ["chair", "table", "sofa", "bed", "cabinet", "plant",
                                                       "tv_monitor", "backpack", "keyboard", "cushion"])
    of_interest: List[str] = field(default_factory=lambda: ["chair"])  # what the detector reports

    def validate(self, ns="classes/"):
        from .classes import ClassTable
        _req(isinstance(self.names, list) and isinstance(self.of_interest, list), ns + "names",
             "names and of_interest must be lists")
        ClassTable(self.names, self.of_interest).validate(ns)


@dataclass
class FramesConfig:
    world: str = "world"
    body: str = "body"
    camera: str = "camera"

    def validate(self, ns="frames/"):
        for n in ("world", "body", "camera"):
            _req(isinstance(getattr(self, n), str) and getattr(self, n), ns + n, "must be a non-empty frame name")
        _req(len({self.world, self.body, self.camera}) == 3, ns + "camera", "frame names must differ")


@dataclass
class FaultsConfig:
    """Bad input on purpose, to test that the nodes drop and count it (all off by default)."""
    tf_gap_s: Optional[List[float]] = None  # [start, end] sim s (ROS time): no world->body tf, no mav/pose
    detector_scale: float = 1.0      # detections' instance image size / depth size; 1 = same resolution
    frame_drop_fraction: float = 0.0  # probability that a camera frame (images, camera_info, detections) is not sent
    seed: int = 3                    # frame-drop random seed

    def validate(self, ns="faults/"):
        if self.tf_gap_s is not None:
            _req(isinstance(self.tf_gap_s, list) and len(self.tf_gap_s) == 2 and all(map(_finite, self.tf_gap_s))
                 and 0 <= self.tf_gap_s[0] < self.tf_gap_s[1], ns + "tf_gap_s",
                 "must be [start, end] sim s with 0 <= start < end, or empty")
        _req(_finite(self.detector_scale) and 0.05 <= self.detector_scale <= 4.0, ns + "detector_scale",
             "must be in [0.05, 4]")
        _req(_finite(self.frame_drop_fraction) and 0 <= self.frame_drop_fraction < 1, ns + "frame_drop_fraction",
             "must be in [0, 1)")
        _req(isinstance(self.seed, int) and self.seed >= 0, ns + "seed", "must be an integer >= 0")


@dataclass
class SimConfig:
    camera: CameraConfig = field(default_factory=CameraConfig)
    noise: NoiseConfig = field(default_factory=NoiseConfig)
    detector: DetectorConfig = field(default_factory=DetectorConfig)
    mav: MavConfig = field(default_factory=MavConfig)
    scene: SceneConfig = field(default_factory=SceneConfig)
    classes: ClassesConfig = field(default_factory=ClassesConfig)
    frames: FramesConfig = field(default_factory=FramesConfig)
    faults: FaultsConfig = field(default_factory=FaultsConfig)
    real_time_factor: float = 1.0    # sim seconds per wall second; 0 = as fast as possible
    lockstep: bool = False
    lockstep_nodes: List[str] = field(default_factory=list)
    lockstep_timeout_s: float = 5.0          # wall s to wait for one frame
    lockstep_startup_timeout_s: float = 30.0  # wall s to wait for a depth subscriber before the first frame
    lockstep_planner: bool = False   # lockstep only: call planner/plan_once with sim time stopped (planner_lockstep.py)
    lockstep_planner_retry_s: float = 1.0    # sim s between plan_once calls that gave no path
    lockstep_setpoints: bool = True  # lockstep and ~follow setpoints: stop sim time until each due setpoint arrived
    start_pose: Optional[List[float]] = None  # [x, y, z, yaw] (m, rad); None = scene's start
    bounds_min_m: Optional[List[float]] = None  # accepted path region; None = scene bounds
    bounds_max_m: Optional[List[float]] = None
    start_time_s: float = 1.0        # first sim time stamp, s (0 means "no time" in ROS)
    tf_rate_hz: float = 50.0         # world->body tf and mav/pose rate (sim time)

    def validate(self):
        self.camera.validate()
        self.noise.validate()
        self.detector.validate()
        self.mav.validate()
        self.scene.validate()
        self.classes.validate()
        self.frames.validate()
        self.faults.validate()
        _req(_finite(self.real_time_factor) and self.real_time_factor >= 0, "real_time_factor", "must be >= 0")
        _req(isinstance(self.lockstep_nodes, list) and all(isinstance(n, str) and n for n in self.lockstep_nodes),
             "lockstep_nodes", "must be a list of node names")
        _req(not self.lockstep or self.lockstep_nodes, "lockstep_nodes", "must not be empty when lockstep is on")
        _req(_finite(self.lockstep_timeout_s) and self.lockstep_timeout_s > 0, "lockstep_timeout_s", "must be > 0 s")
        _req(_finite(self.lockstep_startup_timeout_s) and self.lockstep_startup_timeout_s >= 0,
             "lockstep_startup_timeout_s", "must be >= 0 s")
        _req(isinstance(self.lockstep_planner, bool), "lockstep_planner", "must be true or false")
        # Without lockstep the simulator ignores it (sim.launch deterministic:=true lockstep:=false): the run is
        # not repeatable, and after an iteration without a path the planner of a deterministic run (its own
        # retries off) leaves the MAV hovering.
        _req(not self.lockstep_planner or self.lockstep, "lockstep_planner",
             "needs lockstep: true (sim.launch deterministic:=true turns both on; do not set lockstep:=false with it)")
        _req(_finite(self.lockstep_planner_retry_s) and self.lockstep_planner_retry_s > 0, "lockstep_planner_retry_s",
             "must be > 0 s")
        _req(isinstance(self.lockstep_setpoints, bool), "lockstep_setpoints", "must be true or false")
        if self.start_pose is not None:
            _req(isinstance(self.start_pose, list) and len(self.start_pose) == 4 and all(map(_finite, self.start_pose)),
                 "start_pose", "must be [x, y, z, yaw] (m, rad) or empty")
        for name in ("bounds_min_m", "bounds_max_m"):
            v = getattr(self, name)
            if v is not None:
                _req(isinstance(v, list) and len(v) == 3 and all(map(_finite, v)), name, "must be 3 finite numbers (m)")
        _req((self.bounds_min_m is None) == (self.bounds_max_m is None), "bounds_max_m",
             "give both bounds_min_m and bounds_max_m, or neither")
        if self.bounds_min_m is not None:
            _req(all(a < b for a, b in zip(self.bounds_min_m, self.bounds_max_m)), "bounds_max_m",
                 "must be > bounds_min_m on every axis")
        _req(_finite(self.start_time_s) and self.start_time_s > 0, "start_time_s", "must be > 0 s")
        _req(_finite(self.tf_rate_hz) and self.tf_rate_hz > 0, "tf_rate_hz", "must be > 0 Hz")
        return self


def from_dict(d: Dict[str, Any], cls=SimConfig, ns: str = "", unknown: Optional[List[str]] = None):
    """Builds a config dataclass from a nested dict (e.g. rosparam), rejecting wrong types.

    Unknown keys raise ConfigError, or are appended to ``unknown`` if a list is
    given (so that one parameter file can be shared with other nodes).
    """
    if d is None:
        d = {}
    if not isinstance(d, dict):
        raise ConfigError(ns.rstrip("/") or "(root)", "must be a dictionary")
    obj = cls()
    names = {f.name for f in fields(cls)}
    for k, v in d.items():
        if k not in names:
            if unknown is None:
                raise ConfigError(ns + k, "unknown parameter")
            unknown.append(ns + k)
            continue
        cur = getattr(obj, k)
        if is_dataclass(cur):
            setattr(obj, k, from_dict(v, type(cur), ns + k + "/", unknown))
            continue
        if isinstance(cur, bool):
            _req(isinstance(v, bool), ns + k, "must be true or false")
        elif isinstance(cur, float) and isinstance(v, int) and not isinstance(v, bool):
            v = float(v)
        elif isinstance(cur, float):
            _req(isinstance(v, float), ns + k, "must be a number")
        elif isinstance(cur, int):
            _req(isinstance(v, int) and not isinstance(v, bool), ns + k, "must be an integer")
        elif isinstance(cur, str):
            _req(isinstance(v, str), ns + k, "must be a string")
        elif cur is None and isinstance(v, (int, float)) and not isinstance(v, bool):
            v = float(v)  # Optional[float] setting given a number
        elif cur is None or isinstance(cur, list):
            if cur is None and (v is None or v == [] or v == ""):
                v = None
            elif v is not None:
                _req(isinstance(v, list), ns + k, "must be a list")
                numeric = cur is None or (cur and isinstance(cur[0], float))
                if numeric:
                    v = [float(x) if isinstance(x, int) and not isinstance(x, bool) else x for x in v]
        setattr(obj, k, v)
    return obj

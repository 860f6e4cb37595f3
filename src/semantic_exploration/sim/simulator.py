"""ROS-free core of the simulator: scene, camera, detector, MAV, collisions and path checks.

The ROS node (node.py) owns time and I/O; everything that decides what the
simulator does lives here so that it is testable without a ROS master.
"""

import math
import struct
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from .classes import ClassTable
from .config import ConfigError, SimConfig
from .detector import Detector
from .mav import CollisionChecker, PathFollower
from .renderer import Renderer
from .scene import Scene, SceneError, load_scene

#: Camera optical axes (z forward, x right, y down) in a body-like frame (x forward, z up).
R_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


class PathError(ValueError):
    """A path was rejected; the message says why."""


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                              math.cos(yaw), math.sin(yaw))
    return (np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]]) @ np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
            @ np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]]))


def quaternion_from_matrix(R: np.ndarray) -> Tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation matrix."""
    t = np.trace(R)
    if t > 0:
        s = math.sqrt(t + 1.0) * 2
        return ((R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s, 0.25 * s)
    i = int(np.argmax(np.diag(R)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = math.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k]) * 2
    q = [0.0, 0.0, 0.0, 0.0]
    q[i] = 0.25 * s
    q[j] = (R[j, i] + R[i, j]) / s
    q[k] = (R[k, i] + R[i, k]) / s
    q[3] = (R[k, j] - R[j, k]) / s
    return tuple(q)


def yaw_from_quaternion(x: float, y: float, z: float, w: float) -> float:
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def path_pose_count(buff: bytes) -> int:
    """Number of poses in a serialised nav_msgs/Path, read from its header
    alone (uint32 seq, stamp, frame_id string, then the poses' uint32 count),
    so that an oversized path is refused before anything is deserialised.
    Raises PathError if the buffer is too short to hold that much."""
    if len(buff) < 16:
        raise PathError("truncated message (%d bytes)" % len(buff))
    (n_frame,) = struct.unpack_from("<I", buff, 12)
    if len(buff) < 20 + n_frame:
        raise PathError("truncated message (%d bytes, frame_id of %d)" % (len(buff), n_frame))
    (count,) = struct.unpack_from("<I", buff, 16 + n_frame)
    return count


def waypoints_from_poses(poses: Sequence[Tuple[Sequence[float], Sequence[float]]]) -> List[Tuple[float, ...]]:
    """(position, quaternion xyzw) pairs -> (x, y, z, yaw); raises PathError on NaN/inf or a zero quaternion."""
    out = []
    for k, (p, q) in enumerate(poses):
        if not all(math.isfinite(v) for v in list(p) + list(q)):
            raise PathError("pose %d has a NaN or infinite value" % k)
        if math.hypot(*q) < 1e-6:  # hypot: no underflow of tiny components to 0
            raise PathError("pose %d has a zero quaternion (yaw undefined)" % k)
        n2 = sum(v * v for v in q)
        if n2 == math.inf:  # components near 1e200: scaled first (other quaternions as ever, to the bit)
            scale = max(abs(v) for v in q)
            q = [v / scale for v in q]
            n2 = sum(v * v for v in q)
        n = math.sqrt(n2)
        out.append((float(p[0]), float(p[1]), float(p[2]), yaw_from_quaternion(*(v / n for v in q))))
    return out


def start_pose_of(scene: Scene, start_pose=None) -> Tuple[float, float, float, float]:
    """The MAV's start (x, y, z, yaw; m, rad): start_pose if given, else the
    scene's, else the centre of its box at 1.2 m (at most 0.3 m under its top)."""
    start = start_pose or scene.start
    if start is None:
        c = scene.bounds.mean(0)
        start = (c[0], c[1], min(1.2, scene.bounds[1, 2] - 0.3), 0.0)
    return tuple(float(v) for v in start)


class Simulator:
    def __init__(self, cfg: SimConfig, scene: Scene):
        cfg.validate()
        self.cfg = cfg
        self.scene = scene
        self.classes = ClassTable(cfg.classes.names, cfg.classes.of_interest)
        self.renderer = Renderer(scene, cfg.camera, self.classes, cfg.scene.non_returning, cfg.noise)
        self.detector = Detector(cfg.detector, self.classes)
        self.collision = CollisionChecker(scene.triangles(), cfg.mav.radius_m)
        if cfg.bounds_min_m is not None:
            self.bounds = np.array([cfg.bounds_min_m, cfg.bounds_max_m], float)
        else:
            self.bounds = scene.bounds
        self.start = start_pose_of(scene, cfg.start_pose)
        self.follower = PathFollower(cfg.mav, self.start)
        self.T_BC = np.eye(4)
        self.T_BC[:3, :3] = rpy_matrix(*cfg.camera.mount_rpy_rad) @ R_OPTICAL
        self.T_BC[:3, 3] = cfg.camera.T_BC_xyz_m
        self.collisions = 0
        self.in_collision = False
        self.path_length_m = 0.0

    @staticmethod
    def from_config(cfg: SimConfig) -> "Simulator":
        """Loads (scene.file) or generates (scene.seed, scene.size_m) the scene; raises SceneError."""
        cfg.validate()
        if cfg.scene.file:
            scene = load_scene(cfg.scene.file, cfg.scene.labels or None, cfg.scene.up_axis)
        else:
            from .generator import generate
            scene = generate(cfg.scene.seed, cfg.scene.size_m)
        return Simulator(cfg, scene)

    # ----------------------------------------------------------------- state
    @property
    def pose(self) -> Tuple[float, float, float, float]:
        return self.follower.pose

    def T_WB(self) -> np.ndarray:
        x, y, z, yaw = self.follower.pose
        T = np.eye(4)
        T[:3, :3] = rpy_matrix(0.0, 0.0, yaw)
        T[:3, 3] = (x, y, z)
        return T

    def T_WC(self) -> np.ndarray:
        return self.T_WB() @ self.T_BC

    def start_collides(self) -> bool:
        return self.collision.collides(self.start[:3])

    # ------------------------------------------------------------------ path
    def check_path(self, waypoints: Sequence[Sequence[float]]) -> List[Tuple[float, ...]]:
        """Returns the waypoints if acceptable, else raises PathError naming the bad waypoint
        (or the length limit mav/max_path_poses)."""
        if len(waypoints) > self.cfg.mav.max_path_poses:
            raise PathError("%d poses are more than mav/max_path_poses = %d"
                            % (len(waypoints), self.cfg.mav.max_path_poses))
        lo, hi = self.bounds
        out = []
        for k, w in enumerate(waypoints):
            if len(w) != 4:
                raise PathError("waypoint %d must be (x, y, z, yaw)" % k)
            if not all(math.isfinite(float(v)) for v in w):
                raise PathError("waypoint %d has a NaN or infinite value" % k)
            p = np.array(w[:3], float)
            if np.any(p < lo) or np.any(p > hi):
                raise PathError("waypoint %d (%.2f, %.2f, %.2f) is outside the bounds [%s] - [%s]"
                                % (k, p[0], p[1], p[2], ", ".join("%.2f" % v for v in lo),
                                   ", ".join("%.2f" % v for v in hi)))
            out.append(tuple(float(v) for v in w))
        return out

    def set_path(self, waypoints: Sequence[Sequence[float]], checked: bool = False) -> None:
        """Follows `waypoints`; `checked`: check_path() of this simulator already accepted them
        (the node checks a path once, on arrival, not again on the physics loop)."""
        self.follower.set_path(waypoints if checked else self.check_path(waypoints))

    # ------------------------------------------------------------------ step
    def step(self, dt: float) -> Dict:
        """Advances the MAV by dt s. Returns {"goal_reached": bool, "collision": None or info dict}."""
        p0 = self.follower.p.copy()
        reached = self.follower.step(dt)
        self.path_length_m += float(np.linalg.norm(self.follower.p - p0))
        d, tri = self.collision.contact(self.follower.p)
        info = None
        if tri >= 0 and not self.in_collision:
            self.collisions += 1
            oid = int(self.scene.face_object[tri])
            info = {"count": self.collisions, "position": tuple(self.follower.p), "distance_m": d,
                    "object_id": oid, "label": self.scene.objects.get(oid, "unlabelled")}
        self.in_collision = tri >= 0
        return {"goal_reached": reached, "collision": info}

    # ---------------------------------------------------------------- camera
    def render(self) -> Dict:
        """Images from the current pose plus the detector's output (mask, detections)."""
        out = self.renderer.render(self.T_WC())
        out["detection_mask"], out["detections"] = self.detector.detect(out["instance"], out["class"])
        return out


def load_simulator(cfg: SimConfig, scene_file: Optional[str] = None, labels: str = "") -> Simulator:
    """Simulator for cfg, optionally with another scene file (and its label table, "" = next to
    the mesh); raises SceneError/ConfigError."""
    if scene_file is not None:
        cfg.scene.file = scene_file
        cfg.scene.labels = labels
    try:
        return Simulator.from_config(cfg)
    except (SceneError, ConfigError):
        raise
    except (OSError, ValueError, KeyError, IndexError, AttributeError, TypeError) as e:
        # A malformed file that the readers' own checks missed (e.g. a PLY face element without
        # vertex indices): a rejected scene, never an exception out of the simulator's loop.
        raise SceneError("malformed scene (%s: %s)" % (type(e).__name__, e))

"""What mav_sim refuses of a setpoint (setpoint_position/local, with ~follow
setpoints), ROS-free. A refused setpoint is counted under one reason, the
first of these that applies:

  setpoint_unreadable       the bytes are no geometry_msgs/PoseStamped (checked by the node)
  setpoint_wrong_frame      header.frame_id neither empty nor the world frame ("/world" is world)
  setpoint_not_finite       a NaN or infinite position or orientation value
  setpoint_zero_quaternion  an orientation of norm below 1e-6 (yaw undefined)
  setpoint_out_of_bounds    the position outside the accepted region (bounds_min_m /
                            bounds_max_m, else the scene's box), boundary included as inside
                            (checked again if the scene changed before the physics loop took it)

and the node counts anything else a setpoint raises as setpoint_error.

A non-unit quaternion is normalised, not refused. A stamp at or before the
previous setpoint's is not refused either: the setpoint is flown without a
feed-forward velocity (SetpointMotion starts afresh), as a flight controller
takes the newest position it is sent. Nor is a setpoint far from the MAV: the
MAV flies there within its speed and acceleration limits."""

import math
from typing import Optional, Sequence, Tuple

import numpy as np

from .simulator import PathError, waypoints_from_poses

REASONS = ("setpoint_unreadable", "setpoint_wrong_frame", "setpoint_not_finite", "setpoint_zero_quaternion",
           "setpoint_out_of_bounds")
ZERO_QUATERNION_NORM = 1e-6  # as waypoints_from_poses


class SetpointRefused(PathError):
    """A refused setpoint: `reason` (one of REASONS) and why, in the message."""

    def __init__(self, reason: str, detail: str):
        super().__init__(detail)
        self.reason = reason


def check_setpoint(frame_id: str, world: str, position: Sequence[float], quaternion: Sequence[float],
                   bounds: Optional[Tuple[Sequence[float], Sequence[float]]] = None) -> Tuple[float, ...]:
    """The setpoint as (x, y, z, yaw) (m, rad) if mav_sim takes it; else raises SetpointRefused.
    bounds: (min, max) corners in world, m; None = not checked (no scene loaded yet)."""
    frame = frame_id.lstrip("/")
    if frame and frame != world:
        raise SetpointRefused("setpoint_wrong_frame", "in frame '%s' (expected '%s')" % (frame, world))
    values = [float(v) for v in list(position) + list(quaternion)]
    if not all(math.isfinite(v) for v in values):
        raise SetpointRefused("setpoint_not_finite", "with a NaN or infinite value (%s)"
                              % ", ".join("%g" % v for v in values))
    if math.hypot(*quaternion) < ZERO_QUATERNION_NORM:
        raise SetpointRefused("setpoint_zero_quaternion", "with a zero quaternion (%s; yaw undefined)"
                              % ", ".join("%g" % v for v in quaternion))
    if bounds is not None:
        check_in_bounds(position, bounds)
    return waypoints_from_poses([(position, quaternion)])[0]


def check_in_bounds(position: Sequence[float], bounds: Tuple[Sequence[float], Sequence[float]]) -> None:
    """Raises SetpointRefused (setpoint_out_of_bounds) if position (m, world) is outside bounds (min, max)."""
    lo, hi = np.asarray(bounds[0], float), np.asarray(bounds[1], float)
    p = np.asarray(position, float)
    if np.any(p < lo) or np.any(p > hi):
        raise SetpointRefused("setpoint_out_of_bounds", "at (%g, %g, %g): outside the bounds [%s] - [%s]" % (
            p[0], p[1], p[2], ", ".join("%.2f" % v for v in lo), ", ".join("%.2f" % v for v in hi)))

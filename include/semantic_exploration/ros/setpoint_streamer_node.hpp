#pragma once
/// @file setpoint_streamer_node.hpp
/// Turns the planner's trajectory into a stream of position setpoints for a
/// flight controller (the MAVROS `setpoint_position/local` convention; no
/// MAVROS dependency).
///
/// Subscribes `planner/trajectory` (trajectory_msgs/MultiDOFJointTrajectory,
/// one joint, in frames/world) and `mav/pose` (geometry_msgs/PoseStamped of
/// the body in world). Publishes, every 1 / `setpoint_streamer/rate_hz` s of
/// ROS time, `setpoint_position/local` (PoseStamped in world: position and a
/// level orientation of the setpoint yaw); `mav/goal_reached` (PoseStamped,
/// the pose) once a trajectory has ended and the pose is within
/// `goal_tolerance_m` / `goal_yaw_tolerance_rad` of its end; and
/// `mav/path_rejected` (std_msgs/String: why) for a trajectory it refuses,
/// so the planner replans.
///
/// Behaviour:
/// - The setpoint is the trajectory at (now - start), linearly interpolated
///   between its points (SampledTrajectory); start = max(header.stamp, time
///   of arrival), so a trajectory planned while the MAV hovered starts at its
///   beginning. A trajectory with no points cancels the active one.
/// - With no active trajectory it holds position: at the end of the last
///   trajectory; before the first one since streaming (re)started, the
///   setpoint is the current pose, so that a flight controller switched to
///   offboard then stays where it is.
/// - When the newest pose is older than `pose_timeout_s` (by its stamp) it
///   stops streaming and drops the active trajectory, with one log line; a
///   flight controller in offboard mode then falls back to its own failsafe.
///   When poses come back it streams again, at the new pose.
/// - A trajectory is refused (counted in /dropped_input, published on
///   mav/path_rejected) if it is malformed (conversions.hpp
///   fromTrajectoryMsg), arrives without a fresh pose, or starts more than
///   `max_start_offset_m` from the MAV's pose.

#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <trajectory_msgs/MultiDOFJointTrajectory.h>

#include "semantic_exploration/core/planning/trajectory.hpp"
#include "semantic_exploration/ros/node_common.hpp"
#include "semantic_exploration/ros/params.hpp"

namespace semexp_ros {

class SetpointStreamerNode {
 public:
  SetpointStreamerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  void poseCallback(const geometry_msgs::PoseStampedConstPtr& msg);
  void trajectoryCallback(const trajectory_msgs::MultiDOFJointTrajectoryConstPtr& msg);
  void tick(const ros::TimerEvent& ev);
  bool poseFresh(const ros::Time& now) const;
  /// The setpoint at `now` (the trajectory's, or the held one).
  semexp::SampledTrajectory::Sample setpoint(const ros::Time& now) const;
  void reject(const std::string& reason, const std::string& why);

  SetpointStreamerConfig config_;
  FrameNames frames_;
  DropCounter drops_;

  bool have_pose_ = false;
  geometry_msgs::PoseStamped pose_msg_;
  semexp::SampledTrajectory::Sample pose_;  ///< position and yaw of pose_msg_

  bool streaming_ = false;    ///< setpoints are being published (a fresh pose)
  bool active_ = false;       ///< a trajectory is being followed
  bool goal_pending_ = false; ///< the last trajectory ended, its goal not yet reported
  bool anchored_ = false;     ///< hold_ is fixed (a trajectory ended); else it is the current pose
  semexp::SampledTrajectory trajectory_;
  ros::Time start_;
  semexp::SampledTrajectory::Sample hold_;  ///< the setpoint while no trajectory is active

  ros::Subscriber pose_sub_, trajectory_sub_;
  ros::Publisher setpoint_pub_, goal_pub_, rejected_pub_;
  ros::Timer timer_;
};

}  // namespace semexp_ros

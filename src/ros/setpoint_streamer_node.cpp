#include "semantic_exploration/ros/setpoint_streamer_node.hpp"

#include <std_msgs/String.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "semantic_exploration/ros/conversions.hpp"

namespace semexp_ros {

namespace {

std::string fmt3(const Eigen::Vector3d& p) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "(%.2f, %.2f, %.2f)", p.x(), p.y(), p.z());
  return buf;
}

}  // namespace

SetpointStreamerNode::SetpointStreamerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  const auto p = ParamReader::fromNodeHandle(pnh);
  config_ = loadSetpointStreamer(p);
  frames_ = loadFrames(p);
  setpoint_pub_ = nh.advertise<geometry_msgs::PoseStamped>("setpoint_position/local", 10);
  goal_pub_ = nh.advertise<geometry_msgs::PoseStamped>("mav/goal_reached", 10);
  rejected_pub_ = nh.advertise<std_msgs::String>("mav/path_rejected", 5);
  pose_sub_ = nh.subscribe("mav/pose", 10, &SetpointStreamerNode::poseCallback, this);
  trajectory_sub_ = nh.subscribe("planner/trajectory", 2, &SetpointStreamerNode::trajectoryCallback, this);
  timer_ = nh.createTimer(ros::Duration(1.0 / config_.rate_hz), &SetpointStreamerNode::tick, this);
  ROS_INFO("setpoint_streamer: %.1f Hz on %s, pose from %s (stale after %.2f s), trajectories from %s",
           config_.rate_hz, setpoint_pub_.getTopic().c_str(), pose_sub_.getTopic().c_str(), config_.pose_timeout_s,
           trajectory_sub_.getTopic().c_str());
}

void SetpointStreamerNode::poseCallback(const geometry_msgs::PoseStampedConstPtr& msg) {
  const auto& q = msg->pose.orientation;
  const auto& t = msg->pose.position;
  const double n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!std::isfinite(t.x + t.y + t.z) || !std::isfinite(n) || n < 1e-6) {
    drops_.drop("bad_pose", "setpoint_streamer: pose with a non-finite position or a zero quaternion ignored");
    return;
  }
  std::string frame = msg->header.frame_id;
  if (!frame.empty() && frame[0] == '/') frame.erase(0, 1);
  if (!frame.empty() && frame != frames_.world) {
    drops_.drop("bad_pose", "setpoint_streamer: pose in frame '" + frame + "' ignored (expected '" +
                                frames_.world + "')");
    return;
  }
  pose_msg_ = *msg;
  pose_.t_s = 0.0;
  pose_.position_W = Eigen::Vector3d(t.x, t.y, t.z);
  pose_.yaw_rad = std::atan2(2.0 * (q.w * q.z + q.x * q.y), q.w * q.w + q.x * q.x - q.y * q.y - q.z * q.z);
  have_pose_ = true;
}

bool SetpointStreamerNode::poseFresh(const ros::Time& now) const {
  return have_pose_ && (now - pose_msg_.header.stamp).toSec() <= config_.pose_timeout_s;
}

semexp::SampledTrajectory::Sample SetpointStreamerNode::setpoint(const ros::Time& now) const {
  return active_ ? trajectory_.at((now - start_).toSec()) : hold_;
}

void SetpointStreamerNode::reject(const std::string& reason, const std::string& why) {
  drops_.drop(reason, "setpoint_streamer: refused a trajectory: " + why);
  std_msgs::String s;
  s.data = why;
  rejected_pub_.publish(s);
}

void SetpointStreamerNode::trajectoryCallback(const trajectory_msgs::MultiDOFJointTrajectoryConstPtr& msg) {
  const ros::Time now = ros::Time::now();
  semexp::SampledTrajectory tr;
  const std::string bad = fromTrajectoryMsg(*msg, frames_.world, tr);
  if (!bad.empty()) return reject("bad_trajectory", bad);
  if (!poseFresh(now)) {
    return reject("no_pose", have_pose_ ? "the pose is stale (no pose for " +
                                              std::to_string((now - pose_msg_.header.stamp).toSec()) + " s)"
                                        : "no pose received yet");
  }
  if (tr.empty()) {
    hold_ = streaming_ ? setpoint(now) : pose_;
    active_ = goal_pending_ = false;
    anchored_ = true;
    ROS_INFO("setpoint_streamer: empty trajectory: holding at %s", fmt3(hold_.position_W).c_str());
    return;
  }
  // Measured from the MAV, not from the setpoint: a trajectory planned from where the MAV is stays
  // acceptable when the MAV did not reach the previous setpoint.
  const double offset = (tr.front().position_W - pose_.position_W).norm();
  if (offset > config_.max_start_offset_m) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "it starts %.2f m from the MAV (setpoint_streamer/"
                  "max_start_offset_m = %.2f m)", offset, config_.max_start_offset_m);
    return reject("far_start", buf);
  }
  trajectory_ = std::move(tr);
  start_ = std::max(msg->header.stamp, now);
  active_ = goal_pending_ = true;
  ROS_INFO("setpoint_streamer: following a trajectory of %zu points, %.2f s, to %s (yaw %.2f)",
           msg->points.size(), trajectory_.duration_s(), fmt3(trajectory_.back().position_W).c_str(),
           trajectory_.back().yaw_rad);
}

void SetpointStreamerNode::tick(const ros::TimerEvent&) {
  const ros::Time now = ros::Time::now();
  if (!have_pose_) {
    ROS_INFO_THROTTLE(10.0, "setpoint_streamer: no pose on %s yet: not streaming", pose_sub_.getTopic().c_str());
    return;
  }
  if (!poseFresh(now)) {
    if (streaming_)
      ROS_WARN("setpoint_streamer: the newest pose is %.2f s old (setpoint_streamer/pose_timeout_s = %.2f s): "
               "stopped streaming setpoints%s", (now - pose_msg_.header.stamp).toSec(), config_.pose_timeout_s,
               active_ ? " and dropped the trajectory" : "");
    streaming_ = active_ = goal_pending_ = false;
    return;
  }
  if (!streaming_) {
    streaming_ = true;
    anchored_ = false;
    ROS_INFO("setpoint_streamer: streaming setpoints, holding at the pose %s (yaw %.2f) until a trajectory "
             "arrives", fmt3(pose_.position_W).c_str(), pose_.yaw_rad);
  }
  if (!active_ && !anchored_) hold_ = pose_;
  semexp::SampledTrajectory::Sample sp = setpoint(now);
  if (active_ && (now - start_).toSec() >= trajectory_.duration_s()) {
    active_ = false;
    anchored_ = true;
    hold_ = sp = trajectory_.at(trajectory_.duration_s());
  }
  if (goal_pending_ && !active_ && (pose_.position_W - hold_.position_W).norm() <= config_.goal_tolerance_m &&
      std::abs(std::remainder(pose_.yaw_rad - hold_.yaw_rad, 2.0 * M_PI)) <= config_.goal_yaw_tolerance_rad) {
    goal_pending_ = false;
    goal_pub_.publish(pose_msg_);
    ROS_INFO("setpoint_streamer: goal reached at %s", fmt3(pose_.position_W).c_str());
  }
  geometry_msgs::PoseStamped out;
  out.header.stamp = now;
  out.header.frame_id = frames_.world;
  out.pose.position = toPoint(sp.position_W);
  out.pose.orientation = yawQuaternion(sp.yaw_rad);
  setpoint_pub_.publish(out);
}

}  // namespace semexp_ros

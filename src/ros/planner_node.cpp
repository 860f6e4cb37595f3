#include "semantic_exploration/ros/planner_node.hpp"

#include <nav_msgs/Path.h>
#include <sensor_msgs/Image.h>
#include <trajectory_msgs/MultiDOFJointTrajectory.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "semantic_exploration/CandidateViewArray.h"
#include "semantic_exploration/ExplorationStatus.h"
#include "semantic_exploration/GetMap.h"
#include "semantic_exploration/core/planning/path_check.hpp"
#include "semantic_exploration/ros/conversions.hpp"
#include "semantic_exploration/ros/planner_markers.hpp"

namespace semexp_ros {

using semantic_exploration::ExplorationStatus;

PlannerNode::PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  const auto p = ParamReader::fromNodeHandle(pnh);
  config_ = loadPlanner(p);
  exploration_ = loadExploration(p);
  camera_ = loadCamera(p);
  bounds_ = loadBounds(p);
  frames_ = loadFrames(p);
  termination_ = loadTermination(p);
  retirement_ = loadFrontierRetirement(p);
  semexp::FrontierRetirement(retirement_, camera_, bounds_, config_.clearance_radius_m(), 1.0);  // checks them together
  object_retirement_ = loadObjectRetirement(p);
  node_config_ = loadPlannerNode(p);
  trajectory_ = loadTrajectory(p);
  poses_ = std::make_unique<PoseSource>(loadTf(p), false);  // the latest pose, never an interpolated one: no gap guard
  services_ = std::make_unique<PlannerServices>(nh, config_, camera_, node_config_.service_timeout_s, drops_);

  path_pub_ = pnh.advertise<nav_msgs::Path>("path", 1, true);
  // Not latched: a setpoint streamer that connects late must not fly an old trajectory.
  trajectory_pub_ = pnh.advertise<trajectory_msgs::MultiDOFJointTrajectory>("trajectory", 1);
  candidates_pub_ = pnh.advertise<semantic_exploration::CandidateViewArray>("candidates", 1, true);
  markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("candidate_markers", 1, true);
  status_pub_ = pnh.advertise<ExplorationStatus>("status", 10, true);
  const char* gains[4] = {"entropy", "background", "object", "combined"};
  for (int i = 0; i < 4; ++i)
    gain_pubs_[i] = pnh.advertise<sensor_msgs::Image>(std::string("gain_images/") + gains[i], 1, true);
  plan_srv_ = pnh.advertiseService("plan_once", &PlannerNode::planOnce, this);
  replica_srv_ = pnh.advertiseService("get_map", &PlannerNode::getReplica, this);
  update_sub_ = nh.subscribe("background_map/map_update", 50, &PlannerNode::mapUpdateCallback, this);
  frontiers_sub_ = nh.subscribe("background_map/frontiers", 1, &PlannerNode::frontiersCallback, this);
  objects_sub_ = nh.subscribe("object_map/objects", 1, &PlannerNode::objectsCallback, this);
  goal_sub_ = nh.subscribe("mav/goal_reached", 1, &PlannerNode::goalReachedCallback, this);
  stats_sub_ = nh.subscribe("background_map/stats", 1, &PlannerNode::statsCallback, this);
  rejected_sub_ = nh.subscribe("mav/path_rejected", 5, &PlannerNode::pathRejectedCallback, this);
  timer_ = nh.createTimer(ros::Duration(0.2), &PlannerNode::timerCallback, this);
  ROS_INFO("planner: n %d, P_fr %.2f, a_ent/a_bg/a_obj %.2f/%.2f/%.2f, d_bg %.1f m, d_obj %.1f m",
           config_.n_candidates, config_.p_frontier, config_.a_ent, config_.a_bg, config_.a_obj,
           exploration_.d_bg_m, exploration_.d_obj_m);
  state_ = ExplorationStatus::STATE_WAITING;
  publishStatus(state_, "waiting for the map");
}

void PlannerNode::publishStatus(uint8_t state, const std::string& message) {
  // Between iterations: the iteration's fields stay at 0 (planning_time_s among them, which is how
  // eval/runlog.py tells an iteration's status from these).
  ExplorationStatus s;
  s.header.stamp = ros::Time::now();
  s.header.frame_id = frames_.world;
  s.state = state;
  s.iteration = iteration_;
  s.message = message;
  s.service_timeouts = static_cast<uint32_t>(drops_.count("service_timeout"));
  s.background_observed_share = static_cast<float>(background_share_);
  status_pub_.publish(s);
}

// ---------------------------------------------------------------- map input

bool PlannerNode::applyBlocks(const semantic_exploration::MapBlocks& msg, bool& gap) {
  gap = false;
  semexp::MapBlocksData u;
  const std::string bad = fromMapBlocksMsg(msg, u);
  if (!bad.empty()) {
    drops_.drop("bad_map_encoding", bad);
    return false;
  }
  switch (replica_.apply(u)) {
    case semexp::MapReplica::Result::kApplied:
      // The last applied, not the newest: applied updates come in sequence,
      // and after a clock that went back (a bag played again) the stamps of
      // the same map go back with it.
      replica_stamp_ = msg.header.stamp;
      return true;
    case semexp::MapReplica::Result::kStale:
      // background_map restarted and counts from 1 again; its blocks must not
      // be merged onto the old map. Seen as sequence 1 after a later one, or
      // as any older sequence with a newer stamp: the restarted node's 1 may
      // never arrive (map_update is not latched, and it can go out before the
      // planner has connected to the new node), or its resync may fail. An
      // update queued before a resync is older than what the replica holds,
      // in sequence and in stamp, and is only stale.
      gap = (u.sequence == 1 && replica_.sequence() > 1) || msg.header.stamp > replica_stamp_;
      return false;
    case semexp::MapReplica::Result::kGap: gap = true; return false;
    case semexp::MapReplica::Result::kBadInput: drops_.drop("bad_map_update", replica_.lastError()); return false;
  }
  return false;
}

bool PlannerNode::resync() {
  semantic_exploration::GetMap srv;
  if (!services_->getMap(srv)) return false;
  bool gap = false;
  srv.response.map.full = true;
  const bool ok = applyBlocks(srv.response.map, gap);
  if (ok) ROS_INFO("planner: map replica resynced at sequence %lu (%zu blocks)",
                   static_cast<unsigned long>(replica_.sequence()), replica_.blockCount());
  return ok;
}

bool PlannerNode::getReplica(semantic_exploration::GetMap::Request&, semantic_exploration::GetMap::Response& res) {
  if (replica_.empty()) {
    ROS_WARN("planner: ~get_map refused: the replica holds no map yet");
    return false;
  }
  // The replica keeps uniform blocks as one value: its snapshot is compact whatever was asked.
  res.map = toMapBlocksMsg(replica_.snapshot(), ros::Time::now(), frames_.world);
  ROS_INFO("planner: ~get_map: sent the replica (%zu blocks, sequence %lu)", replica_.blockCount(),
           static_cast<unsigned long>(replica_.sequence()));
  return true;
}

void PlannerNode::mapUpdateCallback(const semantic_exploration::MapBlocksConstPtr& msg) {
  bool gap = false;
  if (!applyBlocks(*msg, gap) && gap) {
    ROS_WARN("planner: map update %lu after %lu (%s): resyncing", static_cast<unsigned long>(msg->sequence),
             static_cast<unsigned long>(replica_.sequence()),
             msg->sequence <= replica_.sequence() ? "the map restarted" : "updates were lost");
    resync();
  }
}

void PlannerNode::frontiersCallback(const sensor_msgs::PointCloud2ConstPtr& msg) {
  const std::string bad = frontiersFromCloud(*msg, frontiers_W_);
  if (!bad.empty()) {
    drops_.drop("bad_frontiers", bad);
    return;
  }
  have_frontiers_ = true;
  frontiers_stamp_ = msg->header.stamp;
}

void PlannerNode::objectsCallback(const semantic_exploration::ObjectArrayConstPtr& msg) {
  std::size_t dropped = 0;
  objects_ = toObjectSummaries(*msg, dropped);
  objects_stamp_ = msg->header.stamp;
  if (dropped > 0) drops_.drop("bad_object", "object with a non-finite box, centroid or share ignored", dropped);
}

void PlannerNode::statsCallback(const semantic_exploration::MapStatsConstPtr& msg) {
  const std::string bad = fromMapStats(*msg, explored_volume_m3_, background_share_);
  if (!bad.empty()) {
    drops_.drop("bad_stats", bad);
    return;
  }
  map_retired_frontiers_ = msg->retired_frontier_count;
  stats_stamp_ = msg->header.stamp;
  stats_frontiers_stamp_ = msg->frontiers_stamp;
  stats_update_sequence_ = msg->map_update_sequence;
}

// ---------------------------------------------------------------- triggers

void PlannerNode::goalReachedCallback(const geometry_msgs::PoseStampedConstPtr&) {
  if (finished_ || state_ != ExplorationStatus::STATE_EXECUTING) return;
  std::string message;
  iterate(message);
}

void PlannerNode::pathRejectedCallback(const std_msgs::StringConstPtr& msg) {
  if (finished_ || state_ != ExplorationStatus::STATE_EXECUTING) return;
  // Replan on the next timer tick after retry_period_s, not at once: the
  // same map would likely give the same path.
  ROS_WARN("planner: the executor rejected the path (%s); replanning in %.1f s", msg->data.c_str(),
           node_config_.retry_period_s);
  state_ = ExplorationStatus::STATE_WAITING;
  last_attempt_ = ros::WallTime::now();
  if (planner_) planner_->discardViews();  // the path was not flown: no evidence for retirement
  publishStatus(state_, "path rejected by the executor: " + msg->data);
}

void PlannerNode::timerCallback(const ros::TimerEvent&) {
  if (finished_) return;
  if (state_ == ExplorationStatus::STATE_EXECUTING) {
    const double waited = (ros::Time::now() - executing_since_).toSec();
    if (waited < node_config_.goal_timeout_factor * expected_duration_s_ + 10.0) return;
    ROS_WARN("planner: goal not reached after %.1f s (expected %.1f s); replanning", waited, expected_duration_s_);
  } else if ((ros::WallTime::now() - last_attempt_).toSec() < node_config_.retry_period_s) {
    return;
  }
  std::string message;
  iterate(message);  // reports "waiting for the map" itself while the replica is empty
}

bool PlannerNode::planOnce(semantic_exploration::PlanOnce::Request& req,
                           semantic_exploration::PlanOnce::Response& res) {
  res.success = res.pending = false;
  // A finished exploration (any termination reason) stays finished: a lockstep
  // simulator keeps asking while its MAV hovers, and planning again would fly on.
  if (finished_) {
    res.message = "not planned: the exploration finished: " + finish_summary_;
    return true;
  }
  std::string missing = req.frame_stamp.isZero() ? "" : missingInputs(req.frame_stamp);
  Eigen::Isometry3d T_WB;
  if (missing.empty() && !req.pose_stamp.isZero()) {
    const std::string err = poses_->lookup(frames_.world, frames_.body, req.pose_stamp, T_WB);
    if (!err.empty()) missing = "the MAV pose at " + std::to_string(req.pose_stamp.toSec()) + " s: " + err;
  }
  if (!missing.empty()) {
    res.pending = true;
    res.message = "not planned: waiting for " + missing;
    return true;
  }
  res.success = iterate(res.message, req.stamp, req.pose_stamp);
  return true;
}

std::string PlannerNode::missingInputs(const ros::Time& frame) const {
  const auto at = [](const ros::Time& t) { return std::to_string(t.toSec()) + " s"; };
  if (stats_stamp_ < frame)
    return "background_map/stats of the frame at " + at(frame) + " (newest here: " + at(stats_stamp_) + ")";
  if (replica_.sequence() < stats_update_sequence_)
    return "background_map/map_update " + std::to_string(stats_update_sequence_) + " (the replica is at " +
           std::to_string(replica_.sequence()) + ")";
  if (frontiers_stamp_ < stats_frontiers_stamp_)
    return "background_map/frontiers of " + at(stats_frontiers_stamp_) + " (newest here: " + at(frontiers_stamp_) + ")";
  // object_map publishes its objects for every frame it handles (deterministic runs: publish_period_s 0).
  if (objects_sub_.getNumPublishers() > 0 && objects_stamp_ < frame)
    return "object_map/objects of the frame at " + at(frame) + " (newest here: " + at(objects_stamp_) + ")";
  return "";
}

// ---------------------------------------------------------------- iteration

bool PlannerNode::iterate(std::string& message, const ros::Time& stamp, const ros::Time& pose_stamp) {
  last_attempt_ = ros::WallTime::now();
  const ros::Time now = stamp.isZero() ? ros::Time::now() : stamp;
  const auto wait = [&](const std::string& why) {
    message = why;
    publishStatus(ExplorationStatus::STATE_WAITING, message);
    return false;
  };
  if (replica_.empty()) return wait("waiting for the map (the replica is empty)");
  Eigen::Isometry3d T_WB;
  const std::string err = poses_->lookup(frames_.world, frames_.body, pose_stamp, T_WB);
  if (!err.empty()) return wait("waiting for the MAV pose: " + err);
  if (!planner_ || planner_resolution_m_ != replica_.resolution_m()) {
    planner_ = std::make_unique<semexp::ExplorationPlanner>(config_, exploration_, bounds_, camera_,
                                                             replica_.resolution_m(), termination_, retirement_,
                                                             object_retirement_);
    planner_resolution_m_ = replica_.resolution_m();
  }
  if (!have_frontiers_) return wait("waiting for the first frontier cloud");
  if (!started_) {
    started_ = true;
    start_time_ = now;
  }
  ++iteration_;
  services_->newIteration();
  state_ = ExplorationStatus::STATE_PLANNING;
  publishStatus(state_, "planning");

  semexp::ExplorationInputs in;
  in.position_W = T_WB.translation();
  in.yaw_rad = std::atan2(T_WB.linear()(1, 0), T_WB.linear()(0, 0));
  in.elapsed_s = (now - start_time_).toSec();
  in.frontiers_W = frontiers_W_;
  in.objects = objects_;
  in.explored_volume_m3 = explored_volume_m3_;
  in.background_observed_share = background_share_;

  semexp::ExplorationProviders prov;
  // Read-only while planning: the map and bounds change only in this node's callbacks, which wait for it.
  prov.is_free = [this](const Eigen::Vector3d& p, double r) {
    return bounds_.contains(p) && replica_.sphereFree(p, r);
  };
  prov.not_occupied = [this](const Eigen::Vector3d& p, double r) { return replica_.sphereNotOccupied(p, r); };
  prov.line_not_occupied = [this](const Eigen::Vector3d& from, const Eigen::Vector3d& u, double length_m,
                                  double step_m) { return replica_.lineNotOccupied(from, u, length_m, step_m); };
  prov.gains = [this](const std::vector<Eigen::Vector3d>& ps) {
    return services_->gains(ps, objects_, replica_.resolution_m());
  };
  prov.history = [this](const std::vector<Eigen::Vector3d>& ps) { return services_->history(ps); };

  semexp::IterationResult r;
  try {
    r = planner_->plan(in, prov);
  } catch (const std::exception& e) {
    r = semexp::IterationResult();
    r.provider_error = true;
    r.message = std::string("planning failed: ") + e.what();
  }
  // Failures of optional services do not stop the iteration; say so.
  for (const auto& note : services_->notes()) r.message += "; " + note;
  if (r.winner >= 0) {
    // Last guard: the replica may have changed since the path was planned.
    const semexp::PathClearance check = semexp::checkPathClearance(
        r.path_W, r.candidates[static_cast<std::size_t>(r.winner)].plan.escaped, config_.clearance_radius_m(),
        config_.mav_radius_m, std::max(0.5 * replica_.resolution_m(), 1e-3), prov.not_occupied);
    if (!check.safe) {
      r.message = "the chosen path failed the final occupancy check (" + check.why + ") and was not published; " +
                  r.message;
      r.winner = -1;
      planner_->discardViews();
    }
  }
  if (!r.object_retirement_events.empty()) ROS_INFO("planner: iteration %u: %s", iteration_, r.object_retirement_events.c_str());
  if (!r.way_out.empty()) ROS_INFO("planner: iteration %u: %s", iteration_, r.way_out.c_str());
  const bool published = r.winner >= 0;
  if (published) publishWinner(r, now);
  publishResult(r, now, in.yaw_rad);

  if (r.finished) {
    finished_ = true;
    finish_summary_ = r.termination_reason + " (" + r.message + ")";
    state_ = ExplorationStatus::STATE_FINISHED;
    ROS_INFO("planner: exploration finished after %u iterations: %s", iteration_, finish_summary_.c_str());
  } else {
    state_ = published ? ExplorationStatus::STATE_EXECUTING : ExplorationStatus::STATE_WAITING;
    if (!published) ROS_WARN("planner: iteration %u: %s", iteration_, r.message.c_str());
  }
  auto status = toExplorationStatus(r, state_, iteration_, frames_.world, now, objects_, background_share_);
  status.service_timeouts = static_cast<uint32_t>(drops_.count("service_timeout"));
  status_pub_.publish(status);
  message = r.message;
  last_attempt_ = ros::WallTime::now();  // the retry period is the pause after an attempt, however long it took
  return published;
}

void PlannerNode::publishWinner(const semexp::IterationResult& r, const ros::Time& now) {
  path_pub_.publish(toPath(r.path_W, r.path_yaw_rad, frames_.world, now));
  const auto& w = r.candidates[static_cast<std::size_t>(r.winner)];
  expected_duration_s_ = w.path_time_s;
  try {
    const semexp::Trajectory tr(r.path_W, r.path_yaw_rad, config_.v_max_mps, config_.omega_max_radps, trajectory_);
    trajectory_pub_.publish(
        toTrajectoryMsg(tr.sample(trajectory_.trajectory_sample_period_s), frames_.world, frames_.body, now));
    // The trajectory stops at every vertex and accelerates: longer than the utility's estimate.
    expected_duration_s_ = std::max(expected_duration_s_, tr.duration_s());
  } catch (const std::invalid_argument& e) {  // the planner's path is finite and non-empty: a defect if it happens
    ROS_ERROR("planner: no trajectory for the path of iteration %u: %s", iteration_, e.what());
  }
  executing_since_ = now;
  // One line per iteration: what won and why, so a run's log shows where the MAV went and for which gain.
  ROS_INFO("planner: iteration %u: %s", iteration_, winnerSummary(r, background_share_, map_retired_frontiers_).c_str());
}

void PlannerNode::publishResult(const semexp::IterationResult& r, const ros::Time& stamp, double current_yaw) {
  const semantic_exploration::CandidateViewArray arr = toCandidateViewArray(r, frames_.world, stamp, current_yaw);
  candidates_pub_.publish(arr);
  markers_pub_.publish(candidateMarkers(r, arr.header, replica_.resolution_m(), objects_));
  if (r.winner < 0) return;
  const int w = config_.raycast_width, h = config_.raycast_height;
  const std::vector<float>* images[4] = {&r.winner_gains.entropy.values, &r.winner_gains.background.values,
                                         &r.winner_gains.object.values, &r.winner_combined.values};  // gain_pubs_ order
  for (int k = 0; k < 4; ++k) gain_pubs_[k].publish(floatImageMsg(arr.header, *images[k], w, h));
}

}  // namespace semexp_ros

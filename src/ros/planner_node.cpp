#include "semantic_exploration/ros/planner_node.hpp"

#include <nav_msgs/Path.h>
#include <sensor_msgs/Image.h>
#include <visualization_msgs/MarkerArray.h>

#include "semantic_exploration/CandidateViewArray.h"
#include "semantic_exploration/ExplorationStatus.h"

namespace semexp_ros {

PlannerNode::PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : tf_listener_(tf_buffer_) {
  const auto p = ParamReader::fromNodeHandle(pnh);
  config_ = loadPlanner(p);
  exploration_ = loadExploration(p);
  camera_ = loadCamera(p);
  bounds_ = loadBounds(p);
  frames_ = loadFrames(p);
  path_pub_ = pnh.advertise<nav_msgs::Path>("path", 1, true);
  candidates_pub_ = pnh.advertise<semantic_exploration::CandidateViewArray>("candidates", 1, true);
  markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("candidate_markers", 1, true);
  status_pub_ = pnh.advertise<semantic_exploration::ExplorationStatus>("status", 10, true);
  const char* gains[4] = {"gain_images/entropy", "gain_images/background", "gain_images/object",
                          "gain_images/combined"};
  for (int i = 0; i < 4; ++i) gain_pubs_[i] = pnh.advertise<sensor_msgs::Image>(gains[i], 1, true);
  plan_srv_ = pnh.advertiseService("plan_once", &PlannerNode::planOnce, this);
  update_sub_ = nh.subscribe("background_map/map_update", 50, &PlannerNode::mapUpdateCallback, this);
  frontiers_sub_ = nh.subscribe("background_map/frontiers", 1, &PlannerNode::frontiersCallback, this);
  objects_sub_ = nh.subscribe("object_map/objects", 1, &PlannerNode::objectsCallback, this);
  goal_sub_ = nh.subscribe("mav/goal_reached", 1, &PlannerNode::goalReachedCallback, this);
  ROS_INFO("planner: n %d, P_fr %.2f, a_ent/a_bg/a_obj %.2f/%.2f/%.2f, d_bg %.1f m, d_obj %.1f m",
           config_.n_candidates, config_.p_frontier, config_.a_ent, config_.a_bg, config_.a_obj,
           exploration_.d_bg_m, exploration_.d_obj_m);
  publishStatus(semantic_exploration::ExplorationStatus::STATE_WAITING, "waiting for the map");
}

void PlannerNode::publishStatus(uint8_t state, const std::string& message) {
  semantic_exploration::ExplorationStatus s;
  s.header.stamp = ros::Time::now();
  s.header.frame_id = frames_.world;
  s.state = state;
  s.iteration = iteration_;
  s.message = message;
  status_pub_.publish(s);
}

void PlannerNode::mapUpdateCallback(const semantic_exploration::MapBlocksConstPtr& msg) {
  last_sequence_ = msg->sequence;
}
void PlannerNode::frontiersCallback(const sensor_msgs::PointCloud2ConstPtr&) {}
void PlannerNode::objectsCallback(const semantic_exploration::ObjectArrayConstPtr&) {}
void PlannerNode::goalReachedCallback(const geometry_msgs::PoseStampedConstPtr&) {}

bool PlannerNode::planOnce(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  res.success = false;
  res.message = "planner: the planning core is not wired into this node";
  return true;
}

}  // namespace semexp_ros

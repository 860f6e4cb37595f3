#pragma once
/// @file planner_node.hpp
/// ROS shell of the next-best-view planner (paper Section IV-D).
///
/// Subscribes `background_map/map_update`, `background_map/frontiers`,
/// `object_map/objects`, `mav/goal_reached`; pose from tf2. Publishes
/// `~path` (nav_msgs/Path, yaw in orientation), `~candidates`
/// (CandidateViewArray), `~candidate_markers`, `~gain_images/*`, `~status`
/// (ExplorationStatus); serves `~plan_once` (std_srvs/Trigger).

#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "semantic_exploration/MapBlocks.h"
#include "semantic_exploration/ObjectArray.h"
#include "semantic_exploration/ros/node_common.hpp"
#include "semantic_exploration/ros/params.hpp"

namespace semexp_ros {

class PlannerNode {
 public:
  PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  void mapUpdateCallback(const semantic_exploration::MapBlocksConstPtr& msg);
  void frontiersCallback(const sensor_msgs::PointCloud2ConstPtr& msg);
  void objectsCallback(const semantic_exploration::ObjectArrayConstPtr& msg);
  void goalReachedCallback(const geometry_msgs::PoseStampedConstPtr& msg);
  bool planOnce(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  void publishStatus(uint8_t state, const std::string& message);

  semexp::PlannerConfig config_;
  semexp::ExplorationConfig exploration_;
  semexp::PinholeCamera camera_;
  semexp::Bounds bounds_;
  FrameNames frames_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Subscriber update_sub_, frontiers_sub_, objects_sub_, goal_sub_;
  ros::Publisher path_pub_, candidates_pub_, markers_pub_, status_pub_;
  ros::Publisher gain_pubs_[4];
  ros::ServiceServer plan_srv_;
  uint32_t iteration_ = 0;
  uint64_t last_sequence_ = 0;
};

}  // namespace semexp_ros

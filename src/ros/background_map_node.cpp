#include "semantic_exploration/ros/background_map_node.hpp"

#include <sensor_msgs/PointCloud2.h>

#include "semantic_exploration/FrameIntegrated.h"
#include "semantic_exploration/MapBlocks.h"
#include "semantic_exploration/MapStats.h"

namespace semexp_ros {

BackgroundMapNode::BackgroundMapNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : tf_listener_(tf_buffer_) {
  const auto p = ParamReader::fromNodeHandle(pnh);
  camera_ = loadCamera(p);
  bounds_ = loadBounds(p);
  config_ = loadBackgroundMap(p);
  exploration_ = loadExploration(p);
  frames_ = loadFrames(p);
  p.get("tf_timeout_s", tf_timeout_s_);
  if (!(tf_timeout_s_ >= 0)) throw semexp::ConfigError("tf_timeout_s", "must be >= 0 s");

  occupied_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("occupied", 1, true);
  frontiers_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("frontiers", 1, true);
  update_pub_ = pnh.advertise<semantic_exploration::MapBlocks>("map_update", 10);
  stats_pub_ = pnh.advertise<semantic_exploration::MapStats>("stats", 10);
  integrated_pub_ = nh.advertise<semantic_exploration::FrameIntegrated>("frame_integrated", 10);
  gains_srv_ = pnh.advertiseService("compute_gains", &BackgroundMapNode::computeGains, this);
  get_map_srv_ = pnh.advertiseService("get_map", &BackgroundMapNode::getMap, this);
  save_srv_ = pnh.advertiseService("save", &BackgroundMapNode::save, this);
  info_sub_ = nh.subscribe("camera/camera_info", 1, &BackgroundMapNode::infoCallback, this);
  depth_sub_ = nh.subscribe("camera/depth/image_raw", 2, &BackgroundMapNode::depthCallback, this);
  ROS_INFO("background_map: resolution %.3f m, bounds [%.1f %.1f %.1f] - [%.1f %.1f %.1f] m",
           config_.resolution_m, bounds_.min_m.x(), bounds_.min_m.y(), bounds_.min_m.z(), bounds_.max_m.x(),
           bounds_.max_m.y(), bounds_.max_m.z());
}

void BackgroundMapNode::infoCallback(const sensor_msgs::CameraInfoConstPtr& msg) {
  semexp::PinholeCamera c;
  const auto err = cameraFromInfo(*msg, camera_.d_min_m, camera_.d_max_m, c);
  if (!err.empty()) {
    drops_.drop("bad_camera_info", err);
    return;
  }
  camera_ = c;
  have_info_ = true;
}

void BackgroundMapNode::depthCallback(const sensor_msgs::ImageConstPtr& msg) {
  semantic_exploration::FrameIntegrated done;
  done.header = msg->header;
  done.node = "background_map";
  done.integrated = false;
  integrated_pub_.publish(done);
}

bool BackgroundMapNode::computeGains(semantic_exploration::ComputeGains::Request&,
                                     semantic_exploration::ComputeGains::Response&) {
  ROS_WARN_THROTTLE(5.0, "background_map: compute_gains called before the map core is wired");
  return false;
}

bool BackgroundMapNode::getMap(semantic_exploration::GetMap::Request&, semantic_exploration::GetMap::Response&) {
  return false;
}

bool BackgroundMapNode::save(semantic_exploration::SaveMap::Request&, semantic_exploration::SaveMap::Response& res) {
  res.success = false;
  res.message = "background_map: the map core is not wired into this node";
  return true;
}

}  // namespace semexp_ros

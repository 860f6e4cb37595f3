#include "semantic_exploration/ros/depth_history_node.hpp"

#include <visualization_msgs/MarkerArray.h>

namespace semexp_ros {

DepthHistoryNode::DepthHistoryNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : tf_listener_(tf_buffer_) {
  const auto p = ParamReader::fromNodeHandle(pnh);
  config_ = loadDepthHistory(p);
  camera_ = loadCamera(p);
  bounds_ = loadBounds(p);
  frames_ = loadFrames(p);
  markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("markers", 1, true);
  masks_srv_ = pnh.advertiseService("get_masks", &DepthHistoryNode::getMasks, this);
  depth_sub_ = nh.subscribe("camera/depth/image_raw", 2, &DepthHistoryNode::depthCallback, this);
  ROS_INFO("depth_history: %.2f m cells, %dx%d images", config_.cell_size_m, config_.width, config_.height);
}

void DepthHistoryNode::depthCallback(const sensor_msgs::ImageConstPtr& msg) {
  cv::Mat depth_m;
  const auto err = depthToMeters(*msg, depth_m);
  if (!err.empty()) drops_.drop("bad_depth", err);
}

bool DepthHistoryNode::getMasks(semantic_exploration::GetHistoryMasks::Request&,
                                semantic_exploration::GetHistoryMasks::Response&) {
  return false;
}

}  // namespace semexp_ros

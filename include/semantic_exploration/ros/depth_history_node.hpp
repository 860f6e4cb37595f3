#pragma once
/// @file depth_history_node.hpp
/// ROS shell of the invalid-depth history (paper Section IV-C).
///
/// Subscribes `camera/depth/image_raw`, `camera/camera_info`; pose from tf2.
/// Publishes `~markers` (MarkerArray); serves `~get_masks` (GetHistoryMasks).

#include <ros/ros.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "semantic_exploration/GetHistoryMasks.h"
#include "semantic_exploration/ros/node_common.hpp"
#include "semantic_exploration/ros/params.hpp"

namespace semexp_ros {

class DepthHistoryNode {
 public:
  DepthHistoryNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  void depthCallback(const sensor_msgs::ImageConstPtr& msg);
  bool getMasks(semantic_exploration::GetHistoryMasks::Request& req,
                semantic_exploration::GetHistoryMasks::Response& res);

  semexp::DepthHistoryConfig config_;
  semexp::PinholeCamera camera_;
  semexp::Bounds bounds_;
  FrameNames frames_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Subscriber depth_sub_;
  ros::Publisher markers_pub_;
  ros::ServiceServer masks_srv_;
  DropCounter drops_;
};

}  // namespace semexp_ros

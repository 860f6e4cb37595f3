#pragma once
/// @file instance_matching_node.hpp
/// ROS shell of instance matching (paper Section IV-B.1).
///
/// Subscribes `detections` (Detections) and `camera/depth/image_raw`; pose
/// from tf2; renders known objects through the `object_map/render_instances`
/// service; publishes `matched_detections` (MatchedDetections).

#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "semantic_exploration/Detections.h"
#include "semantic_exploration/ros/node_common.hpp"
#include "semantic_exploration/ros/params.hpp"

namespace semexp_ros {

class InstanceMatchingNode {
 public:
  InstanceMatchingNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  void detectionsCallback(const semantic_exploration::DetectionsConstPtr& msg);

  semexp::MatchingConfig config_;
  semexp::ClassTable classes_;
  FrameNames frames_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Subscriber detections_sub_;
  ros::Publisher matched_pub_;
  ros::ServiceClient render_client_;
  DropCounter drops_;
};

}  // namespace semexp_ros

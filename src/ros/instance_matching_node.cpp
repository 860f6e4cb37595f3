#include "semantic_exploration/ros/instance_matching_node.hpp"

#include "semantic_exploration/MatchedDetections.h"
#include "semantic_exploration/RenderInstances.h"

namespace semexp_ros {

InstanceMatchingNode::InstanceMatchingNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : tf_listener_(tf_buffer_) {
  const auto p = ParamReader::fromNodeHandle(pnh);
  config_ = loadMatching(p);
  classes_ = loadClasses(p);
  frames_ = loadFrames(p);
  matched_pub_ = nh.advertise<semantic_exploration::MatchedDetections>("matched_detections", 10);
  render_client_ = nh.serviceClient<semantic_exploration::RenderInstances>("object_map/render_instances");
  detections_sub_ = nh.subscribe("detections", 5, &InstanceMatchingNode::detectionsCallback, this);
  ROS_INFO("instance_matching: iou_threshold %.2f, min_mask_pixels %d", config_.iou_threshold,
           config_.min_mask_pixels);
}

void InstanceMatchingNode::detectionsCallback(const semantic_exploration::DetectionsConstPtr& msg) {
  drops_.drop("matching_unavailable", "matching core not wired into this node");
}

}  // namespace semexp_ros

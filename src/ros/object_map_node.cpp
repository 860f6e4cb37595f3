#include "semantic_exploration/ros/object_map_node.hpp"

#include <visualization_msgs/MarkerArray.h>

#include "semantic_exploration/FrameIntegrated.h"
#include "semantic_exploration/ObjectArray.h"

namespace semexp_ros {

ObjectMapNode::ObjectMapNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : tf_listener_(tf_buffer_) {
  const auto p = ParamReader::fromNodeHandle(pnh);
  config_ = loadObjectMap(p);
  classes_ = loadClasses(p);
  exploration_ = loadExploration(p);
  camera_ = loadCamera(p);
  frames_ = loadFrames(p);
  objects_pub_ = pnh.advertise<semantic_exploration::ObjectArray>("objects", 1, true);
  meshes_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("meshes", 1, true);
  integrated_pub_ = nh.advertise<semantic_exploration::FrameIntegrated>("frame_integrated", 10);
  render_srv_ = pnh.advertiseService("render_instances", &ObjectMapNode::renderInstances, this);
  gains_srv_ = pnh.advertiseService("compute_gains", &ObjectMapNode::computeGains, this);
  save_srv_ = pnh.advertiseService("save", &ObjectMapNode::save, this);
  matched_sub_ = nh.subscribe("matched_detections", 5, &ObjectMapNode::matchedCallback, this);
  std::string interest;
  for (const auto& c : classes_.of_interest) interest += (interest.empty() ? "" : ", ") + c;
  ROS_INFO("object_map: classes of interest [%s]", interest.c_str());
}

void ObjectMapNode::matchedCallback(const semantic_exploration::MatchedDetectionsConstPtr& msg) {
  semantic_exploration::FrameIntegrated done;
  done.header = msg->header;
  done.node = "object_map";
  done.integrated = false;
  integrated_pub_.publish(done);
}

bool ObjectMapNode::renderInstances(semantic_exploration::RenderInstances::Request&,
                                    semantic_exploration::RenderInstances::Response&) {
  return false;
}

bool ObjectMapNode::computeGains(semantic_exploration::ComputeGains::Request&,
                                 semantic_exploration::ComputeGains::Response&) {
  return false;
}

bool ObjectMapNode::save(semantic_exploration::SaveMap::Request&, semantic_exploration::SaveMap::Response& res) {
  res.success = false;
  res.message = "object_map: the object map core is not wired into this node";
  return true;
}

}  // namespace semexp_ros

#pragma once
/// @file object_map_node.hpp
/// ROS shell of the per-object TSDF submaps (paper Section IV-B).
///
/// Subscribes `matched_detections`, `camera/depth/image_raw`,
/// `camera/rgb/image_raw`; pose from tf2. Publishes `~objects`
/// (ObjectArray), `~meshes` (MarkerArray), `frame_integrated`; serves
/// `~render_instances`, `~compute_gains`, `~save`.

#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "semantic_exploration/ComputeGains.h"
#include "semantic_exploration/MatchedDetections.h"
#include "semantic_exploration/RenderInstances.h"
#include "semantic_exploration/SaveMap.h"
#include "semantic_exploration/ros/node_common.hpp"
#include "semantic_exploration/ros/params.hpp"

namespace semexp_ros {

class ObjectMapNode {
 public:
  ObjectMapNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  void matchedCallback(const semantic_exploration::MatchedDetectionsConstPtr& msg);
  bool renderInstances(semantic_exploration::RenderInstances::Request& req,
                       semantic_exploration::RenderInstances::Response& res);
  bool computeGains(semantic_exploration::ComputeGains::Request& req, semantic_exploration::ComputeGains::Response& res);
  bool save(semantic_exploration::SaveMap::Request& req, semantic_exploration::SaveMap::Response& res);

  semexp::ObjectMapConfig config_;
  semexp::ClassTable classes_;
  semexp::ExplorationConfig exploration_;
  semexp::PinholeCamera camera_;
  FrameNames frames_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Subscriber matched_sub_;
  ros::Publisher objects_pub_, meshes_pub_, integrated_pub_;
  ros::ServiceServer render_srv_, gains_srv_, save_srv_;
  DropCounter drops_;
};

}  // namespace semexp_ros

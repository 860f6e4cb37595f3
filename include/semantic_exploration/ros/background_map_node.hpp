#pragma once
/// @file background_map_node.hpp
/// ROS shell of the background occupancy map (paper Section IV-A).
///
/// Subscribes `camera/depth/image_raw` (32FC1 m or 16UC1 mm),
/// `camera/rgb/image_raw`, `camera/camera_info`; pose from tf2 at the image
/// stamp. Publishes `~occupied`, `~frontiers` (PointCloud2), `~map_update`
/// (MapBlocks), `~stats` (MapStats), `frame_integrated`; serves
/// `~compute_gains`, `~get_map`, `~save`.

#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <memory>

#include "semantic_exploration/ComputeGains.h"
#include "semantic_exploration/GetMap.h"
#include "semantic_exploration/SaveMap.h"
#include "semantic_exploration/ros/node_common.hpp"
#include "semantic_exploration/ros/params.hpp"

namespace semexp_ros {

class BackgroundMapNode {
 public:
  BackgroundMapNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  void depthCallback(const sensor_msgs::ImageConstPtr& msg);
  void infoCallback(const sensor_msgs::CameraInfoConstPtr& msg);
  bool computeGains(semantic_exploration::ComputeGains::Request& req, semantic_exploration::ComputeGains::Response& res);
  bool getMap(semantic_exploration::GetMap::Request& req, semantic_exploration::GetMap::Response& res);
  bool save(semantic_exploration::SaveMap::Request& req, semantic_exploration::SaveMap::Response& res);

  semexp::PinholeCamera camera_;
  semexp::Bounds bounds_;
  semexp::BackgroundMapConfig config_;
  semexp::ExplorationConfig exploration_;
  FrameNames frames_;
  double tf_timeout_s_ = 0.1;

  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Subscriber depth_sub_, info_sub_;
  ros::Publisher occupied_pub_, frontiers_pub_, update_pub_, stats_pub_, integrated_pub_;
  ros::ServiceServer gains_srv_, get_map_srv_, save_srv_;
  DropCounter drops_;
  bool have_info_ = false;
};

}  // namespace semexp_ros

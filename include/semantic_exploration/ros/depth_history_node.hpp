#pragma once
/// @file depth_history_node.hpp
/// ROS shell of the invalid-depth history (paper Section IV-C).
///
/// Subscribes `camera/depth/image_raw` (32FC1 m or 16UC1 mm),
/// `camera/camera_info`; pose from tf2 (world <- depth frame at the image
/// stamp). Publishes `~markers` (MarkerArray: one cube per grid cell holding
/// invalid directions, redder with more of them; at most once per
/// marker_period_s) and `frame_integrated` (FrameIntegrated, node
/// "depth_history", for the simulator's lockstep); serves `~get_masks`
/// (GetHistoryMasks).
///
/// The history's image layout uses the camera's vertical field of view, so
/// it is built at the first depth frame whose size matches the latest
/// camera_info (or, before any camera_info, the `camera/*` parameters) and
/// kept for the run. A camera_info over the size cap or of another size
/// than the depth frames is dropped ("bad_camera_info").

#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <memory>

#include "semantic_exploration/GetHistoryMasks.h"
#include "semantic_exploration/core/depth_history.hpp"
#include "semantic_exploration/ros/camera_node.hpp"

namespace semexp_ros {

class DepthHistoryNode : public CameraNode {
 public:
  DepthHistoryNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  void depthCallback(const sensor_msgs::ImageConstPtr& msg);
  bool getMasks(semantic_exploration::GetHistoryMasks::Request& req,
                semantic_exploration::GetHistoryMasks::Response& res);
  void publishMarkers(const ros::Time& stamp);
  /// The history's image layout is fixed at its first frame.
  bool cameraChangeable() const override { return !history_; }

  semexp::DepthHistoryConfig config_;
  DepthHistoryNodeConfig node_config_;
  std::unique_ptr<semexp::DepthHistory> history_;
  uint64_t frames_integrated_ = 0;
  bool markers_dirty_ = false;
  ros::WallTime last_markers_;
  ros::Subscriber depth_sub_;
  ros::Publisher markers_pub_;
  ros::ServiceServer masks_srv_;
};

}  // namespace semexp_ros

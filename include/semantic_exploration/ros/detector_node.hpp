#pragma once
/// @file detector_node.hpp
/// ROS shell of the instance-segmentation detector (core/detector/).
///
/// Subscribes `camera/rgb/image_raw` (rgb8, bgr8, rgba8, bgra8 or mono8) and
/// `camera/camera_info` (its size is the depth image's: the mapping nodes
/// take depth of the camera_info's size). Publishes `detections`
/// (semantic_exploration/Detections: a 16UC1 instance image of the
/// camera_info's size, `camera/width` x `camera/height` until one arrives,
/// plus one entry per instance; header = the colour image's). Frames that
/// cannot be used (unknown encoding, failed inference) and camera_info of size 0
/// or beyond PinholeCamera's caps are dropped and counted
/// on /dropped_input. A missing, unreadable or wrongly shaped model stops the
/// node at start-up naming `detector/model_path` (or the parameter at fault).

#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <memory>

#include "semantic_exploration/core/class_table.hpp"
#include "semantic_exploration/core/detector/instance_segmenter.hpp"
#include "semantic_exploration/ros/node_common.hpp"

namespace semexp_ros {

class DetectorNode {
 public:
  DetectorNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  void colourCallback(const sensor_msgs::ImageConstPtr& msg);
  void infoCallback(const sensor_msgs::CameraInfoConstPtr& msg);

  semexp::ClassTable classes_;
  std::unique_ptr<semexp::InstanceSegmenter> segmenter_;
  cv::Size out_size_;  ///< instance image size: the depth image's (camera_info), px
  semexp::DetectorTiming sum_;  ///< summed stage times since the last timing log, ms
  uint64_t frames_ = 0, frames_since_log_ = 0;
  ros::WallTime last_log_;
  ros::Subscriber colour_sub_, info_sub_;
  ros::Publisher detections_pub_;
  DropCounter drops_;
};

}  // namespace semexp_ros

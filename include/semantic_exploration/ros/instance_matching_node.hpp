#pragma once
/// @file instance_matching_node.hpp
/// ROS shell of instance matching (paper Section IV-B.1).
///
/// Subscribes `detections` (Detections) and `camera/depth/image_raw`
/// (approximately time-synchronised) and `camera/camera_info`; pose from tf2;
/// renders the known objects through the `object_map/render_instances`
/// service; matches with semexp::matchDetections (policy in
/// core/instance_matching.hpp); publishes `matched_detections`
/// (MatchedDetections) with masks under min_mask_pixels removed. Detections
/// of classes without object maps are left out; bad input (sizes, encodings,
/// unknown class ids, a class_name that is not class_id's, masks of unlisted instance ids, missing tf, a camera
/// outside `bounds`, render service down) is dropped with a counter and a throttled log line, and the
/// frame goes on without detections (so object_map still handles it). Each frame is reported on
/// `frame_integrated` (its CPU time for the run's CPU budget; lockstep does not wait for this node).

#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/synchronizer.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <memory>

#include "semantic_exploration/Detections.h"
#include "semantic_exploration/RenderInstances.h"
#include "semantic_exploration/ros/camera_node.hpp"

namespace semexp_ros {

class InstanceMatchingNode : public CameraNode {
 public:
  InstanceMatchingNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  using SyncPolicy =
      message_filters::sync_policies::ApproximateTime<semantic_exploration::Detections, sensor_msgs::Image>;

  void frameCallback(const semantic_exploration::DetectionsConstPtr& msg, const sensor_msgs::ImageConstPtr& depth);
  /// Publishes the frame without detections (an all-zero instance image of width_px x height_px).
  void publishEmpty(const std_msgs::Header& header, int width_px, int height_px);
  /// Calls object_map/render_instances; on a failure reconnects and tries once more.
  bool callRender(semantic_exploration::RenderInstances& srv);

  ros::NodeHandle nh_;
  semexp::MatchingConfig config_;
  semexp::ClassTable classes_;
  message_filters::Subscriber<semantic_exploration::Detections> detections_sub_;
  message_filters::Subscriber<sensor_msgs::Image> depth_sub_;
  std::unique_ptr<message_filters::Synchronizer<SyncPolicy>> sync_;
  ros::Publisher matched_pub_;
  ros::ServiceClient render_client_;
  FrameGapCounter frame_gaps_;  ///< detection frames missing from the paired stream ("frame_gap")
};

}  // namespace semexp_ros

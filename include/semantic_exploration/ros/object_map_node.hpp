#pragma once
/// @file object_map_node.hpp
/// ROS shell of the per-object TSDF submaps (paper Section IV-B).
///
/// Subscribes `matched_detections`, `camera/depth/image_raw`,
/// `camera/rgb/image_raw` (approximately time-synchronised) and
/// `camera/camera_info`; pose from tf2. Publishes `~objects` (ObjectArray) and
/// `~meshes` (MarkerArray: per object its coloured mesh, ns object_meshes; its
/// surface's bounding box as a LINE_LIST, ns object_boxes; and a
/// "<class> #<id>" TEXT_VIEW_FACING label above it, ns object_labels; marker
/// id = object id), both at most every object_map/publish_period_s,
/// and `frame_integrated` after every frame; serves `~render_instances`,
/// `~compute_gains` and `~save`. Bad input (sizes, encodings, unknown classes
/// or objects, missing tf, a camera outside `bounds`) is dropped with a
/// counter and a throttled log line.

#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/synchronizer.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <memory>
#include <set>

#include "semantic_exploration/ComputeGains.h"
#include "semantic_exploration/MatchedDetections.h"
#include "semantic_exploration/RenderInstances.h"
#include "semantic_exploration/SaveMap.h"
#include "semantic_exploration/core/object_map.hpp"
#include "semantic_exploration/core/object_summary_cache.hpp"
#include "semantic_exploration/ros/camera_node.hpp"

namespace semexp_ros {

class ObjectMapNode : public CameraNode {
 public:
  ObjectMapNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  using SyncPolicy = message_filters::sync_policies::ApproximateTime<semantic_exploration::MatchedDetections,
                                                                     sensor_msgs::Image, sensor_msgs::Image>;

  void frameCallback(const semantic_exploration::MatchedDetectionsConstPtr& matched,
                     const sensor_msgs::ImageConstPtr& depth, const sensor_msgs::ImageConstPtr& rgb);
  void publishObjects(const ros::Time& stamp);
  /// Serves ~render_instances (answerRender); its CPU time counts in the next reported frame.
  bool renderInstances(semantic_exploration::RenderInstances::Request& req,
                       semantic_exploration::RenderInstances::Response& res);
  bool answerRender(semantic_exploration::RenderInstances::Request& req,
                    semantic_exploration::RenderInstances::Response& res);
  bool computeGains(semantic_exploration::ComputeGains::Request& req, semantic_exploration::ComputeGains::Response& res);
  bool save(semantic_exploration::SaveMap::Request& req, semantic_exploration::SaveMap::Response& res);

  semexp::ObjectMapConfig config_;
  semexp::ClassTable classes_;
  semexp::ExplorationConfig exploration_;
  std::unique_ptr<semexp::ObjectMap> map_;
  ros::Time last_stamp_;
  ros::Time last_published_stamp_;  ///< newest stamp ~objects went out with
  bool integrated_any_ = false;  ///< For the once-only first-frame log line.
  /// Last render_instances answer, reused by the frame it was made for if the map did not change since.
  struct CachedRender {
    ros::Time stamp;
    std::uint64_t version = 0;
    cv::Mat ids;
  } cached_render_;
  std::unique_ptr<semexp::ObjectSummaryCache> summaries_;  ///< ~objects' summaries (d_obj), kept per TSDF revision
  ros::WallTime last_publish_;
  std::set<std::uint32_t> marker_ids_;  ///< objects whose markers rviz holds (deleted when the object goes)
  message_filters::Subscriber<semantic_exploration::MatchedDetections> matched_sub_;
  message_filters::Subscriber<sensor_msgs::Image> depth_sub_, rgb_sub_;
  std::unique_ptr<message_filters::Synchronizer<SyncPolicy>> sync_;
  ros::Publisher objects_pub_, meshes_pub_;
  ros::ServiceServer render_srv_, gains_srv_, save_srv_;
};

}  // namespace semexp_ros

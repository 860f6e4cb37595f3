#pragma once
/// @file background_map_node.hpp
/// ROS shell of the background occupancy map (paper Section IV-A).
///
/// Subscribes `camera/depth/image_raw` (32FC1 m or 16UC1 mm),
/// `camera/rgb/image_raw` (optional; paired with depth by stamp),
/// `camera/camera_info`; pose from tf2 at the image stamp. Publishes
/// `~occupied` (PointCloud2 xyzrgb, throttled), `~frontiers` (PointCloud2 xyz,
/// throttled; active frontiers only), `~retired_frontiers` (PointCloud2 xyz,
/// throttled; frontiers retired by FrontierEvidence), `~map_update` (MapBlocks, changed blocks only), `~stats`
/// (MapStats), `frame_integrated`; serves `~compute_gains`, `~get_map`,
/// `~save` (OctoMap .bt plus the own format).
///
/// Bad input (unsupported encodings, sizes that disagree with camera_info,
/// depth before any camera_info, no tf at the stamp, a camera outside the
/// bounds) drops the frame with a throttled log line and a MapStats counter;
/// invalid depth pixels are counted and carve nothing. Depth frames missing
/// from the stream (stamp gaps of the camera period) are counted as
/// "frame_gap"; every count also goes to /dropped_input (DropCounter).
///
/// Respawned mid-flight by its launch (the /run_id its first instance
/// recorded), the node marks no free sphere around the start (the MAV may fly
/// just above the floor) and asks `restore_map_service` (the planner's
/// `~get_map`, its replica) for the occupancy it lost; colour and observation
/// distances start anew. If that fails (logged, and counted as the service
/// call's failure or "bad_restored_map") the map starts empty.

#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <deque>
#include <memory>
#include <string>

#include "semantic_exploration/ComputeGains.h"
#include "semantic_exploration/GetMap.h"
#include "semantic_exploration/SaveMap.h"
#include "semantic_exploration/core/frontier_evidence.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"
#include "semantic_exploration/ros/camera_node.hpp"
#include "semantic_exploration/ros/service_caller.hpp"
#include "semantic_exploration/ros/node_common.hpp"

namespace semexp_ros {

class BackgroundMapNode : public CameraNode {
 public:
  BackgroundMapNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  void depthCallback(const sensor_msgs::ImageConstPtr& msg);
  void rgbCallback(const sensor_msgs::ImageConstPtr& msg);
  void flushTimer(const ros::WallTimerEvent&);
  /// Integrates depth (with `rgb` if non-null); always reports frame_integrated.
  void processFrame(const sensor_msgs::ImageConstPtr& depth, const sensor_msgs::ImageConstPtr& rgb);
  /// A respawned instance: the lost occupancy from restore_map_service (logged either way).
  void restoreMap(ros::NodeHandle& nh);
  sensor_msgs::ImageConstPtr matchingRgb(const ros::Time& stamp) const;
  void publishStats(const std_msgs::Header& header);
  void publishClouds(const ros::Time& stamp);
  void publishOccupied(const ros::Time& stamp);
  /// A new ~occupied subscriber: sends the cloud if the last one was skipped for want of listeners.
  void occupiedConnected(const ros::SingleSubscriberPublisher&);
  bool computeGains(semantic_exploration::ComputeGains::Request& req, semantic_exploration::ComputeGains::Response& res);
  bool getMap(semantic_exploration::GetMap::Request& req, semantic_exploration::GetMap::Response& res);
  bool save(semantic_exploration::SaveMap::Request& req, semantic_exploration::SaveMap::Response& res);

  semexp::BackgroundMapConfig config_;
  semexp::ExplorationConfig exploration_;
  BackgroundMapNodeConfig node_config_;

  std::unique_ptr<semexp::OccupancyMap> map_;
  std::unique_ptr<semexp::FrontierEvidence> evidence_;  ///< frontiers looked at without resolving them
  ros::Subscriber depth_sub_, rgb_sub_;
  ros::Publisher occupied_pub_, frontiers_pub_, retired_pub_, update_pub_, stats_pub_;
  ros::ServiceServer gains_srv_, get_map_srv_, save_srv_;
  ros::WallTimer flush_timer_;
  FrameGapCounter depth_gaps_;  ///< depth frames missing from the stream ("frame_gap")

  std::deque<sensor_msgs::ImageConstPtr> rgb_buffer_;  ///< recent colour images, oldest first
  sensor_msgs::ImageConstPtr pending_depth_;           ///< depth waiting for its colour image
  ros::WallTime pending_since_;
  ros::WallTime last_rgb_wall_;
  ros::WallTime last_occupied_pub_, last_frontier_pub_;
  // What went out before each stats message (MapStats map_update_sequence, frontiers_stamp): a listener
  // that has the stats of a frame can tell whether the update and cloud published before them reached it.
  std::uint64_t last_update_sequence_ = 0;
  ros::Time last_frontiers_stamp_;
  std_msgs::Header last_header_;
  std::uint64_t frames_integrated_ = 0;
  std::string run_id_;           ///< the launch's /run_id ("" without one)
  bool respawned_ = false;  ///< an earlier instance of this run marked the start free: no sphere, map restored
  std::unique_ptr<ServiceCaller> restore_caller_;  ///< restoreMap's bounded call (kept: a call given up ends later)
  std::uint64_t invalid_depth_pixels_ = 0;
  float last_integration_ms_ = 0.f, last_frontier_ms_ = 0.f;
  semexp::OccupancyMap::SurfaceObservation surface_;  ///< surface seen from <= d_bg, at the last measurement
  StampPeriod surface_share_period_;                   ///< paces surface_ (surface_share_period_s)
  bool frontiers_dirty_ = false;  ///< the map changed since the last ~frontiers cloud
  bool occupied_dirty_ = false;   ///< ... since the last ~occupied cloud (sent or skipped)
  bool occupied_skipped_ = false;  ///< an ~occupied cloud was due but nobody listened
};

}  // namespace semexp_ros

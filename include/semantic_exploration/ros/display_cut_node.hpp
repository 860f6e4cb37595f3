#pragma once
/// @file display_cut_node.hpp
/// A display cut for rviz: the background map's clouds without what lies
/// above `display_cut/max_z_m` (the ceiling, and the frontiers over it), so
/// that a view from above shows the rooms, the objects, the path and the
/// frontiers inside the map instead of its roof.
///
/// Republishes `background_map/occupied` as `~occupied` and
/// `background_map/frontiers` as `~frontiers` (PointCloud2, latched, same
/// fields), keeping the points whose z is <= max_z_m. It subscribes to a
/// source only while its output has a subscriber, so without rviz it costs
/// nothing (and background_map builds no occupied cloud for it). A cloud
/// without a FLOAT32 z is dropped and counted (`bad_cloud`).

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include <string>

#include "semantic_exploration/ros/node_common.hpp"

namespace semexp_ros {

class DisplayCutNode {
 public:
  DisplayCutNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  struct Relay {
    std::string from;
    ros::Publisher pub;
    ros::Subscriber sub;
  };
  /// Subscribes to the source while the output has subscribers.
  void update(Relay& r);
  void cloud(Relay& r, const sensor_msgs::PointCloud2ConstPtr& msg);

  ros::NodeHandle nh_;
  double max_z_m_ = 2.0;
  DropCounter drops_;
  Relay relays_[2];
};

}  // namespace semexp_ros

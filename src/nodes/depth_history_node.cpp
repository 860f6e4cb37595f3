// depth_history: see README (nodes table) and include/semantic_exploration/ros/depth_history_node.hpp.
#include "semantic_exploration/ros/depth_history_node.hpp"
#include "semantic_exploration/ros/node_common.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "depth_history");
  return semexp_ros::runNode<semexp_ros::DepthHistoryNode>("depth_history");
}

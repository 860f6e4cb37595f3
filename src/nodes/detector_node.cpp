// detector: see README (nodes table) and include/semantic_exploration/ros/detector_node.hpp.
#include "semantic_exploration/ros/detector_node.hpp"
#include "semantic_exploration/ros/node_common.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "detector");
  return semexp_ros::runNode<semexp_ros::DetectorNode>("detector");
}

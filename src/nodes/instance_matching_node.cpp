// instance_matching: see README (nodes table) and include/semantic_exploration/ros/instance_matching_node.hpp.
#include "semantic_exploration/ros/instance_matching_node.hpp"
#include "semantic_exploration/ros/node_common.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "instance_matching");
  return semexp_ros::runNode<semexp_ros::InstanceMatchingNode>("instance_matching");
}

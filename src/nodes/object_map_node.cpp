// object_map: see README (nodes table) and include/semantic_exploration/ros/object_map_node.hpp.
#include "semantic_exploration/ros/object_map_node.hpp"
#include "semantic_exploration/ros/node_common.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "object_map");
  return semexp_ros::runNode<semexp_ros::ObjectMapNode>("object_map");
}

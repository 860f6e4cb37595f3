// display_cut: see README (nodes table) and include/semantic_exploration/ros/display_cut_node.hpp.
#include "semantic_exploration/ros/display_cut_node.hpp"
#include "semantic_exploration/ros/node_common.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "display_cut");
  return semexp_ros::runNode<semexp_ros::DisplayCutNode>("display_cut");
}

// setpoint_streamer: see README (nodes table) and include/semantic_exploration/ros/setpoint_streamer_node.hpp.
#include "semantic_exploration/ros/setpoint_streamer_node.hpp"
#include "semantic_exploration/ros/node_common.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "setpoint_streamer");
  return semexp_ros::runNode<semexp_ros::SetpointStreamerNode>("setpoint_streamer");
}

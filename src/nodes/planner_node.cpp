// planner: see README (nodes table) and include/semantic_exploration/ros/planner_node.hpp.
#include "semantic_exploration/ros/planner_node.hpp"
#include "semantic_exploration/ros/node_common.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "planner");
  return semexp_ros::runNode<semexp_ros::PlannerNode>("planner");
}

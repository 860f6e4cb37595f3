// detector: see README (nodes table) and include/semantic_exploration/ros/detector_node.hpp.
#include "semantic_exploration/ros/node_main.hpp"

int main(int argc, char** argv) { return semexp_ros::runNodeMain(semexp_ros::NodeKind::kDetector, argc, argv); }

// The node executables' common main (see node_main.hpp).
#include "semantic_exploration/ros/node_main.hpp"

#include "semantic_exploration/ros/background_map_node.hpp"
#include "semantic_exploration/ros/depth_history_node.hpp"
#include "semantic_exploration/ros/detector_node.hpp"
#include "semantic_exploration/ros/display_cut_node.hpp"
#include "semantic_exploration/ros/instance_matching_node.hpp"
#include "semantic_exploration/ros/node_common.hpp"
#include "semantic_exploration/ros/object_map_node.hpp"
#include "semantic_exploration/ros/planner_node.hpp"
#include "semantic_exploration/ros/setpoint_streamer_node.hpp"

namespace semexp_ros {

const char* nodeName(NodeKind kind) {
  switch (kind) {
    case NodeKind::kBackgroundMap: return "background_map";
    case NodeKind::kInstanceMatching: return "instance_matching";
    case NodeKind::kObjectMap: return "object_map";
    case NodeKind::kDepthHistory: return "depth_history";
    case NodeKind::kPlanner: return "planner";
    case NodeKind::kDetector: return "detector";
    case NodeKind::kSetpointStreamer: return "setpoint_streamer";
    case NodeKind::kDisplayCut: return "display_cut";
  }
  return "unknown_node";
}

int runNodeMain(NodeKind kind, int argc, char** argv) {
  const char* name = nodeName(kind);
  ros::init(argc, argv, name);
  switch (kind) {
    case NodeKind::kBackgroundMap: return runNode<BackgroundMapNode>(name);
    case NodeKind::kInstanceMatching: return runNode<InstanceMatchingNode>(name);
    case NodeKind::kObjectMap: return runNode<ObjectMapNode>(name);
    case NodeKind::kDepthHistory: return runNode<DepthHistoryNode>(name);
    case NodeKind::kPlanner: return runNode<PlannerNode>(name);
    case NodeKind::kDetector: return runNode<DetectorNode>(name);
    case NodeKind::kSetpointStreamer: return runNode<SetpointStreamerNode>(name);
    case NodeKind::kDisplayCut: return runNode<DisplayCutNode>(name);
  }
  ROS_FATAL("%s: no such node kind (%d)", name, static_cast<int>(kind));  // an enumerator missing above
  return 1;
}

}  // namespace semexp_ros

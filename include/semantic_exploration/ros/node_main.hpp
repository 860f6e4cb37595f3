#pragma once
/// @file node_main.hpp
/// The one call each node executable's main() makes. Deliberately free of ROS
/// and node headers: a main that included its node class would parse roscpp,
/// the messages and the core again (about 8 s of compile CPU per executable)
/// only to instantiate runNode; node_main.cpp does that once for all nodes.

namespace semexp_ros {

/// The nodes that have an executable of their own (src/nodes/<name>_node.cpp).
enum class NodeKind {
  kBackgroundMap,
  kInstanceMatching,
  kObjectMap,
  kDepthHistory,
  kPlanner,
  kDetector,
  kSetpointStreamer,
  kDisplayCut,
};

/// The node's default ROS name ("background_map", ...), also its log prefix.
const char* nodeName(NodeKind kind);

/// ros::init under nodeName(kind), then runNode for that node's class: its
/// exit code (0 after a clean shutdown, 2 for invalid configuration, 1 for
/// any other error at start-up).
int runNodeMain(NodeKind kind, int argc, char** argv);

}  // namespace semexp_ros

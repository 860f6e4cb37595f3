#pragma once
/// @file planner_markers.hpp
/// rviz markers of one planning iteration (`planner/candidate_markers`).

#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include "semantic_exploration/core/planning/exploration_planner.hpp"

namespace semexp_ros {

/// A DELETEALL first, then per candidate a sphere coloured by utility relative
/// to the best (red low, green high; grey if unreachable; the winner's twice
/// as large) in namespace "candidates"; for reachable ones an arrow along the
/// chosen yaw ("candidate_yaw") and the utility in 1/s as text
/// ("candidate_utility"); and the winner's path as a blue line strip
/// ("winner_path"). All in header.frame_id.
visualization_msgs::MarkerArray candidateMarkers(const semexp::IterationResult& r, const std_msgs::Header& header);

}  // namespace semexp_ros

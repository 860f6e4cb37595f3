#pragma once
/// @file planner_markers.hpp
/// rviz markers and the log line of one planning iteration (`planner/candidate_markers`).

#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>

#include "semantic_exploration/core/planning/exploration_planner.hpp"

namespace semexp_ros {

/// A DELETEALL first, then per candidate a sphere coloured by utility relative
/// to the best (red low, green high; grey if unreachable; the winner's twice
/// as large) in namespace "candidates"; for reachable ones an arrow along the
/// chosen yaw ("candidate_yaw") and the utility in 1/s as text
/// ("candidate_utility"); and the winner's path as a blue line strip
/// ("winner_path"), and the retired frontier voxels as purple cubes of
/// voxel_size_m ("retired_frontiers"; active ones are in the background
/// map's frontier cloud), and the boxes of the objects retired by evidence
/// as purple wireframes ("retired_objects"; `objects` gives their boxes).
/// All in header.frame_id.
visualization_msgs::MarkerArray candidateMarkers(const semexp::IterationResult& r, const std_msgs::Header& header,
                                                 double voxel_size_m,
                                                 const std::vector<semexp::ObjectSummary>& objects = {});

/// One line on the winner of an iteration for the log: its source, where,
/// its gains, path and utility, and the frontiers and background share
/// (background_share: seen from <= d_bg, negative if unknown; map_retired:
/// frontier voxels the background map retired by evidence).
std::string winnerSummary(const semexp::IterationResult& r, double background_share, std::size_t map_retired);

}  // namespace semexp_ros

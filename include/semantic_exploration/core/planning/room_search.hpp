#pragma once
/// @file room_search.hpp
/// A way out of a pocket of free space. The MAV can end a flight at a valid
/// position whose only way out is a passage barely wider than its clearance
/// sphere: a corner it flew into to look at frontiers near the floor, whose
/// entrance narrowed as the camera saw its walls. RRT* samples the whole
/// bounds and almost never lands in such a passage, so every candidate fails
/// and the mission ends with no_reachable_candidate although a path exists.
/// The planner searches only then: an iteration without a winner from a
/// cramped start (exploration_planner.cpp).
/// A breadth-first search on a lattice around the start finds the passage
/// deterministically: it walks valid segments (the planner's own motion
/// check) until it reaches a point with room, where sampling works again.

#include <Eigen/Core>
#include <vector>

#include "semantic_exploration/core/planning/interfaces.hpp"
#include "semantic_exploration/core/planning/path_planner.hpp"

namespace semexp {

struct RoomSearchSettings {
  double room_radius_m = 0.33;    ///< a point has room when a sphere this large around it is free, m
  double search_radius_m = 1.5;   ///< lattice points farther than this from the start are not visited, m
  double step_m = 0.08;           ///< lattice spacing, m
  std::size_t max_points = 20000; ///< lattice points entered at most (bounds the cost of a search)
};

/// The way from start_W to the lattice point with room fewest lattice steps
/// away (26-connected; ties by a fixed neighbour order): start_W first, the
/// point with room last, every segment valid for `paths` (segmentValid) and
/// shortened where a longer segment is valid too. Empty if start_W is
/// invalid, already has room, search_radius_m is 0, or no point with room is
/// reachable within the search radius and max_points. A search radius below
/// one step still searches the start's 26 neighbours. is_free: the sphere
/// test of the room criterion (the planner's is_free).
std::vector<Eigen::Vector3d> findRoom(const PathPlanner& paths, const CollisionQuery& is_free,
                                      const Eigen::Vector3d& start_W, const RoomSearchSettings& settings);

/// The planning start at the end of `route_W` (findRoom's result, non-empty):
/// paths planned from it begin with the route.
PlanningStart startAfterRoute(const std::vector<Eigen::Vector3d>& route_W);

}  // namespace semexp

#pragma once
/// @file path_check.hpp
/// The last guard before a path is published: no point of it lies within the
/// clearance radius of an occupied voxel of the map the path will be flown in.
/// The path planner checks its own motions, but the map may have changed
/// between planning and publishing (a replica update arrived meanwhile), and
/// an escape out of an invalid start is checked with a smaller radius.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "semantic_exploration/core/planning/interfaces.hpp"

namespace semexp {

/// Outcome of checkPathClearance().
struct PathClearance {
  bool safe = false;
  std::string why;  ///< empty when safe; else where the path comes too close, or "empty path"
};

/// Samples every segment of `path_W` at most `step_m` apart (endpoints
/// included) and asks `not_occupied(q, radius)` at each sample. The radius is
/// clearance_radius_m, except on the first segment of an `escaped` path (a
/// way out of a start inside the clearance of an obstacle), where it is
/// mav_radius_m / 2, as the path planner checks it. An empty path is not safe;
/// a single vertex is (nothing is flown). Throws std::invalid_argument if
/// step_m or a radius is not > 0 or not_occupied is empty.
PathClearance checkPathClearance(const std::vector<Eigen::Vector3d>& path_W, bool escaped, double clearance_radius_m,
                                 double mav_radius_m, double step_m, const CollisionQuery& not_occupied);

}  // namespace semexp

#pragma once
/// @file path_planner.hpp
/// Paths from the current position to candidate positions (paper Section
/// IV-D.2, DESIGN Section 5 step 2): OMPL InformedRRTstar on a 3-D state space
/// within the bounds, a state being valid when a sphere around it is free.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "semantic_exploration/core/bounds.hpp"
#include "semantic_exploration/core/planner_config.hpp"
#include "semantic_exploration/core/planning/interfaces.hpp"

namespace semexp {

struct PlannedPath {
  enum class Status {
    kStraight,      ///< the straight segment was free; no planner run
    kExact,         ///< the planner reached the (possibly projected) goal
    kApproximate,   ///< the planner got as close as it could; the path ends there
    kStartInvalid,  ///< the start sphere is not free and no escape was possible
    kFailed,        ///< no path leaving the start
  };
  Status status = Status::kFailed;
  /// Vertices in world, m; the first is the start, the last the position
  /// actually reached (the candidate position from then on). Empty on failure.
  std::vector<Eigen::Vector3d> path_W;
  bool escaped = false;             ///< path_W[0] -> path_W[1] is an escape from an invalid start
  double distance_to_goal_m = 0.0;  ///< from the path end to the requested goal, m
  double time_s = 0.0;              ///< wall time spent on this path, s

  bool ok() const { return !path_W.empty(); }
  static const char* name(Status s);
};

/// Where planning starts from: the MAV's position, an escape point next to
/// it when its own sphere is not free (see PathPlanner), or the end of a way
/// out of a pocket (room_search.hpp).
struct PlanningStart {
  Eigen::Vector3d start_W = Eigen::Vector3d::Zero();  ///< the MAV's position, m
  Eigen::Vector3d from_W = Eigen::Vector3d::Zero();   ///< where the planner starts: start_W, the escape point or the way out's end, m
  /// Vertices every path flies before from_W, start_W first (empty when
  /// from_W = start_W): {start_W} for an escape, more for a way out of a pocket.
  std::vector<Eigen::Vector3d> lead_W;
  bool escaped = false;                               ///< from_W is an escape point from an invalid start
  bool ok = false;                                    ///< false: start invalid and no escape
};

/// The point a path to a requested goal aims for, known before any planning:
/// the requested goal clamped into the bounds and moved to the nearest valid
/// state near it, or to the first valid point on the line back to the start.
/// A path that reaches its goal ends exactly at goal_W.
struct ResolvedGoal {
  Eigen::Vector3d requested_W = Eigen::Vector3d::Zero();  ///< as asked, m
  Eigen::Vector3d goal_W = Eigen::Vector3d::Zero();       ///< where the path aims, m
  bool valid = false;      ///< goal_W is a valid state (else the planner only gets as close as it can)
  bool moved_far = false;  ///< goal_W comes from the line back to the start (then the path counts as approximate)
};

/// Seed of candidate `candidate`'s path solve in planning iteration
/// `iteration` under the planner seed `seed`: the same triple always gives
/// the same path, whichever thread plans it and in whatever order.
std::uint32_t pathSeed(std::uint32_t seed, std::uint64_t iteration, std::uint64_t candidate);

/// Plans collision-free paths for a sphere of radius R (config.mav_radius_m).
///
/// Validity: inside the bounds shrunk by R, and `is_free(p, R_c)` with
/// R_c = sqrt(C^2 + (resolution / 2)^2), C = R + clearance_margin_m: motions
/// are checked at points at most one map resolution apart, and every point
/// within C of a checked segment lies within R_c of its nearest checked
/// point, so the whole swept volume of radius C is known free, not only the
/// sampled spheres (the planner node re-checks published paths at C). The
/// margin keeps R from surfaces hiding in voxels the map holds free (glass
/// returns no depth; grazing rays carve the voxel in front of a wall).
///
/// Per goal: (1) if the straight segment is valid it is the path, no planner;
/// (2) an invalid goal (e.g. a frontier touching unknown space) is moved to
/// the nearest valid point within goal_search_radius = 2 R + 2 resolution,
/// searched on shells of 26 directions, and a goal with no valid point that
/// close to the first valid point on the line back to the start (then the
/// result counts as approximate); (3) InformedRRTstar with the path
/// length objective and a cost threshold of cost_threshold_factor times the
/// straight-line distance (so a solve stops early once near-optimal), within
/// time_budget_s (or ompl_iterations iterations, see
/// PlannerConfig::ompl_termination); approximate solutions are accepted; (4)
/// the path is simplified (vertex reduction and shortcutting, collision-checked
/// by OMPL) and re-checked densely here; a simplified path failing that check
/// is replaced by the raw solution; an exact solution, which OMPL may end
/// within 0.5 resolution of the goal, is made to end exactly at it where the
/// last segment allows.
///
/// Every random engine of a solve is seeded from the seed passed in (see
/// seeded_ompl.hpp), so with ompl_termination "iterations" a path depends only
/// on (start, goal, seed, map).
///
/// Invalid start: if `not_occupied` is given (sphere holds no occupied voxel,
/// unknown allowed), the nearest valid point within escape_radius_m whose
/// straight segment from the start keeps R/2 from occupied voxels is used as
/// an escape and planning continues from there; otherwise kStartInvalid. (R/2:
/// the MAV is already at the start; a surface seen from a new angle may have
/// grown into its sphere, and the escape moves away from it.)
///
/// planAll() plans several goals in parallel (config.planning_threads, 0 =
/// all hardware threads), each thread with its own OMPL instances. The
/// queries must be thread-safe.
class PathPlanner {
 public:
  PathPlanner(const PlannerConfig& config, const Bounds& bounds, double resolution_m, CollisionQuery is_free,
              CollisionQuery not_occupied = {}, double escape_radius_m = 1.0);

  /// Escape from an invalid start, if needed and possible.
  PlanningStart planningStart(const Eigen::Vector3d& start_W) const;
  /// Goal projection (step 2 above); needs from.ok.
  ResolvedGoal resolveGoal(const PlanningStart& from, const Eigen::Vector3d& goal_W) const;
  /// resolveGoal for several goals in parallel.
  std::vector<ResolvedGoal> resolveGoals(const PlanningStart& from, const std::vector<Eigen::Vector3d>& goals_W) const;

  /// One path from `from` to a resolved goal, OMPL seeded with `seed`.
  PlannedPath plan(const PlanningStart& from, const ResolvedGoal& goal, std::uint32_t seed) const;
  /// Several in parallel; seeds[i] for goals[i].
  std::vector<PlannedPath> planAll(const PlanningStart& from, const std::vector<ResolvedGoal>& goals,
                                    const std::vector<std::uint32_t>& seeds) const;

  /// planningStart + resolveGoal + plan in one.
  PlannedPath plan(const Eigen::Vector3d& start_W, const Eigen::Vector3d& goal_W, std::uint32_t seed = 0) const;
  /// The same for several goals in parallel, goal i seeded with pathSeed(seed, 0, i).
  std::vector<PlannedPath> planAll(const Eigen::Vector3d& start_W, const std::vector<Eigen::Vector3d>& goals_W,
                                    std::uint32_t seed = 0) const;

  /// State validity as used by the planner (bounds + inflated sphere).
  bool valid(const Eigen::Vector3d& p_W) const;
  /// Segment validity checked at points at most one resolution apart.
  bool segmentValid(const Eigen::Vector3d& a_W, const Eigen::Vector3d& b_W) const;
  /// Whole-path validity (segmentValid on every segment).
  bool pathValid(const std::vector<Eigen::Vector3d>& path_W) const;
  /// Nearest valid point within radius_m of p_W (shells of 26 directions,
  /// step = resolution); false if none.
  bool nearestValid(const Eigen::Vector3d& p_W, double radius_m, Eigen::Vector3d& out_W) const;

  double checkRadius_m() const { return check_radius_m_; }
  int threads() const;

 private:
  PlannedPath planFromValidStart(const Eigen::Vector3d& start_W, const ResolvedGoal& goal, std::uint32_t seed) const;

  PlannerConfig config_;
  Bounds bounds_;
  Bounds state_bounds_;  ///< bounds shrunk by R
  double resolution_m_;
  double check_radius_m_;
  CollisionQuery is_free_;
  CollisionQuery not_occupied_;
  double escape_radius_m_;
};

}  // namespace semexp

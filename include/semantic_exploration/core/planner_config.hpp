#pragma once
/// @file planner_config.hpp
/// Settings of the planner (paper Section IV-D).

#include <cmath>
#include <cstdint>
#include <string>

#include "semantic_exploration/core/config_error.hpp"
// The planner takes the history's masks; its settings live in their own header.
#include "semantic_exploration/core/depth_history_config.hpp"
#include "semantic_exploration/core/spherical_grid.hpp"

namespace semexp {

struct PlannerConfig {
  int n_candidates = 20;            ///< candidates sampled per iteration (Table I n)
  double p_frontier = 0.5;          ///< probability of sampling from frontiers (Table I P_fr)
  double a_ent = 0.34;              ///< weight of the entropy gain
  double a_bg = 0.33;               ///< weight of the background distance gain
  double a_obj = 0.33;              ///< weight of the object distance gain
  double v_max_mps = 1.5;           ///< maximum speed, m/s
  double omega_max_radps = 0.75;    ///< maximum yaw rate, rad/s
  double mav_radius_m = 0.125;      ///< collision sphere radius R, m
  /// Clearance kept beyond R from occupied (and, where unknown is not free,
  /// unknown) voxel boxes, m. A surface can sit inside a voxel the map
  /// carved free (grazing rays, glass that returns no depth), so R alone
  /// lets the MAV touch it.
  double clearance_margin_m = 0.04;
  int raycast_width = 36;           ///< 360-degree raycast width w
  int raycast_height = 10;          ///< raycast height h
  double time_budget_s = 0.1;       ///< OMPL time per candidate, s
  double time_limit_s = 600.0;      ///< exploration time limit (sim time), s; 0 = none
  int max_failed_iterations = 5;    ///< stop after this many iterations without a reachable candidate
  std::uint32_t seed = 1;           ///< random seed of the sampler
  double object_observed_fraction = 0.9;  ///< an object counts as observed from <= d_obj at this ObjectInfo observed_fraction, [0, 1]
  double object_standoff_factor = 0.5;    ///< object view points lie this times d_obj outside the object's bounding box
  /// View points tried around each object candidate; the one whose view (in
  /// G's best yaw window) takes in the most object gain, then the most G,
  /// becomes the candidate. 1 = one view point in a random direction.
  int object_view_samples = 8;
  double min_path_time_s = 0.1;           ///< floor of the path time in u = g / t, s (a view at the current pose stays finite)
  double cost_threshold_factor = 1.05;    ///< a solve stops once its path is within this factor of the straight-line distance
  double simplify_time_s = 0.02;          ///< time for path simplification per candidate, s
  int convergence_solutions = 5;         ///< a solve also stops once the moving average cost of this many improving solutions settles; 0 = off
  double convergence_epsilon = 0.05;      ///< ... i.e. changes by less than this fraction
  int planning_threads = 0;               ///< threads planning candidates in parallel; 0 = all hardware threads
  int stall_iterations = 20;              ///< stop ("no_progress") when the explored volume grew less than stall_volume_m3 over this many iterations; 0 = off
  double stall_volume_m3 = 0.1;           ///< see stall_iterations, m^3
  /// What ends one candidate's OMPL solve besides reaching the cost threshold
  /// or converging: "time" (time_budget_s of wall time) or "iterations"
  /// (ompl_iterations RRT* iterations, and simplification without a time
  /// limit). With "iterations" a solve depends on its inputs and seed only,
  /// so a run is reproducible whatever the machine load.
  std::string ompl_termination = "time";
  int ompl_iterations = 1000;             ///< RRT* iterations per candidate when ompl_termination is "iterations"
  /// Plan paths only until no unplanned candidate can beat the best utility
  /// found (candidates in decreasing order of the bound g / t_min); picks the
  /// same winner as planning every candidate (false).
  bool lazy_planning = true;
  /// An iteration without a winner from a cramped start (no free sphere of
  /// twice the clearance radius) is, before it counts as failed, planned
  /// again from the nearest point with room within this distance
  /// (room_search.hpp): the way out of a pocket whose passage RRT* does not
  /// sample, m; 0 = off.
  double room_search_radius_m = 1.5;

  /// Whether OMPL solves end on an iteration count (reproducible) rather than wall time.
  bool ompl_by_iterations() const { return ompl_termination == "iterations"; }

  /// Radius of the sphere that must be free along paths and at view points, m.
  double clearance_radius_m() const { return mav_radius_m + clearance_margin_m; }

  void validate(const std::string& ns = "planner/") const {
    require(n_candidates > 0, ns + "n_candidates", "must be > 0");
    require(std::isfinite(p_frontier) && p_frontier >= 0 && p_frontier <= 1, ns + "p_frontier", "must be in [0, 1]");
    require(std::isfinite(a_ent) && a_ent >= 0 && a_ent <= 1, ns + "a_ent", "must be in [0, 1]");
    require(std::isfinite(a_bg) && a_bg >= 0 && a_bg <= 1, ns + "a_bg", "must be in [0, 1]");
    require(std::isfinite(a_obj) && a_obj >= 0 && a_obj <= 1, ns + "a_obj", "must be in [0, 1]");
    require(std::abs(a_ent + a_bg + a_obj - 1.0) < 1e-3, ns + "a_ent",
            "a_ent + a_bg + a_obj must sum to 1 (they sum to " + std::to_string(a_ent + a_bg + a_obj) + ")");
    require(std::isfinite(v_max_mps) && v_max_mps > 0, ns + "v_max_mps", "must be > 0 m/s");
    require(std::isfinite(omega_max_radps) && omega_max_radps > 0, ns + "omega_max_radps", "must be > 0 rad/s");
    require(std::isfinite(mav_radius_m) && mav_radius_m > 0, ns + "mav_radius_m", "must be > 0 m");
    require(std::isfinite(clearance_margin_m) && clearance_margin_m >= 0, ns + "clearance_margin_m", "must be >= 0 m");
    require(raycast_width > 0, ns + "raycast_width", "must be > 0");
    require(raycast_height > 0, ns + "raycast_height", "must be > 0");
    // One gain request per iteration: n_candidates images of raycast_width x raycast_height.
    require(SphericalGrid::checkRequest(n_candidates, raycast_width, raycast_height).empty(), ns + "raycast_width",
            SphericalGrid::checkRequest(n_candidates, raycast_width, raycast_height) + " (with n_candidates)");
    require(std::isfinite(time_budget_s) && time_budget_s > 0, ns + "time_budget_s", "must be > 0 s");
    require(std::isfinite(time_limit_s) && time_limit_s >= 0, ns + "time_limit_s", "must be >= 0 s");
    require(max_failed_iterations > 0, ns + "max_failed_iterations", "must be > 0");
    require(std::isfinite(object_observed_fraction) && object_observed_fraction >= 0 && object_observed_fraction <= 1,
            ns + "object_observed_fraction", "must be in [0, 1]");
    require(std::isfinite(object_standoff_factor) && object_standoff_factor >= 0, ns + "object_standoff_factor",
            "must be >= 0");
    require(object_view_samples >= 1 && object_view_samples <= 64, ns + "object_view_samples", "must be in [1, 64]");
    // The views of every object candidate are evaluated in one gain request (no object is sampled at P_fr = 1).
    require(p_frontier >= 1.0 ||
                SphericalGrid::checkRequest(static_cast<long>(n_candidates) * object_view_samples, raycast_width,
                                        raycast_height)
                .empty(),
            ns + "object_view_samples",
            SphericalGrid::checkRequest(static_cast<long>(n_candidates) * object_view_samples, raycast_width,
                                        raycast_height) +
                " (n_candidates x object_view_samples views)");
    require(std::isfinite(min_path_time_s) && min_path_time_s > 0, ns + "min_path_time_s", "must be > 0 s");
    require(std::isfinite(cost_threshold_factor) && cost_threshold_factor >= 1, ns + "cost_threshold_factor",
            "must be >= 1");
    require(std::isfinite(simplify_time_s) && simplify_time_s >= 0, ns + "simplify_time_s", "must be >= 0 s");
    require(convergence_solutions >= 0, ns + "convergence_solutions", "must be >= 0 (0 = off)");
    require(std::isfinite(convergence_epsilon) && convergence_epsilon > 0 && convergence_epsilon < 1,
            ns + "convergence_epsilon", "must be in (0, 1)");
    require(stall_iterations >= 0, ns + "stall_iterations", "must be >= 0 (0 = off)");
    require(std::isfinite(stall_volume_m3) && stall_volume_m3 >= 0, ns + "stall_volume_m3", "must be >= 0 m^3");
    require(planning_threads >= 0, ns + "planning_threads", "must be >= 0 (0 = all hardware threads)");
    require(ompl_termination == "time" || ompl_termination == "iterations", ns + "ompl_termination",
            "must be \"time\" or \"iterations\" (is \"" + ompl_termination + "\")");
    require(ompl_iterations > 0, ns + "ompl_iterations", "must be > 0");
    require(std::isfinite(room_search_radius_m) && room_search_radius_m >= 0 && room_search_radius_m <= 5,
            ns + "room_search_radius_m", "must be in [0, 5] m (0 = off)");
  }
};

}  // namespace semexp

#pragma once
/// @file exploration_planner.hpp
/// One next-best-view planning iteration (paper Section IV-D, DESIGN Section
/// 5): sample candidates, evaluate their gains at their view positions in one
/// batched call, plan paths to them in parallel (lazily: only until no other
/// candidate can win, see PlannerConfig::lazy_planning), choose the highest
/// utility, give the winner's path vertices their yaw, and decide when
/// exploration is over: "explored" (no
/// frontier left, every object observed from <= d_obj), "time_limit",
/// "no_progress" (explored volume stalled, see PlannerConfig::stall_*) or
/// "no_reachable_candidate" (max_failed_iterations in a row without a
/// reachable candidate of positive utility).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "semantic_exploration/core/bounds.hpp"
#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/exploration_config.hpp"
#include "semantic_exploration/core/planner_config.hpp"
#include "semantic_exploration/core/planning/candidate_evaluation.hpp"
#include "semantic_exploration/core/planning/interfaces.hpp"
#include "semantic_exploration/core/planning/frontier_retirement.hpp"
#include "semantic_exploration/core/planning/object_retirement.hpp"
#include "semantic_exploration/core/planning/path_planner.hpp"
#include "semantic_exploration/core/planning/termination.hpp"
#include "semantic_exploration/core/planning/sampler.hpp"

namespace semexp {

/// The state of the world seen by one iteration.
struct ExplorationInputs {
  Eigen::Vector3d position_W = Eigen::Vector3d::Zero();  ///< current MAV position, m
  double yaw_rad = 0.0;                                  ///< current MAV yaw, rad
  double elapsed_s = 0.0;                                ///< time since exploration started, s
  std::vector<Eigen::Vector3d> frontiers_W;              ///< frontier voxel centres, m
  std::vector<ObjectSummary> objects;
  /// Share of the observed background surface seen from <= d_bg, [0, 1]
  /// (OccupancyMap::surfaceObservedWithin); negative if unknown, which keeps
  /// the background condition of "explored" from holding where it is pursued.
  double background_observed_share = -1.0;
  /// Explored (free + occupied) volume of the background map, m^3; negative
  /// if unknown. Feeds the "no_progress" stop (termination.hpp).
  double explored_volume_m3 = -1.0;
};

/// The map behind the planner.
struct ExplorationProviders {
  CollisionQuery is_free;       ///< required
  CollisionQuery not_occupied;  ///< optional: enables escapes from an invalid start
  /// Optional: the lines of sight of frontier retirement asked at once
  /// (same answers as not_occupied point by point, fewer map look-ups).
  LineQuery line_not_occupied;
  GainProvider gains;           ///< required
  HistoryProvider history;      ///< optional: no history = all directions valid
};

struct EvaluatedCandidate {
  CandidateSample sample;
  PlannedPath plan;
  Eigen::Vector3d position_W = Eigen::Vector3d::Zero();  ///< path end (the view position), else the sample
  bool reachable = false;  ///< a collision-free path was found
  double yaw_rad = 0.0;    ///< best yaw from the sliding window
  double gain_entropy = 0.0, gain_bg = 0.0, gain_obj = 0.0;  ///< window means of the three images
  double gain = 0.0;         ///< window mean of the combined image G (Eq. 2)
  double path_time_s = 0.0;  ///< estimated flight time, s
  double utility = 0.0;      ///< gain / path time, 1/s (capped at utility_bound); 0 if not planned
  /// Upper bound of the utility before any path is planned: the gain at the
  /// view position over the least time any path there takes (straight-line
  /// length / v_max, yaw change / omega_max, min_path_time_s), 1/s.
  double utility_bound = 0.0;
  Eigen::Vector3d view_W = Eigen::Vector3d::Zero();  ///< where the path aims and the bound's gain was taken, m
  bool planned = false;  ///< a path was planned (lazy planning skips candidates that cannot win)
};

struct IterationResult {
  std::vector<EvaluatedCandidate> candidates;
  int winner = -1;                       ///< index into candidates, -1 if none
  std::vector<Eigen::Vector3d> path_W;   ///< the winner's path (first vertex = current position)
  std::vector<double> path_yaw_rad;      ///< yaw per path vertex
  GainSet winner_gains;                  ///< the winner's three gain images
  GainImage winner_combined;             ///< and G
  bool finished = false;                 ///< exploration is over; see termination_reason
  std::string termination_reason;        ///< "explored", "time_limit", "no_progress", "no_reachable_candidate" or ""
  bool provider_error = false;           ///< a gain/history provider failed (e.g. a service timed out)
  std::string message;                   ///< what happened, human readable
  int candidates_reachable = 0;          ///< of the planned candidates
  int candidates_planned = 0;            ///< candidates a path was planned for
  std::size_t object_views = 0;          ///< view points around the object candidates whose gains were computed
  /// The termination check of this iteration: which conditions of "explored" hold.
  TerminationDecision termination;
  std::size_t active_frontiers = 0;              ///< frontier voxels still to be observed
  std::vector<Eigen::Vector3d> retired_frontiers_W;  ///< frontier voxels no reachable view can observe
  std::size_t retired_clusters_geometry = 0, retired_clusters_evidence = 0, frontier_clusters = 0;
  /// Objects retired by evidence (object_retirement.hpp): not sampled, not holding "explored".
  std::vector<std::uint32_t> retired_object_ids;
  std::string object_retirement_events;  ///< objects retired or back this iteration, for the log ("" if none)
  /// The way out of a pocket this iteration planned from, for the log ("" if none; room_search.hpp).
  std::string way_out;
  double sampling_s = 0.0, path_planning_s = 0.0, gains_s = 0.0, yaw_s = 0.0, total_s = 0.0;  ///< wall times
  /// Wall time of frontier retirement: judging this iteration's frontiers and recording the winner's views, s.
  double retirement_s = 0.0;
};

class ExplorationPlanner {
 public:
  /// map_resolution_m: the background map's voxel edge (motion checks).
  ExplorationPlanner(const PlannerConfig& planner, const ExplorationConfig& exploration, const Bounds& bounds,
                     const PinholeCamera& camera, double map_resolution_m,
                     const TerminationConfig& termination = TerminationConfig(),
                     const FrontierRetirementConfig& retirement = FrontierRetirementConfig(),
                     const ObjectRetirementConfig& object_retirement = ObjectRetirementConfig());

  /// Runs one iteration. Never throws for provider failures (they are
  /// reported in the result and do not count as failed iterations).
  IterationResult plan(const ExplorationInputs& in, const ExplorationProviders& providers);

  /// The winner of the last plan() was not flown (dropped by a final check,
  /// rejected by the executor): its views are not evidence for retirement.
  void discardViews() {
    retirement_.discardViews();
    object_retirement_.discardView();
  }

  /// Consecutive iterations without a reachable candidate of positive utility.
  int failedIterations() const { return failed_iterations_; }
  const PlannerConfig& config() const { return planner_; }
  int windowColumns() const { return window_columns_; }

 private:
  bool fail(IterationResult& r, const std::string& why);
  /// An iteration without a winner in which no candidate has a gain at its
  /// view position: records a view of each frontier candidate's cluster for
  /// frontier retirement (frontier_retirement.hpp), so that K such iterations
  /// can retire what no view can see before max_failed_iterations end the mission.
  void recordUnseeableFrontiers(IterationResult& r, const CollisionQuery& not_occupied, const LineQuery& line);
  /// Moves each object sample to the view point of its object's ring
  /// (CandidateSampler::objectViewRing) whose best yaw window (of G, as the
  /// candidate will fly it) holds the most object gain, ties broken by G: one
  /// batched gain call for all of them. The utility that ranks candidates is
  /// untouched. False on a provider failure (reported in r).
  bool chooseObjectViews(std::vector<CandidateSample>& samples, const std::vector<ObjectSummary>& objects,
                         const ExplorationProviders& prov, IterationResult& r);

  PlannerConfig planner_;
  ExplorationConfig exploration_;
  Bounds bounds_;
  PinholeCamera camera_;
  double map_resolution_m_;
  CandidateSampler sampler_;
  int window_columns_;
  int failed_iterations_ = 0;
  TerminationCheck termination_;
  FrontierRetirement retirement_;
  ObjectRetirement object_retirement_;
  std::uint64_t sampling_iterations_ = 0;   ///< iterations that sampled candidates; seeds their paths
};

}  // namespace semexp

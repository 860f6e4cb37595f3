#pragma once
/// @file termination.hpp
/// When the exploration is over (paper Section IV-D: "The exploration stops
/// when F = {} and all of the background and objects have been observed from
/// a distance at least d_bg and d_obj"), measured live, and the stops that
/// keep a run from going on forever: the time limit and "no_progress".
///
/// The three conditions of "explored", each measured every iteration:
///  - frontiers: at most max_active_frontiers active frontier voxels (frontiers
///    no reachable view can observe are retired, see frontier_retirement.hpp);
///  - background: the share of the observed background surface (occupied
///    voxels) seen from <= d_bg is at least background_observed_share;
///  - objects: every object's share seen from <= d_obj is at least
///    PlannerConfig::object_observed_fraction, or the object is retired by
///    evidence (object_retirement.hpp: flights aimed at it did not move it).
/// A condition is only required where the planner pursues it: background
/// with a_bg > 0, objects with a_obj > 0. The paper's classic baseline
/// (a_bg = a_obj = 0) thus stops on frontiers alone, by its own rule.
///
/// "no_progress": nothing the planner pursues improved over the last
/// stall_iterations iterations: the explored volume grew less than
/// stall_volume_m3, the active frontier voxels did not become fewer (they
/// do as frontiers are observed or retired) and no frontier cluster was
/// retired by evidence for the first time (flights past noisy surfaces add
/// frontier voxels that can hide the retirements from the count; a cluster
/// counts once, so retire-and-return cycles cannot hold the run open), and
/// (where pursued) neither
/// the background share nor any object's share grew by stall_share, and no
/// object appeared.

#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "semantic_exploration/core/config_error.hpp"
#include "semantic_exploration/core/planner_config.hpp"
#include "semantic_exploration/core/planning/interfaces.hpp"

namespace semexp {

struct TerminationConfig {
  /// "explored" needs at most this many active frontier voxels. A few
  /// isolated voxels flicker between frontier and not with sensor noise and
  /// hold no space worth a flight; 0 is the paper's F = {}.
  int max_active_frontiers = 0;
  /// "explored" needs at least this share of the observed background surface
  /// seen from <= d_bg, [0, 1]. The paper asks for all of it; 0.9 leaves room
  /// for surfaces seen only at grazing angles, but no measured run has reached
  /// it yet (docs/BENCHMARKS.md "Termination").
  double background_observed_share = 0.9;
  /// A share (background or an object's) growing by at least this much over
  /// the stall window counts as progress, [0, 1].
  double stall_share = 0.01;

  void validate(const std::string& ns = "termination/") const {
    require(max_active_frontiers >= 0, ns + "max_active_frontiers", "must be >= 0");
    require(std::isfinite(background_observed_share) && background_observed_share >= 0 &&
                background_observed_share <= 1,
            ns + "background_observed_share", "must be in [0, 1]");
    require(std::isfinite(stall_share) && stall_share > 0 && stall_share <= 1, ns + "stall_share",
            "must be in (0, 1]");
  }
};

/// What one iteration knows about the state of the exploration.
struct TerminationInputs {
  double elapsed_s = 0.0;              ///< since the exploration started, s
  std::size_t active_frontiers = 0;    ///< frontier voxels not retired
  double background_share = -1.0;      ///< background surface share seen from <= d_bg, [0, 1]; < 0 unknown
  std::vector<ObjectSummary> objects;  ///< observed_fraction = share seen from <= d_obj
  /// Objects retired by evidence (ObjectRetirement): below the share, yet not holding "explored".
  std::vector<std::uint32_t> retired_object_ids;
  double explored_volume_m3 = -1.0;    ///< < 0 unknown
  /// Distinct frontier clusters retired by evidence so far, each counted
  /// once (FrontierRetirement::evidenceRetirements).
  std::size_t frontier_clusters_retired = 0;
};

/// The outcome of one check.
struct TerminationDecision {
  bool finished = false;
  std::string reason;          ///< "explored", "time_limit", "no_progress" or "" while going on
  std::string message;         ///< what held, with the measured figures
  bool frontiers_done = false;
  bool background_done = false;  ///< also true where the background is not pursued
  bool objects_done = false;     ///< also true where objects are not pursued
  std::size_t objects_retired = 0;  ///< objects below the share that count as done because they are retired
  /// The condition of "explored" that became true last ("frontiers",
  /// "background" or "objects"; "" until all hold).
  std::string last_condition;
};

class TerminationCheck {
 public:
  /// Uses planner.time_limit_s, stall_iterations, stall_volume_m3,
  /// object_observed_fraction and the weights a_bg, a_obj (which conditions
  /// are pursued). Throws ConfigError on invalid settings.
  TerminationCheck(const TerminationConfig& config, const PlannerConfig& planner);

  /// Checks once per iteration (the stall window counts calls).
  TerminationDecision check(const TerminationInputs& in);

  bool pursuesBackground() const { return planner_.a_bg > 0; }
  bool pursuesObjects() const { return planner_.a_obj > 0; }
  const TerminationConfig& config() const { return config_; }

 private:
  struct Sample {
    double volume_m3;
    std::size_t active_frontiers;
    std::size_t frontier_clusters_retired;
    double background_share;
    std::map<std::uint32_t, double> object_shares;
  };
  /// True if anything pursued improved between `old` and `now`; `what` says what did not.
  bool progressed(const Sample& old, const Sample& now, std::string& what) const;

  TerminationConfig config_;
  PlannerConfig planner_;
  std::deque<Sample> history_;  ///< the last stall_iterations + 1 samples
  /// Checks since each condition last became true (-1 while false).
  std::map<std::string, long> held_since_;
  long checks_ = 0;
};

}  // namespace semexp

#pragma once
/// @file object_retirement.hpp
/// Objects whose remaining surface no flight aimed at them brings within
/// d_obj stop holding the exploration open (paper Section IV-D asks for every
/// object observed from <= d_obj; a chair's seat underside, or its side
/// against a wall, can stay out of a level camera's reach).
///
/// The evidence rule, like FrontierRetirement's for frontier clusters: an
/// object below PlannerConfig::object_observed_fraction is retired after
/// max_failed_views flights that were meant to observe it (the winner was an
/// object candidate of it) and after which its share seen from <= d_obj did
/// not move by at least min_share_change. A flight that moves the share
/// clears the count: up is surface newly seen from close by, down is new
/// surface seen from afar (there is more of it to observe). A retired object
/// comes back once its share moves by min_share_change from its value at
/// retirement, either way, for the same reasons, or reaches the done share.
/// Retired objects are not sampled and do not hold "explored"
/// (termination.hpp). Their unobserved voxels still add object gain to other
/// candidates' views (the object map's gain service does not know of them).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "semantic_exploration/core/config_error.hpp"
#include "semantic_exploration/core/planning/interfaces.hpp"

namespace semexp {

struct ObjectRetirementConfig {
  bool enabled = true;            ///< false: no object is ever retired
  int max_failed_views = 3;       ///< flights aimed at an object that did not move its share before it is retired (K)
  double min_share_change = 0.01; ///< a flight moved an object's share when it changed by this much either way, (0, 1]

  void validate(const std::string& ns = "object_retirement/") const {
    require(max_failed_views > 0, ns + "max_failed_views", "must be > 0");
    require(std::isfinite(min_share_change) && min_share_change > 0 && min_share_change <= 1,
            ns + "min_share_change", "must be in (0, 1]");
  }
};

/// A change of an object's retirement, as update() made it.
struct ObjectRetirementChange {
  std::uint32_t id = 0;
  bool retired = false;  ///< true: retired now; false: back (its share moved or reached the done share)
  double share = 0.0;    ///< its share seen from <= d_obj at the change, [0, 1]
};

class ObjectRetirement {
 public:
  /// done_share: PlannerConfig::object_observed_fraction (objects at or
  /// above it need no view and are never retired). Throws ConfigError on an
  /// invalid config or a done_share outside [0, 1].
  ObjectRetirement(const ObjectRetirementConfig& config, double done_share);

  /// Judges the flight recorded since the last call (recordView) against the
  /// objects' shares now, and brings back retired objects whose share moved.
  /// Objects no longer in the map are forgotten. Returns the objects that
  /// came back (in the order of `objects`), then the one the judged flight
  /// retired, if any.
  std::vector<ObjectRetirementChange> update(const std::vector<ObjectSummary>& objects);
  /// The published path was chosen to observe object `id`, whose share is
  /// share_now; judged at the next update(). Only the last call before an
  /// update() counts (one flight per iteration).
  void recordView(std::uint32_t id, double share_now);
  /// The view recorded last was not flown (the path was dropped or rejected): not judged.
  void discardView() { pending_ = false; }

  bool retired(std::uint32_t id) const;
  /// Ids of the retired objects, ascending.
  std::vector<std::uint32_t> retiredIds() const;
  /// `objects` without the retired ones.
  std::vector<ObjectSummary> active(const std::vector<ObjectSummary>& objects) const;

  const ObjectRetirementConfig& config() const { return config_; }

 private:
  struct State {
    int failed_views = 0;
    bool retired = false;
    double share_at_retirement = 0.0;
  };
  ObjectRetirementConfig config_;
  double done_share_;
  std::map<std::uint32_t, State> state_;
  bool pending_ = false;  ///< a flight aimed at pending_id_ awaits judgement
  std::uint32_t pending_id_ = 0;
  double pending_share_ = 0.0;
};

}  // namespace semexp

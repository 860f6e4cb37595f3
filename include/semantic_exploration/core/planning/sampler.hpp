#pragma once
/// @file sampler.hpp
/// Candidate next positions (paper Section IV-D.1, DESIGN Section 5 step 1).

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <vector>

#include "semantic_exploration/core/bounds.hpp"
#include "semantic_exploration/core/exploration_config.hpp"
#include "semantic_exploration/core/planner_config.hpp"
#include "semantic_exploration/core/planning/interfaces.hpp"

namespace semexp {

/// Where a candidate came from (values as CandidateView.msg's SOURCE_*).
enum class CandidateSource : std::uint8_t { kFrontier = 0, kObject = 1, kFreeSpace = 2 };

/// "frontier", "object" or "free_space".
const char* candidateSourceName(CandidateSource s);

struct CandidateSample {
  Eigen::Vector3d position_W = Eigen::Vector3d::Zero();  ///< sampled position, m
  CandidateSource source = CandidateSource::kFrontier;
  std::uint32_t object_id = 0;  ///< object the sample was taken near (kObject), else 0
};

/// Samples up to n candidates without replacement: each draw takes a frontier
/// with probability P_fr, else an object not yet observed from <= d_obj. A
/// source with zero probability is never used; when the other source is
/// exhausted the remaining one is drawn from until n or nothing is left.
///
/// A frontier candidate is the frontier voxel's centre itself (the path
/// planner then gets as close as the free space allows). An object candidate
/// is a view point beside the object: from its centroid along a random
/// horizontal direction to where that ray leaves the bounding box, plus a
/// standoff of object_standoff_factor * d_obj, at a drawn camera height (see
/// objectViewPoint), so that the surface facing the view point is seen from
/// about half d_obj. Up to 8 directions (45 degrees apart, from a random
/// start) are tried for one whose sphere of radius R is free; if none is, the
/// first is kept and the planner reaches as close to it as it can. With
/// object_view_samples > 1 the planner replaces this point by the best of
/// objectViewRing's. Positions are clamped into the bounds shrunk by R. The
/// random engine is seeded once, so a run is reproducible given the same
/// inputs.
class CandidateSampler {
 public:
  CandidateSampler(const PlannerConfig& planner, const ExplorationConfig& exploration, const Bounds& bounds);

  /// is_free may be empty (then object view points are not checked).
  std::vector<CandidateSample> sample(const std::vector<Eigen::Vector3d>& frontiers_W,
                                      const std::vector<ObjectSummary>& objects, const CollisionQuery& is_free);

  /// Up to n view points drawn uniformly in the bounds shrunk by R whose
  /// sphere of the clearance radius is free (at most 20 n draws), for the
  /// background once no frontier or object is left to sample.
  std::vector<CandidateSample> sampleFreeSpace(const CollisionQuery& is_free);

  /// True if the object still needs a closer observation.
  bool needsObservation(const ObjectSummary& object) const {
    return object.observed_fraction < planner_.object_observed_fraction;
  }

  /// The view point next to `object` along horizontal direction yaw_rad, at the centroid's height.
  Eigen::Vector3d objectViewPoint(const ObjectSummary& object, double yaw_rad) const;
  /// The same at camera height z_W, m. Object candidates draw z_W uniformly
  /// from two clearance radii above the box bottom (0.33 m by default; or the
  /// centroid, if lower) to the box top: a level camera (49 deg vertical
  /// field of view) sees a seat's top only from above it and the legs below
  /// it only from low down. With cameras from 0.45 m up, 73-94% of the
  /// default house's chairs' observable surface can be seen from <= d_obj;
  /// from 0.30 m up, 96-100% (docs/BENCHMARKS.md "Termination").
  Eigen::Vector3d objectViewPoint(const ObjectSummary& object, double yaw_rad, double z_W) const;

  /// Up to planner.object_view_samples view points around `object`: the
  /// objectViewPoint of evenly spaced directions (a random start, 2 pi /
  /// object_view_samples apart), each at its own height drawn as for
  /// sample(); only those whose sphere of the clearance radius is free (all,
  /// if is_free is empty). The planner keeps the one whose view takes in the
  /// most object gain (ExplorationPlanner::chooseObjectViews): which side of
  /// an object still needs a close view is known to the gain images, not to
  /// the object's summary.
  std::vector<Eigen::Vector3d> objectViewRing(const ObjectSummary& object, const CollisionQuery& is_free);

 private:
  /// A camera height for a view of `object`, m (see objectViewPoint).
  double drawViewHeight(const ObjectSummary& object);

  Eigen::Vector3d clampToBounds(const Eigen::Vector3d& p_W) const;

  PlannerConfig planner_;
  ExplorationConfig exploration_;
  Bounds bounds_;
  std::mt19937 rng_;
};

}  // namespace semexp

#pragma once
// OMPL pieces whose random engines are seeded per instance, so that one
// path solve depends only on its own seed and not on how many OMPL random
// engines other threads created before it. (ompl::RNG::setSeed is global: it
// fixes the first of a sequence of seeds handed out in construction order,
// which differs with thread scheduling.)
//
// A solve draws from three engines: RRT*'s goal bias, the informed sampler
// and the path simplifier. OMPL's own direct informed sampler for path length
// keeps its engine private, so SeededPathLengthObjective hands RRT* an
// informed sampler of this file instead (same distribution: uniform over the
// prolate spheroid of states whose start + goal distance sum is within the
// current best cost, intersected with the state bounds). The nearest-neighbour
// structure's random pivots change its layout, not its (exact) answers.
//
// Private to the planning core (not installed).

#include <cstdint>
#include <memory>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/planners/rrt/InformedRRTstar.h>
#include <ompl/util/RandomNumbers.h>

namespace semexp {
namespace ompl_seeded {

/// A well-mixed 32-bit seed from a base seed and a stream number
/// (splitmix64 finaliser), so that nearby inputs give unrelated engines.
std::uint32_t mix(std::uint64_t seed, std::uint64_t stream);

/// InformedRRTstar whose goal-bias engine is seeded.
class InformedRRTstar : public ompl::geometric::InformedRRTstar {
 public:
  InformedRRTstar(const ompl::base::SpaceInformationPtr& si, std::uint32_t seed)
      : ompl::geometric::InformedRRTstar(si) {
    rng_.setLocalSeed(seed);
  }
};

/// PathSimplifier whose engine (random vertex pairs and shortcuts) is seeded.
class PathSimplifier : public ompl::geometric::PathSimplifier {
 public:
  PathSimplifier(const ompl::base::SpaceInformationPtr& si, std::uint32_t seed)
      : ompl::geometric::PathSimplifier(si) {
    rng_.setLocalSeed(seed);
  }
};

/// Path length objective whose informed sampler is an EllipsoidSampler with
/// the given seed. Only for 3-D RealVectorStateSpace problems with one start
/// and a GoalState.
class PathLengthObjective : public ompl::base::PathLengthOptimizationObjective {
 public:
  PathLengthObjective(const ompl::base::SpaceInformationPtr& si, std::uint32_t seed)
      : ompl::base::PathLengthOptimizationObjective(si), seed_(seed) {}
  ompl::base::InformedSamplerPtr allocInformedStateSampler(const ompl::base::ProblemDefinitionPtr& pdef,
                                                           unsigned int max_calls) const override;

 private:
  std::uint32_t seed_;
};

/// Uniform samples of the informed set of a 3-D path-length problem: the
/// states x in the bounds with |x - start| + |x - goal| <= c for the current
/// best cost c (the whole bounds while c is infinite). Draws in the spheroid
/// and rejects what leaves the bounds when the spheroid is the smaller set,
/// otherwise draws in the bounds and rejects what leaves the spheroid; at most
/// numIters_ draws per sample.
class EllipsoidSampler : public ompl::base::InformedSampler {
 public:
  EllipsoidSampler(const ompl::base::ProblemDefinitionPtr& pdef, unsigned int max_calls, std::uint32_t seed);

  bool sampleUniform(ompl::base::State* state, const ompl::base::Cost& max_cost) override;
  bool sampleUniform(ompl::base::State* state, const ompl::base::Cost& min_cost,
                     const ompl::base::Cost& max_cost) override;
  bool hasInformedMeasure() const override { return true; }
  double getInformedMeasure(const ompl::base::Cost& cost) const override;
  ompl::base::Cost heuristicSolnCost(const ompl::base::State* state) const override;

 private:
  double spheroidVolume(double cost) const;
  void write(const Eigen::Vector3d& p, ompl::base::State* state) const;

  ompl::RNG rng_;
  Eigen::Vector3d start_, goal_, lo_, hi_;
  Eigen::Matrix3d axes_;  ///< columns: unit focal axis and two unit normals to it
  double focal_distance_m_ = 0.0;
};

}  // namespace ompl_seeded
}  // namespace semexp

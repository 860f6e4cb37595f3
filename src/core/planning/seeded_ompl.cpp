#include "seeded_ompl.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/goals/GoalState.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>

namespace ob = ompl::base;

namespace semexp {
namespace ompl_seeded {

namespace {

Eigen::Vector3d toEigen(const ob::State* s) {
  const auto* v = s->as<ob::RealVectorStateSpace::StateType>();
  return {v->values[0], v->values[1], v->values[2]};
}

}  // namespace

std::uint32_t mix(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<std::uint32_t>(z ^ (z >> 32));
}

ob::InformedSamplerPtr PathLengthObjective::allocInformedStateSampler(const ob::ProblemDefinitionPtr& pdef,
                                                                      unsigned int max_calls) const {
  return std::make_shared<EllipsoidSampler>(pdef, max_calls, seed_);
}

EllipsoidSampler::EllipsoidSampler(const ob::ProblemDefinitionPtr& pdef, unsigned int max_calls,
                                   std::uint32_t seed)
    : ob::InformedSampler(pdef, max_calls), rng_(seed) {
  const auto* space = space_->as<ob::RealVectorStateSpace>();
  const auto* goal = dynamic_cast<const ob::GoalState*>(pdef->getGoal().get());
  if (space->getDimension() != 3 || pdef->getStartStateCount() != 1 || goal == nullptr)
    throw std::invalid_argument("EllipsoidSampler: needs a 3-D space, one start and a goal state");
  start_ = toEigen(pdef->getStartState(0));
  goal_ = toEigen(goal->getState());
  const ob::RealVectorBounds& b = space->getBounds();
  for (int i = 0; i < 3; ++i) {
    lo_[i] = b.low[static_cast<std::size_t>(i)];
    hi_[i] = b.high[static_cast<std::size_t>(i)];
  }
  focal_distance_m_ = (goal_ - start_).norm();
  // Focal axis, then any two unit vectors completing a right-handed basis.
  const Eigen::Vector3d e1 =
      focal_distance_m_ > 0 ? Eigen::Vector3d((goal_ - start_) / focal_distance_m_) : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d helper = std::abs(e1.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d e2 = e1.cross(helper).normalized();
  axes_.col(0) = e1;
  axes_.col(1) = e2;
  axes_.col(2) = e1.cross(e2);
}

double EllipsoidSampler::spheroidVolume(double cost) const {
  // Semi-axes c / 2 along the foci and sqrt(c^2 - d^2) / 2 across.
  if (!(cost > focal_distance_m_)) return 0.0;
  const double a = 0.5 * cost, b2 = 0.25 * (cost * cost - focal_distance_m_ * focal_distance_m_);
  return 4.0 / 3.0 * M_PI * a * b2;
}

double EllipsoidSampler::getInformedMeasure(const ob::Cost& cost) const {
  const double box = (hi_ - lo_).prod();
  if (!opt_->isFinite(cost)) return box;
  return std::min(box, spheroidVolume(cost.value()));
}

ob::Cost EllipsoidSampler::heuristicSolnCost(const ob::State* state) const {
  const Eigen::Vector3d p = toEigen(state);
  return ob::Cost((p - start_).norm() + (p - goal_).norm());
}

void EllipsoidSampler::write(const Eigen::Vector3d& p, ob::State* state) const {
  auto* v = state->as<ob::RealVectorStateSpace::StateType>();
  for (int i = 0; i < 3; ++i) v->values[i] = p[i];
}

bool EllipsoidSampler::sampleUniform(ob::State* state, const ob::Cost& max_cost) {
  const auto in_box = [this]() {
    return Eigen::Vector3d(rng_.uniformReal(lo_.x(), hi_.x()), rng_.uniformReal(lo_.y(), hi_.y()),
                           rng_.uniformReal(lo_.z(), hi_.z()));
  };
  if (!opt_->isFinite(max_cost)) {
    write(in_box(), state);
    return true;
  }
  const double c = max_cost.value();
  if (!(c > focal_distance_m_)) return false;  // no state is better than the straight line
  const bool from_spheroid = spheroidVolume(c) < (hi_ - lo_).prod();
  const double a = 0.5 * c, b = 0.5 * std::sqrt(c * c - focal_distance_m_ * focal_distance_m_);
  const Eigen::Vector3d centre = 0.5 * (start_ + goal_);
  for (unsigned int k = 0; k < numIters_; ++k) {
    Eigen::Vector3d p;
    if (from_spheroid) {
      Eigen::Vector3d u;  // uniform in the unit ball, by rejection from the cube
      do {
        u = Eigen::Vector3d(rng_.uniformReal(-1.0, 1.0), rng_.uniformReal(-1.0, 1.0), rng_.uniformReal(-1.0, 1.0));
      } while (u.squaredNorm() > 1.0);
      p = centre + axes_ * Eigen::Vector3d(a * u.x(), b * u.y(), b * u.z());
      if ((p.array() < lo_.array()).any() || (p.array() > hi_.array()).any()) continue;
    } else {
      p = in_box();
      if ((p - start_).norm() + (p - goal_).norm() > c) continue;
    }
    write(p, state);
    return true;
  }
  return false;
}

bool EllipsoidSampler::sampleUniform(ob::State* state, const ob::Cost& min_cost, const ob::Cost& max_cost) {
  for (unsigned int k = 0; k < numIters_; ++k) {
    if (!sampleUniform(state, max_cost)) return false;
    if (!opt_->isCostBetterThan(heuristicSolnCost(state), min_cost)) return true;
  }
  return false;
}

}  // namespace ompl_seeded
}  // namespace semexp

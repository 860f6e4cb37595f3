#include "semantic_exploration/core/planning/path_planner.hpp"

#include "semantic_exploration/core/parallel_for.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>

#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/base/terminationconditions/CostConvergenceTerminationCondition.h>
#include <ompl/base/terminationconditions/IterationTerminationCondition.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/util/Console.h>

#include "seeded_ompl.hpp"

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace semexp {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

Eigen::Vector3d toEigen(const ob::State* s) {
  const auto* v = s->as<ob::RealVectorStateSpace::StateType>();
  return {v->values[0], v->values[1], v->values[2]};
}

// The 26 unit directions of the 3x3x3 neighbourhood, for shell searches.
const std::vector<Eigen::Vector3d>& shellDirections() {
  static const std::vector<Eigen::Vector3d> dirs = [] {
    std::vector<Eigen::Vector3d> d;
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z)
          if (x || y || z) d.push_back(Eigen::Vector3d(x, y, z).normalized());
    return d;
  }();
  return dirs;
}

}  // namespace

const char* PlannedPath::name(Status s) {
  switch (s) {
    case Status::kStraight: return "straight";
    case Status::kExact: return "exact";
    case Status::kApproximate: return "approximate";
    case Status::kStartInvalid: return "start_invalid";
    case Status::kFailed: return "failed";
  }
  return "?";
}

PathPlanner::PathPlanner(const PlannerConfig& config, const Bounds& bounds, double resolution_m,
                         CollisionQuery is_free, CollisionQuery not_occupied, double escape_radius_m)
    : config_(config),
      bounds_(bounds),
      resolution_m_(resolution_m),
      is_free_(std::move(is_free)),
      not_occupied_(std::move(not_occupied)),
      escape_radius_m_(escape_radius_m) {
  config_.validate();
  bounds_.validate();
  if (!(std::isfinite(resolution_m_) && resolution_m_ > 0))
    throw std::invalid_argument("PathPlanner: resolution_m must be > 0");
  if (!is_free_) throw std::invalid_argument("PathPlanner: is_free query missing");
  const double clearance_m = config_.clearance_radius_m();
  check_radius_m_ = std::sqrt(clearance_m * clearance_m + 0.25 * resolution_m_ * resolution_m_);
  state_bounds_ = bounds_;
  const Eigen::Vector3d r = Eigen::Vector3d::Constant(config_.mav_radius_m);
  state_bounds_.min_m = bounds_.min_m + r;
  state_bounds_.max_m = bounds_.max_m - r;
  if (((state_bounds_.max_m - state_bounds_.min_m).array() <= 0).any())
    throw std::invalid_argument("PathPlanner: bounds are too small for the MAV radius");
  // OMPL logs every solve at INFO level; keep errors only.
  ompl::msg::setLogLevel(ompl::msg::LOG_ERROR);
}

int PathPlanner::threads() const {
  if (config_.planning_threads > 0) return config_.planning_threads;
  return std::max(1u, std::thread::hardware_concurrency());
}

bool PathPlanner::valid(const Eigen::Vector3d& p) const {
  return p.allFinite() && state_bounds_.contains(p) && is_free_(p, check_radius_m_);
}

bool PathPlanner::segmentValid(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  const double len = (b - a).norm();
  const int n = std::max(1, static_cast<int>(std::ceil(len / resolution_m_)));
  for (int i = 0; i <= n; ++i)
    if (!valid(a + (b - a) * (static_cast<double>(i) / n))) return false;
  return true;
}

bool PathPlanner::pathValid(const std::vector<Eigen::Vector3d>& path) const {
  if (path.empty()) return false;
  if (path.size() == 1) return valid(path[0]);
  for (std::size_t i = 1; i < path.size(); ++i)
    if (!segmentValid(path[i - 1], path[i])) return false;
  return true;
}

bool PathPlanner::nearestValid(const Eigen::Vector3d& p, double radius, Eigen::Vector3d& out) const {
  if (valid(p)) {
    out = p;
    return true;
  }
  const int shells = static_cast<int>(std::ceil(radius / resolution_m_));
  for (int k = 1; k <= shells; ++k) {
    const double r = std::min(radius, k * resolution_m_);
    double best = std::numeric_limits<double>::infinity();
    for (const auto& d : shellDirections()) {
      const Eigen::Vector3d q = p + r * d;
      // Within one shell prefer points that stay closest to the bounds-clamped target.
      if (valid(q)) {
        const double dist = (q - p).norm();
        if (dist < best) {
          best = dist;
          out = q;
        }
      }
    }
    if (std::isfinite(best)) return true;
  }
  return false;
}

std::uint32_t pathSeed(std::uint32_t seed, std::uint64_t iteration, std::uint64_t candidate) {
  return ompl_seeded::mix(ompl_seeded::mix(seed, iteration), candidate);
}

PlanningStart PathPlanner::planningStart(const Eigen::Vector3d& start) const {
  PlanningStart out;
  out.start_W = out.from_W = start;
  if (valid(start)) {
    out.ok = true;
    return out;
  }
  // Escape: nearest valid point whose straight segment keeps R/2 from
  // occupied voxels. Only half the radius: the MAV is already there, and a
  // surface seen from a new angle may have grown into its sphere; the escape
  // moves it away from that surface.
  Eigen::Vector3d esc;
  if (!not_occupied_ || !nearestValid(start, escape_radius_m_, esc)) return out;
  const double len = (esc - start).norm();
  const int n = std::max(1, static_cast<int>(std::ceil(len / resolution_m_)));
  for (int i = 0; i <= n; ++i) {
    const Eigen::Vector3d q = start + (esc - start) * (static_cast<double>(i) / n);
    if (!bounds_.contains(q) || !not_occupied_(q, 0.5 * config_.mav_radius_m)) return out;
  }
  out.from_W = esc;
  out.lead_W = {start};
  out.escaped = out.ok = true;
  return out;
}

ResolvedGoal PathPlanner::resolveGoal(const PlanningStart& from, const Eigen::Vector3d& goal_in) const {
  ResolvedGoal out;
  out.requested_W = goal_in;
  // Goals outside the state bounds are pulled in; invalid goals moved to the
  // nearest valid point near them (a frontier voxel always touches unknown).
  Eigen::Vector3d goal = goal_in;
  for (int i = 0; i < 3; ++i) goal[i] = std::clamp(goal[i], state_bounds_.min_m[i], state_bounds_.max_m[i]);
  out.goal_W = goal;
  Eigen::Vector3d projected;
  if (nearestValid(goal, 2.0 * config_.mav_radius_m + 2.0 * resolution_m_, projected)) {
    out.goal_W = projected;
    out.valid = true;
    return out;
  }
  // Deep in unknown or occupied space: take the first valid point on the
  // line back towards the start. An exact solve to it ends early (cost
  // threshold / convergence), where an approximate solve always spends the
  // whole budget; the RRT* approximation remains the fallback.
  const Eigen::Vector3d start = from.from_W;
  const double len = (start - goal).norm();
  const int n = static_cast<int>(std::ceil(len / resolution_m_));
  for (int k = 1; k < n; ++k) {
    const Eigen::Vector3d q = goal + (start - goal) * (static_cast<double>(k) / n);
    if (valid(q)) {
      out.goal_W = q;
      out.valid = out.moved_far = true;
      break;
    }
  }
  return out;
}

std::vector<ResolvedGoal> PathPlanner::resolveGoals(const PlanningStart& from,
                                                     const std::vector<Eigen::Vector3d>& goals) const {
  std::vector<ResolvedGoal> out(goals.size());
  parallelFor(goals.size(), threads(), [&](std::size_t i) { out[i] = resolveGoal(from, goals[i]); });
  return out;
}

PlannedPath PathPlanner::plan(const Eigen::Vector3d& start, const Eigen::Vector3d& goal, std::uint32_t seed) const {
  const PlanningStart from = planningStart(start);
  if (!from.ok) {
    PlannedPath out;
    out.status = PlannedPath::Status::kStartInvalid;
    out.distance_to_goal_m = (goal - start).norm();
    return out;
  }
  return plan(from, resolveGoal(from, goal), seed);
}

PlannedPath PathPlanner::plan(const PlanningStart& from, const ResolvedGoal& goal, std::uint32_t seed) const {
  const auto t0 = Clock::now();
  PlannedPath out;
  if (!from.ok) {
    out.status = PlannedPath::Status::kStartInvalid;
    out.distance_to_goal_m = (goal.requested_W - from.start_W).norm();
  } else {
    out = planFromValidStart(from.from_W, goal, seed);
    if (!from.lead_W.empty()) {
      out.escaped = from.escaped;
      if (out.ok()) {
        out.path_W.insert(out.path_W.begin(), from.lead_W.begin(), from.lead_W.end());
        // Several segments now; one that reaches its goal is what an exact solve gives.
        if (out.status == PlannedPath::Status::kStraight) out.status = PlannedPath::Status::kExact;
      } else if (from.escaped) {
        out.path_W = from.lead_W;  // at least get out of the invalid spot
        out.path_W.push_back(from.from_W);
        out.status = PlannedPath::Status::kApproximate;
      }  // a way out of a pocket alone is no path to this goal: kFailed
      if (out.ok()) out.distance_to_goal_m = (goal.requested_W - out.path_W.back()).norm();
    }
  }
  out.time_s = secondsSince(t0);
  return out;
}

PlannedPath PathPlanner::planFromValidStart(const Eigen::Vector3d& start, const ResolvedGoal& resolved,
                                               std::uint32_t seed) const {
  PlannedPath out;
  const Eigen::Vector3d& goal_in = resolved.requested_W;
  const Eigen::Vector3d goal = resolved.goal_W;
  const bool moved_far = resolved.moved_far;

  if (resolved.valid && segmentValid(start, goal)) {
    out.status = moved_far ? PlannedPath::Status::kApproximate : PlannedPath::Status::kStraight;
    out.path_W = {start, goal};
    out.distance_to_goal_m = (goal_in - goal).norm();
    return out;
  }

  auto space = std::make_shared<ob::RealVectorStateSpace>(3);
  ob::RealVectorBounds b(3);
  for (int i = 0; i < 3; ++i) {
    b.setLow(i, state_bounds_.min_m[i]);
    b.setHigh(i, state_bounds_.max_m[i]);
  }
  space->setBounds(b);
  auto si = std::make_shared<ob::SpaceInformation>(space);
  si->setStateValidityChecker([this](const ob::State* s) { return valid(toEigen(s)); });
  si->setStateValidityCheckingResolution(std::min(1.0, resolution_m_ / space->getMaximumExtent()));
  si->setup();

  ob::ScopedState<ob::RealVectorStateSpace> s(space), g(space);
  for (int i = 0; i < 3; ++i) {
    s[i] = start[i];
    g[i] = goal[i];
  }
  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  pdef->setStartAndGoalStates(s, g, 0.5 * resolution_m_);
  // Three engines, three streams of the one seed.
  auto objective = std::make_shared<ompl_seeded::PathLengthObjective>(si, ompl_seeded::mix(seed, 1));
  objective->setCostThreshold(ob::Cost(config_.cost_threshold_factor * (goal - start).norm()));
  pdef->setOptimizationObjective(objective);

  auto planner = std::make_shared<ompl_seeded::InformedRRTstar>(si, ompl_seeded::mix(seed, 2));
  planner->setProblemDefinition(pdef);
  planner->setup();
  // Stop at the budget (wall time or iterations), or earlier once the
  // solution cost has converged (a detour can never reach the straight-line
  // cost threshold).
  const bool by_iterations = config_.ompl_by_iterations();
  ob::IterationTerminationCondition iterations(static_cast<unsigned int>(config_.ompl_iterations));
  ob::PlannerTerminationCondition ptc = by_iterations ? ob::PlannerTerminationCondition(iterations)
                                                      : ob::timedPlannerTerminationCondition(config_.time_budget_s);
  if (config_.convergence_solutions > 0) {
    ob::ProblemDefinitionPtr pdef_base = pdef;
    ptc = ob::plannerOrTerminationCondition(
        ptc, ob::CostConvergenceTerminationCondition(pdef_base, static_cast<std::size_t>(config_.convergence_solutions),
                                                     config_.convergence_epsilon));
  }
  const ob::PlannerStatus st = planner->solve(ptc);
  if (st != ob::PlannerStatus::EXACT_SOLUTION && st != ob::PlannerStatus::APPROXIMATE_SOLUTION) {
    out.status = PlannedPath::Status::kFailed;
    out.distance_to_goal_m = (goal_in - start).norm();
    return out;
  }
  auto* geo = pdef->getSolutionPath()->as<og::PathGeometric>();
  std::vector<Eigen::Vector3d> raw;
  for (const ob::State* st_i : geo->getStates()) raw.push_back(toEigen(st_i));

  og::PathGeometric simplified(*geo);
  if (config_.simplify_time_s > 0) {
    ompl_seeded::PathSimplifier simplifier(si, ompl_seeded::mix(seed, 3));
    // By iterations: no wall-time cut, the simplification is part of the result.
    const auto simplify_ptc = ob::timedPlannerTerminationCondition(config_.simplify_time_s);
    simplifier.reduceVertices(simplified);
    if (by_iterations || !simplify_ptc()) simplifier.shortcutPath(simplified);
  }
  std::vector<Eigen::Vector3d> path;
  for (const ob::State* st_i : simplified.getStates()) path.push_back(toEigen(st_i));
  // Defensive dense check independent of OMPL's motion validator.
  if (!pathValid(path)) path = raw;
  if (!pathValid(path) || path.empty()) {
    out.status = PlannedPath::Status::kFailed;
    out.distance_to_goal_m = (goal_in - start).norm();
    return out;
  }
  path.front() = start;  // OMPL copies the start exactly; make it bit-exact anyway
  const bool exact = st == ob::PlannerStatus::EXACT_SOLUTION;
  // An exact solution ends within the goal tolerance; end it at the goal
  // itself, so that the view is taken where the candidate was evaluated.
  if (exact && path.back() != goal && resolved.valid) {
    if (path.size() >= 2 && segmentValid(path[path.size() - 2], goal))
      path.back() = goal;
    else if (segmentValid(path.back(), goal))
      path.push_back(goal);
  }
  out.path_W = std::move(path);
  out.status = (exact && !moved_far) ? PlannedPath::Status::kExact : PlannedPath::Status::kApproximate;
  out.distance_to_goal_m = (goal_in - out.path_W.back()).norm();
  return out;
}

std::vector<PlannedPath> PathPlanner::planAll(const PlanningStart& from, const std::vector<ResolvedGoal>& goals,
                                               const std::vector<std::uint32_t>& seeds) const {
  if (seeds.size() != goals.size()) throw std::invalid_argument("PathPlanner::planAll: one seed per goal");
  std::vector<PlannedPath> out(goals.size());
  parallelFor(goals.size(), threads(), [&](std::size_t i) {
    try {
      out[i] = plan(from, goals[i], seeds[i]);
    } catch (const std::exception&) {
      out[i] = PlannedPath();  // kFailed: one bad goal must not end the iteration
    }
  });
  return out;
}

std::vector<PlannedPath> PathPlanner::planAll(const Eigen::Vector3d& start, const std::vector<Eigen::Vector3d>& goals,
                                               std::uint32_t seed) const {
  const PlanningStart from = planningStart(start);
  std::vector<ResolvedGoal> resolved;
  if (from.ok) {
    resolved = resolveGoals(from, goals);
  } else {
    resolved.resize(goals.size());
    for (std::size_t i = 0; i < goals.size(); ++i) resolved[i].requested_W = resolved[i].goal_W = goals[i];
  }
  std::vector<std::uint32_t> seeds(goals.size());
  for (std::size_t i = 0; i < goals.size(); ++i) seeds[i] = pathSeed(seed, 0, i);
  return planAll(from, resolved, seeds);
}

}  // namespace semexp

// Path planning on synthetic maps: every path is collision-free at radius R
// (checked densely here, independent of OMPL), inside the bounds, starts at
// the start; approximate solutions into unknown space; a doorway.
#include <gtest/gtest.h>

#include <ompl/util/RandomNumbers.h>

#include "semexp_test/test_grid.hpp"
#include "semantic_exploration/core/planning/path_planner.hpp"

namespace semexp {
namespace {

// OMPL's random engines derive from one global seed set before the first one exists.
const bool kSeeded = (ompl::RNG::setSeed(42), true);

using semexp_test::TestGrid;

constexpr double kRes = 0.05;

Bounds room_bounds() {
  Bounds b;
  b.min_m = {0.0, 0.0, 0.0};
  b.max_m = {6.0, 4.0, 2.0};
  return b;
}

// 6 x 4 x 2 m, all free, with a wall at x in [2.9, 3.1] that has a doorway
// y in [2.6, 3.4] (0.8 m wide) over the full height.
TestGrid wall_with_doorway() {
  TestGrid g(room_bounds(), kRes, TestGrid::kFree);
  g.fill_box({2.9, 0.0, 0.0}, {3.1, 2.6, 2.0}, TestGrid::kOccupied);
  g.fill_box({2.9, 3.4, 0.0}, {3.1, 4.0, 2.0}, TestGrid::kOccupied);
  return g;
}

// Independent dense check: spheres of radius R every 5 mm along the path.
void expect_safe_path(const TestGrid& g, const std::vector<Eigen::Vector3d>& path, double R,
                      const Eigen::Vector3d& start) {
  ASSERT_FALSE(path.empty());
  EXPECT_TRUE(path.front() == start);
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Eigen::Vector3d a = path[i], b = path[i + 1];
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.005)));
    for (int k = 0; k <= n; ++k) {
      const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(k) / n);
      ASSERT_TRUE(g.bounds().contains(p)) << p.transpose();
      ASSERT_TRUE(g.sphereFree(p, R)) << "collision at " << p.transpose();
    }
  }
}

struct PathPlannerTest : ::testing::Test {
  PlannerConfig config;
  PathPlannerTest() {
    // OMPL stops after ompl_iterations, not after wall time: the answers must not depend on the machine's speed
    // (a 0.2 s budget under the sanitizers left RRT* short of a doorway in ExplorationTest).
    config.ompl_termination = "iterations";
    config.planning_threads = 2;
  }
  PathPlanner make(const TestGrid& g, bool with_escape = false) const {
    CollisionQuery free = [&g](const Eigen::Vector3d& p, double r) { return g.sphereFree(p, r); };
    CollisionQuery not_occ;
    if (with_escape) not_occ = [&g](const Eigen::Vector3d& p, double r) { return g.sphereNotOccupied(p, r); };
    return PathPlanner(config, g.bounds(), g.resolution(), free, not_occ);
  }
};

TEST_F(PathPlannerTest, StraightSegmentNeedsNoPlanner) {
  const TestGrid g = wall_with_doorway();
  const PathPlanner planner = make(g);
  const Eigen::Vector3d start(1, 1, 1), goal(2, 3, 1.5);
  const PlannedPath p = planner.plan(start, goal);
  EXPECT_EQ(p.status, PlannedPath::Status::kStraight);
  ASSERT_EQ(p.path_W.size(), 2u);
  EXPECT_TRUE(p.path_W.back() == goal);
  EXPECT_NEAR(p.distance_to_goal_m, 0.0, 1e-12);
  expect_safe_path(g, p.path_W, config.clearance_radius_m(), start);
}

TEST_F(PathPlannerTest, GoalBehindWallThroughDoorway) {
  const TestGrid g = wall_with_doorway();
  const PathPlanner planner = make(g);
  const Eigen::Vector3d start(1, 1, 1), goal(5, 1, 1);
  for (int trial = 0; trial < 3; ++trial) {
    const PlannedPath p = planner.plan(start, goal);
    ASSERT_TRUE(p.ok()) << PlannedPath::name(p.status);
    EXPECT_EQ(p.status, PlannedPath::Status::kExact);
    EXPECT_LT(p.distance_to_goal_m, kRes);
    expect_safe_path(g, p.path_W, config.clearance_radius_m(), start);
    // The path crosses the wall plane x = 3 inside the doorway.
    bool crossed = false;
    for (std::size_t i = 0; i + 1 < p.path_W.size(); ++i) {
      const Eigen::Vector3d a = p.path_W[i], b = p.path_W[i + 1];
      if ((a.x() - 3.0) * (b.x() - 3.0) <= 0 && a.x() != b.x()) {
        const double y = a.y() + (b.y() - a.y()) * (3.0 - a.x()) / (b.x() - a.x());
        EXPECT_GT(y, 2.6 + config.clearance_radius_m() - 1e-6);
        EXPECT_LT(y, 3.4 - config.clearance_radius_m() + 1e-6);
        crossed = true;
      }
    }
    EXPECT_TRUE(crossed);
    // No shorter than the shortest way around the doorway's lower wall edge
    // (voxel corners (2.875, 2.625) and (3.125, 2.625) at z = 1, kept R
    // away): tangents of 2 * sqrt(2.4812^2 - R^2) = 4.956 m, two arcs of
    // R * 0.7645 rad and 0.25 m across the top: 5.397 m.
    EXPECT_GT(pathLength_m(p.path_W), 5.397 - 1e-3);
  }
}

TEST_F(PathPlannerTest, ApproximateWhenGoalInUnknownSpace) {
  // Known free only for x < 3.5; beyond that unknown (the goal is 1.5 m deep in it).
  TestGrid g(room_bounds(), kRes, TestGrid::kUnknown);
  g.fill_box({0.0, 0.0, 0.0}, {3.5, 4.0, 2.0}, TestGrid::kFree);
  g.fill_box({1.9, 0.0, 0.0}, {2.1, 2.0, 2.0}, TestGrid::kOccupied);  // force a non-straight path
  const PathPlanner planner = make(g);
  const Eigen::Vector3d start(1, 1, 1), goal(5, 1, 1);
  const PlannedPath p = planner.plan(start, goal);
  ASSERT_TRUE(p.ok()) << PlannedPath::name(p.status);
  EXPECT_EQ(p.status, PlannedPath::Status::kApproximate);
  expect_safe_path(g, p.path_W, config.clearance_radius_m(), start);
  // As close as possible: the sphere must stay R + margin from the unknown at
  // x = 3.5, so the end is near x = 3.33, i.e. about 1.67 m from the goal.
  EXPECT_GT(p.path_W.back().x(), 3.0);
  EXPECT_NEAR(p.distance_to_goal_m, (goal - p.path_W.back()).norm(), 1e-12);
  EXPECT_LT(p.distance_to_goal_m, 2.2);
}

TEST_F(PathPlannerTest, FrontierGoalIsProjectedToNearbyFreeSpace) {
  TestGrid g(room_bounds(), kRes, TestGrid::kUnknown);
  g.fill_box({0.0, 0.0, 0.0}, {3.5, 4.0, 2.0}, TestGrid::kFree);
  const auto frontiers = g.frontiers();
  ASSERT_FALSE(frontiers.empty());
  const PathPlanner planner = make(g);
  const Eigen::Vector3d start(1, 1, 1), goal(3.475, 2.0, 1.0);  // a frontier voxel centre
  const PlannedPath p = planner.plan(start, goal);
  ASSERT_TRUE(p.ok());
  expect_safe_path(g, p.path_W, config.clearance_radius_m(), start);
  EXPECT_LT(p.distance_to_goal_m, 2 * config.mav_radius_m + 2 * kRes + 1e-9);
}

TEST_F(PathPlannerTest, KeepsClearOfASurfaceInsideAFreeVoxel) {
  // A wall fills y >= 3.5; a glass pane 1.5 cm in front of it (y = 3.485)
  // returns no depth, so its voxel [3.45, 3.5] is mapped free. The goal asks
  // for a point touching the wall: the path must keep R from the pane, which
  // only the clearance margin beyond R from the wall's voxels guarantees
  // (sqrt(R^2 + (r/2)^2) = 0.1275 m would stop 0.1125 m from the pane).
  TestGrid g(room_bounds(), kRes, TestGrid::kFree);
  g.fill_box({0.0, 3.5, 0.0}, {6.0, 4.0, 2.0}, TestGrid::kOccupied);
  const double pane_y = 3.485;
  const PathPlanner planner = make(g);
  ASSERT_GE(planner.checkRadius_m(), config.mav_radius_m + 0.04 - 1e-12);
  const Eigen::Vector3d start(1, 1, 1);
  for (const Eigen::Vector3d& goal : {Eigen::Vector3d(3, 3.45, 1), Eigen::Vector3d(4, 3.3, 1.5)}) {
    const PlannedPath p = planner.plan(start, goal);
    ASSERT_TRUE(p.ok()) << PlannedPath::name(p.status);
    expect_safe_path(g, p.path_W, config.clearance_radius_m(), start);
    for (const Eigen::Vector3d& q : p.path_W) EXPECT_LT(q.y(), pane_y - config.mav_radius_m) << q.transpose();
    // It still gets as close as the margin allows (within the goal search).
    EXPECT_GT(p.path_W.back().y(), 3.5 - config.clearance_radius_m() - 2 * kRes);
  }
}

TEST_F(PathPlannerTest, ParallelCandidatesAllSafe) {
  const TestGrid g = wall_with_doorway();
  const PathPlanner planner = make(g);
  const Eigen::Vector3d start(1, 1, 1);
  std::vector<Eigen::Vector3d> goals;
  for (int i = 0; i < 8; ++i) goals.emplace_back(0.5 + 0.7 * i, 0.5 + 0.4 * i, 0.5 + 0.15 * i);
  goals.emplace_back(3.0, 1.0, 1.0);  // inside the wall: projected or approximate
  goals.emplace_back(9.0, 9.0, 9.0);  // outside the bounds: clamped
  const auto paths = planner.planAll(start, goals);
  ASSERT_EQ(paths.size(), goals.size());
  for (std::size_t i = 0; i < paths.size(); ++i) {
    SCOPED_TRACE(i);
    ASSERT_TRUE(paths[i].ok()) << PlannedPath::name(paths[i].status);
    expect_safe_path(g, paths[i].path_W, config.clearance_radius_m(), start);
  }
}

TEST_F(PathPlannerTest, InvalidStart) {
  TestGrid g(room_bounds(), kRes, TestGrid::kFree);
  g.fill_box({0.0, 0.0, 0.0}, {1.2, 4.0, 2.0}, TestGrid::kUnknown);  // start sphere touches unknown
  g.fill_box({2.0, 0.0, 0.0}, {2.2, 4.0, 2.0}, TestGrid::kOccupied);
  const Eigen::Vector3d start(1.2, 1.0, 1.0), goal(1.8, 3.0, 1.0);
  // Without an occupancy query: reported, no path.
  const PlannedPath none = make(g).plan(start, goal);
  EXPECT_EQ(none.status, PlannedPath::Status::kStartInvalid);
  EXPECT_FALSE(none.ok());
  // With it: a short escape out of the unknown, then on to the goal.
  const PlannedPath esc = make(g, true).plan(start, goal);
  ASSERT_TRUE(esc.ok());
  EXPECT_TRUE(esc.escaped);
  EXPECT_TRUE(esc.path_W.front() == start);
  EXPECT_LT((esc.path_W[1] - start).norm(), 1.0);
  std::vector<Eigen::Vector3d> rest(esc.path_W.begin() + 1, esc.path_W.end());
  expect_safe_path(g, rest, config.clearance_radius_m(), rest.front());
  // Start inside the occupied wall: no escape through occupied space.
  const PlannedPath wall = make(g, true).plan({2.1, 1.0, 1.0}, goal);
  EXPECT_EQ(wall.status, PlannedPath::Status::kStartInvalid);
}

TEST_F(PathPlannerTest, EmptyMapGivesNoPath) {
  const TestGrid g(room_bounds(), kRes, TestGrid::kUnknown);
  const PlannedPath p = make(g).plan({1, 1, 1}, {3, 3, 1});
  EXPECT_FALSE(p.ok());
  EXPECT_EQ(p.status, PlannedPath::Status::kStartInvalid);
}

}  // namespace
}  // namespace semexp

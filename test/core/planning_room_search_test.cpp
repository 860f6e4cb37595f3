// The way out of a pocket (room_search.hpp): a lattice search through a
// passage RRT* does not sample, on a hand-built grid whose answer is known.
#include <gtest/gtest.h>

#include <functional>

#include "semexp_test/test_grid.hpp"
#include "semantic_exploration/core/planning/exploration_planner.hpp"
#include "semantic_exploration/core/planning/path_check.hpp"
#include "semantic_exploration/core/planning/room_search.hpp"

namespace semexp {
namespace {

using semexp_test::TestGrid;

Bounds bounds() {
  Bounds b;
  b.min_m = {0.0, 0.0, 0.0};
  b.max_m = {6.0, 4.0, 2.0};
  return b;
}

// Solid everywhere but three free boxes (voxel boxes, 5 cm voxels):
//  - a room, z 1.0-2.0 over the whole floor plan;
//  - a pocket, x 4.3-5.2, y 0.6-1.4, z 0.1-0.6: clearance sphere centres
//    (R + margin = 0.165 m) fit at z 0.265-0.435;
//  - a vertical passage from the pocket up into the room, x 4.8-5.2,
//    y 0.8-1.2, z 0.5-1.1: centres fit only within 3.5 cm of its axis
//    (x = 5.0, y = 1.0), a 7 x 7 cm square that random samples in the 6 x 4 x 2 m
//    bounds almost never hit.
// The start (4.6, 1.0, 0.35) lies on the axis's lattice: 4.6 + 4 steps of
// 0.1 m = 5.0, so the search is exact here; a passage off the lattice is
// found only where its free square is at least a step wide.
struct RoomSearchTest : ::testing::Test {
  PlannerConfig config;
  TestGrid grid{bounds(), 0.05, TestGrid::kOccupied};
  CollisionQuery is_free = [this](const Eigen::Vector3d& p, double r) { return grid.sphereFree(p, r); };
  const Eigen::Vector3d start{4.6, 1.0, 0.35};
  RoomSearchSettings settings;
  RoomSearchTest() {
    config.ompl_termination = "iterations";
    config.planning_threads = 2;
    grid.fill_box({0.0, 0.0, 1.0}, {6.0, 4.0, 2.0}, TestGrid::kFree);
    grid.fill_box({4.3, 0.6, 0.1}, {5.2, 1.4, 0.6}, TestGrid::kFree);
    grid.fill_box({4.8, 0.8, 0.5}, {5.2, 1.2, 1.1}, TestGrid::kFree);
    settings.room_radius_m = 2.0 * config.clearance_radius_m();  // 0.33 m: room at z 1.33-1.67
    settings.step_m = 0.1;
  }
  PathPlanner paths() const { return PathPlanner(config, bounds(), 0.05, is_free); }
};

TEST_F(RoomSearchTest, FindsTheWayUpThroughThePassage) {
  const PathPlanner p = paths();
  ASSERT_TRUE(p.valid(start));
  const std::vector<Eigen::Vector3d> route = findRoom(p, is_free, start, settings);
  ASSERT_GE(route.size(), 3u);  // across to the passage's axis, then up: no single straight segment
  EXPECT_TRUE(route.front() == start);
  // Room needs z - 0.33 >= 1.0: on the lattice (z = 0.35 + k 0.1) the lowest
  // level with room is z = 1.35, which breadth-first search reaches first
  // (10 steps up the axis; several points of that level are as few steps
  // away, and the neighbour order picks one).
  EXPECT_NEAR(route.back().z(), 1.35, 1e-9);
  EXPECT_TRUE(is_free(route.back(), settings.room_radius_m));
  EXPECT_TRUE(p.pathValid(route));
  for (std::size_t i = 1; i + 1 < route.size(); ++i) EXPECT_FALSE(is_free(route[i], settings.room_radius_m));
}

TEST_F(RoomSearchTest, NothingWhenThereIsRoomAlreadyOrNoWayOut) {
  EXPECT_TRUE(findRoom(paths(), is_free, {3.0, 2.0, 1.5}, settings).empty());  // in the room
  EXPECT_TRUE(findRoom(paths(), is_free, {3.0, 2.0, 0.5}, settings).empty());  // inside the solid: invalid
  grid.fill_box({4.8, 0.8, 0.75}, {5.2, 1.2, 0.85}, TestGrid::kOccupied);       // the passage closed
  EXPECT_TRUE(findRoom(paths(), is_free, start, settings).empty());
  settings.search_radius_m = 0.5;  // open again, but the room is 1.2 m up
  grid.fill_box({4.8, 0.8, 0.75}, {5.2, 1.2, 0.85}, TestGrid::kFree);
  EXPECT_TRUE(findRoom(paths(), is_free, start, settings).empty());
}

TEST_F(RoomSearchTest, PathsFromTheEndOfTheWayBeginWithIt) {
  const PathPlanner p = paths();
  const std::vector<Eigen::Vector3d> route = findRoom(p, is_free, start, settings);
  ASSERT_FALSE(route.empty());
  const PlanningStart from = startAfterRoute(route);
  EXPECT_TRUE(from.ok);
  EXPECT_FALSE(from.escaped);
  const PlannedPath plan = p.plan(from, p.resolveGoal(from, {1.0, 2.0, 1.5}), 1);
  ASSERT_TRUE(plan.ok());
  ASSERT_GT(plan.path_W.size(), route.size());
  for (std::size_t i = 0; i < route.size(); ++i) EXPECT_TRUE(plan.path_W[i] == route[i]) << i;
  EXPECT_TRUE(p.pathValid(plan.path_W));
  // Every segment keeps the full clearance, the first too (no escape's relaxed radius).
  const PathClearance clear =
      checkPathClearance(plan.path_W, plan.escaped, config.clearance_radius_m(), config.mav_radius_m, 0.025,
                         [this](const Eigen::Vector3d& q, double r) { return grid.sphereFree(q, r); });
  EXPECT_TRUE(clear.safe) << clear.why;
}

TEST_F(RoomSearchTest, TheSearchStopsAtMaxPoints) {
  settings.max_points = 5;  // the passage is more than 5 lattice points away from any room
  EXPECT_TRUE(findRoom(paths(), is_free, start, settings).empty());
}

// Gain images of `value` where `has(p)` holds, 0 elsewhere.
GainProvider gainsWhere(const std::function<bool(const Eigen::Vector3d&)>& has) {
  return [has](const std::vector<Eigen::Vector3d>& ps) {
    std::vector<GainSet> out(ps.size());
    for (std::size_t i = 0; i < ps.size(); ++i) out[i].entropy = GainImage(36, 10, has(ps[i]) ? 0.5f : 0.f);
    return out;
  };
}

// Frontiers in the room; nothing left to see in the pocket.
struct PocketIteration : RoomSearchTest {
  ExplorationProviders prov;
  ExplorationInputs in;
  PocketIteration() {
    config.a_ent = 1.0;
    config.a_bg = config.a_obj = 0.0;
    config.p_frontier = 1.0;
    config.n_candidates = 4;
    prov.is_free = is_free;
    prov.gains = gainsWhere([](const Eigen::Vector3d& p) { return p.z() > 0.9; });
    in.position_W = start;
    in.frontiers_W = {{1.0, 2.0, 1.5}, {2.0, 3.0, 1.5}, {3.0, 1.0, 1.5}, {1.0, 1.0, 1.5}};
  }
  IterationResult plan(bool lazy, int* failed = nullptr) {
    config.lazy_planning = lazy;
    ExplorationPlanner planner(config, ExplorationConfig(), bounds(), PinholeCamera(), 0.05);
    IterationResult r = planner.plan(in, prov);
    if (failed) *failed = planner.failedIterations();
    return r;
  }
};

// One planning iteration from the pocket: RRT* alone takes no candidate out
// of it (its approximate paths end in the pocket, where there is nothing to
// see: no winner; checked below with the iteration's own seeds), so before
// failing the iteration plans again from the point with room and flies the
// way out, lazy and exhaustive alike.
TEST_F(PocketIteration, LeavesThroughThePassageInsteadOfFailing) {
  const IterationResult r = plan(true);
  ASSERT_GE(r.winner, 0) << r.message;
  EXPECT_EQ(r.candidates.size(), 4u);
  EXPECT_EQ(r.way_out.rfind("no winner from (4.60, 1.00, 0.35), which has no room; planned again from (", 0), 0u)
      << r.way_out;
  // The planner searches with its own settings: those of this fixture.
  const std::vector<Eigen::Vector3d> route = findRoom(paths(), is_free, start, settings);
  ASSERT_GE(r.path_W.size(), route.size());
  for (std::size_t i = 0; i < route.size(); ++i) EXPECT_TRUE(r.path_W[i] == route[i]) << i;
  EXPECT_GT(r.path_W.back().z(), 1.0);
  EXPECT_TRUE(paths().pathValid(r.path_W));
  const IterationResult all = plan(false);
  EXPECT_EQ(all.winner, r.winner);
  EXPECT_TRUE(all.path_W == r.path_W);
  EXPECT_EQ(all.way_out, r.way_out);
  // The premise: from the start itself, no candidate's path leaves the pocket.
  const PathPlanner p = paths();
  const PlanningStart from = p.planningStart(start);
  for (std::size_t i = 0; i < r.candidates.size(); ++i) {
    const PlannedPath direct =
        p.plan(from, p.resolveGoal(from, r.candidates[i].view_W), pathSeed(config.seed, 0, i));
    EXPECT_FALSE(direct.ok() && direct.path_W.back().z() > 0.6) << i;
  }
  // Off: the iteration fails (the failure that ended a mission).
  config.room_search_radius_m = 0.0;
  int failed = 0;
  const IterationResult stuck = plan(true, &failed);
  EXPECT_EQ(stuck.winner, -1) << stuck.message;
  EXPECT_TRUE(stuck.way_out.empty());
  EXPECT_EQ(failed, 1);
}

// An iteration with a winner is left alone, cramped start or not: here the
// pocket has something to see, and the winner is a hop inside it.
TEST_F(PocketIteration, NoSecondPassWhenThereIsAWinner) {
  prov.gains = gainsWhere([](const Eigen::Vector3d&) { return true; });
  const IterationResult r = plan(true);
  ASSERT_GE(r.winner, 0) << r.message;
  EXPECT_TRUE(r.way_out.empty()) << r.way_out;
  EXPECT_LT(r.path_W.back().z(), 0.6);
}

// The second pass finds no winner either (everything with gain lies in a
// sealed chamber no path reaches): the iteration fails as it would have.
TEST_F(PocketIteration, FailsWhenTheSecondPassHasNoWinnerEither) {
  grid.fill_box({0.5, 2.5, 0.1}, {1.5, 3.5, 0.6}, TestGrid::kFree);  // the chamber, sealed
  in.frontiers_W = {{1.0, 3.0, 0.35}};
  prov.gains = gainsWhere([](const Eigen::Vector3d& p) { return p.x() < 2.0 && p.z() < 0.9; });
  int failed = 0;
  const IterationResult r = plan(true, &failed);
  EXPECT_EQ(r.winner, -1) << r.message;
  EXPECT_NE(r.way_out.find(": no winner from there either"), std::string::npos) << r.way_out;
  EXPECT_EQ(failed, 1);
  EXPECT_TRUE(r.path_W.empty());
  const IterationResult all = plan(false);
  EXPECT_EQ(all.winner, -1);
  EXPECT_EQ(all.way_out, r.way_out);
}

}  // namespace
}  // namespace semexp

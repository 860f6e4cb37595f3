// The final clearance check of a chosen path (checkPathClearance): a sphere
// obstacle of known radius against paths at hand-computed distances.
#include <gtest/gtest.h>

#include "semantic_exploration/core/planning/path_check.hpp"

using semexp::checkPathClearance;

namespace {

// One occupied ball of radius 0.1 m at (2, 0, 1): a query sphere is "not
// occupied" iff its centre is farther than r + 0.1 from the ball's centre.
const Eigen::Vector3d kObstacle(2.0, 0.0, 1.0);
semexp::CollisionQuery notOccupied() {
  return [](const Eigen::Vector3d& p, double r) { return (p - kObstacle).norm() > r + 0.1; };
}
constexpr double kClearance = 0.165;  // R 0.125 + margin 0.04
constexpr double kRadius = 0.125;
constexpr double kStep = 0.02;

}  // namespace

TEST(PathCheck, RefusesAPathPassingWithinTheClearance) {
  // Straight line at y = 0.25: closest approach 0.25 m to the obstacle's
  // centre, 0.15 m from its surface, inside the clearance of 0.165 m.
  const std::vector<Eigen::Vector3d> path{{0, 0.25, 1}, {4, 0.25, 1}};
  const auto c = checkPathClearance(path, false, kClearance, kRadius, kStep, notOccupied());
  EXPECT_FALSE(c.safe);
  EXPECT_NE(c.why.find("occupied voxel within 0.165 m"), std::string::npos) << c.why;
  EXPECT_NE(c.why.find("segment 1 of 1"), std::string::npos) << c.why;
}

TEST(PathCheck, AcceptsTheSamePathJustOutsideTheClearance) {
  // y = 0.28: 0.18 m from the surface > 0.165 m.
  const std::vector<Eigen::Vector3d> path{{0, 0.28, 1}, {4, 0.28, 1}};
  const auto c = checkPathClearance(path, false, kClearance, kRadius, kStep, notOccupied());
  EXPECT_TRUE(c.safe) << c.why;
  EXPECT_TRUE(c.why.empty());
}

TEST(PathCheck, NamesTheSegmentThatComesTooClose) {
  // Three segments; only the second passes the obstacle (at 0.2 m from its centre).
  const std::vector<Eigen::Vector3d> path{{0, 1, 1}, {1.8, 0.2, 1}, {2.2, 0.2, 1}, {4, 1, 1}};
  const auto c = checkPathClearance(path, false, kClearance, kRadius, kStep, notOccupied());
  EXPECT_FALSE(c.safe);
  EXPECT_NE(c.why.find("segment 2 of 3"), std::string::npos) << c.why;
}

TEST(PathCheck, AnEscapeSegmentIsCheckedAtHalfTheRadius) {
  // The start is 0.22 m from the obstacle's centre (0.12 m from its surface):
  // inside the clearance, but outside R/2 = 0.0625 m; the path leaves away
  // from it, then goes on at a safe distance.
  const std::vector<Eigen::Vector3d> path{{2, 0.22, 1}, {2, 0.6, 1}, {4, 0.6, 1}};
  EXPECT_TRUE(checkPathClearance(path, true, kClearance, kRadius, kStep, notOccupied()).safe);
  const auto strict = checkPathClearance(path, false, kClearance, kRadius, kStep, notOccupied());
  EXPECT_FALSE(strict.safe);
  EXPECT_NE(strict.why.find("segment 1 of 2"), std::string::npos) << strict.why;
  // Only the first segment is an escape: the same closeness on the second is refused.
  const std::vector<Eigen::Vector3d> late{{2, 0.6, 1}, {2, 0.3, 1}, {2, 0.22, 1}};
  EXPECT_FALSE(checkPathClearance(late, true, kClearance, kRadius, kStep, notOccupied()).safe);
}

TEST(PathCheck, EmptyAndSingleVertexPaths) {
  const auto empty = checkPathClearance({}, false, kClearance, kRadius, kStep, notOccupied());
  EXPECT_FALSE(empty.safe);
  EXPECT_EQ(empty.why, "empty path");
  EXPECT_TRUE(checkPathClearance({{0, 0, 1}}, false, kClearance, kRadius, kStep, notOccupied()).safe);
}

TEST(PathCheck, SamplesFinelyEnoughToSeeAThinObstacleBetweenVertices) {
  // A long segment whose vertices are both far away: only the samples in
  // between meet the obstacle.
  const std::vector<Eigen::Vector3d> path{{-10, 0, 1}, {10, 0, 1}};
  EXPECT_FALSE(checkPathClearance(path, false, kClearance, kRadius, kStep, notOccupied()).safe);
}

TEST(PathCheck, RejectsBadArguments) {
  const std::vector<Eigen::Vector3d> path{{0, 0, 1}, {1, 0, 1}};
  EXPECT_THROW(checkPathClearance(path, false, kClearance, kRadius, 0.0, notOccupied()), std::invalid_argument);
  EXPECT_THROW(checkPathClearance(path, false, 0.0, kRadius, kStep, notOccupied()), std::invalid_argument);
  EXPECT_THROW(checkPathClearance(path, false, kClearance, kRadius, kStep, semexp::CollisionQuery()),
               std::invalid_argument);
}

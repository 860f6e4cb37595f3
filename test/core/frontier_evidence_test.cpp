// Frontier voxels looked at from close by without being resolved are retired
// (core/frontier_evidence.hpp), on a free ball carved into unknown space: every
// voxel of its shell is a frontier, at a known distance from its centre.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "semexp_test/box_room.hpp"
#include "semantic_exploration/core/frontier_evidence.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"

using namespace semexp;
using semexp_test::lookPose;

namespace {

Bounds ballBounds() {
  Bounds b;
  b.min_m = {-3.0, -3.0, -3.0};
  b.max_m = {3.0, 3.0, 3.0};
  return b;
}

// A map whose only known space is a free ball of radius 1 m at the origin.
OccupancyMap freeBall() {
  BackgroundMapConfig cfg;  // 4 cm voxels
  OccupancyMap map(cfg, ballBounds());
  map.markFreeSphere(Eigen::Vector3d::Zero(), 1.0);
  map.updateFrontiers();
  return map;
}

// The frontier voxel of the ball's shell nearest `p`.
Eigen::Vector3d frontierNear(const OccupancyMap& map, const Eigen::Vector3d& p) {
  Eigen::Vector3d best = Eigen::Vector3d::Constant(1e9);
  map.forEachFrontier([&](const Eigen::Vector3d& c, double) {
    if ((c - p).norm() < (best - p).norm()) best = c;
  });
  return best;
}

std::vector<float> constantDepth(const PinholeCamera& cam, float d) {
  return std::vector<float>(static_cast<std::size_t>(cam.width) * cam.height, d);
}

// Frontier leaves larger than one voxel.
std::size_t coarseFrontierLeaves(const OccupancyMap& map) {
  std::size_t n = 0;
  map.forEachFrontier([&](const Eigen::Vector3d&, double size_m) { n += size_m > 1.5 * map.resolution(); });
  return n;
}

// Free voxels with an unknown face neighbour whose centres lie in [lo_m, hi_m], by brute force.
std::size_t frontierVoxelsByBruteForce(const OccupancyMap& map, const Eigen::Vector3d& lo_m,
                                       const Eigen::Vector3d& hi_m) {
  const Eigen::Vector3d o = map.origin();
  const double r = map.resolution();
  auto centre = [&](int i, int j, int k) {
    return Eigen::Vector3d(o.x() + r * (i + 0.5), o.y() + r * (j + 0.5), o.z() + r * (k + 0.5));
  };
  auto unknown = [&](int i, int j, int k) { return map.state(centre(i, j, k)) == VoxelState::kUnknown; };
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = static_cast<int>(std::ceil((lo_m[a] - o[a]) / r - 0.5));
    hi[a] = static_cast<int>(std::floor((hi_m[a] - o[a]) / r - 0.5));
  }
  std::size_t n = 0;
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i)
        if (map.state(centre(i, j, k)) == VoxelState::kFree &&
            (unknown(i - 1, j, k) || unknown(i + 1, j, k) || unknown(i, j - 1, k) || unknown(i, j + 1, k) ||
             unknown(i, j, k - 1) || unknown(i, j, k + 1)))
          ++n;
  return n;
}

}  // namespace

TEST(FrontierEvidence, ThreeLooksFromDifferentPlacesRetireAVoxelThatStaysAFrontier) {
  const OccupancyMap map = freeBall();
  ASSERT_GT(map.frontierCount(), 1000u);
  const PinholeCamera cam;
  const Eigen::Vector3d ahead = frontierNear(map, {1.0, 0.0, 0.0});   // on the +x axis, ~0.98 m out
  const Eigen::Vector3d behind = frontierNear(map, {-1.0, 0.0, 0.0});
  ASSERT_NEAR(ahead.x(), 0.98, 0.03);

  FrontierEvidence ev(FrontierEvidenceConfig{});
  const auto none = constantDepth(cam, 0.f);  // no return anywhere: a mirror or window fills the view
  EXPECT_GT(ev.look(map, none.data(), cam, lookPose({0.0, 0.0, 0.0}, 0.0, 0.0)), 0u);
  EXPECT_EQ(ev.looks(ahead), 1);
  EXPECT_EQ(ev.looks(behind), 0);  // behind the camera
  // The same pose again, 0.2 m back (< 0.25 m), or turned on the spot (the ray to the voxel is the same):
  // not a different look.
  ev.look(map, none.data(), cam, lookPose({0.0, 0.0, 0.0}, 0.0, 0.0));
  ev.look(map, none.data(), cam, lookPose({-0.2, 0.0, 0.0}, 0.0, 0.0));
  EXPECT_EQ(ev.looks(ahead), 1);
  ev.look(map, none.data(), cam, lookPose({0.0, 0.0, 0.0}, 20.0 * M_PI / 180.0, 0.0));
  EXPECT_EQ(ev.looks(ahead), 1);
  EXPECT_FALSE(ev.retired(ahead));
  // 0.3 m back (0.3 >= 0.25 m from the last counted look at the origin), then 0.3 m to the side of that.
  ev.look(map, none.data(), cam, lookPose({-0.3, 0.0, 0.0}, 0.0, 0.0));
  EXPECT_EQ(ev.looks(ahead), 2);
  EXPECT_FALSE(ev.retired(ahead));
  // A third place, 0.3 m to the side of the second.
  ev.look(map, none.data(), cam, lookPose({-0.3, 0.3, 0.0}, 0.0, 0.0));
  EXPECT_EQ(ev.looks(ahead), 3);
  EXPECT_TRUE(ev.retired(ahead));
  EXPECT_FALSE(ev.retired(behind));
  EXPECT_GT(ev.retiredCount(), 0u);
  EXPECT_LT(ev.retiredCount(), map.frontierCount());  // the half behind was never seen
}

TEST(FrontierEvidence, TurningTheRayCountsAsANewLook) {
  // With the separation out of reach only the ray to the voxel 0.98 m ahead decides: 0.1 m to the side
  // turns it by atan(0.1 / 0.98) = 5.8 deg (< 15 deg, no look), 0.3 m to the side by 17.0 deg (a look).
  const OccupancyMap map = freeBall();
  const PinholeCamera cam;
  const Eigen::Vector3d ahead = frontierNear(map, {1.0, 0.0, 0.0});
  FrontierEvidenceConfig c;
  c.min_look_separation_m = 10.0;  // only the turn of the ray decides
  FrontierEvidence ev(c);
  const auto none = constantDepth(cam, 0.f);
  ev.look(map, none.data(), cam, lookPose({0.0, 0.0, 0.0}, 0.0, 0.0));
  ASSERT_EQ(ev.looks(ahead), 1);
  ev.look(map, none.data(), cam, lookPose({0.0, 0.1, 0.0}, 0.0, 0.0));
  EXPECT_EQ(ev.looks(ahead), 1);
  ev.look(map, none.data(), cam, lookPose({0.0, 0.3, 0.0}, 0.0, 0.0));
  EXPECT_EQ(ev.looks(ahead), 2);
}

TEST(FrontierEvidence, DisabledCountsNothing) {
  const OccupancyMap map = freeBall();
  const PinholeCamera cam;
  FrontierEvidenceConfig c;
  c.enabled = false;
  FrontierEvidence ev(c);
  const auto none = constantDepth(cam, 0.f);
  EXPECT_EQ(ev.look(map, none.data(), cam, lookPose({0.0, 0.0, 0.0}, 0.0, 0.0)), 0u);
  EXPECT_EQ(ev.looks(frontierNear(map, {1.0, 0.0, 0.0})), 0);
}

TEST(FrontierEvidence, AHitNearerThanTheVoxelByMoreThanTheMarginHidesIt) {
  const OccupancyMap map = freeBall();
  const PinholeCamera cam;
  const Eigen::Vector3d ahead = frontierNear(map, {1.0, 0.0, 0.0});
  const double z = ahead.x();  // z-depth from the origin looking along +x
  const auto look = [&](float depth) {
    FrontierEvidence ev(FrontierEvidenceConfig{});  // occlusion_margin_m 0.1
    const auto d = constantDepth(cam, depth);
    ev.look(map, d.data(), cam, lookPose({0.0, 0.0, 0.0}, 0.0, 0.0));
    return ev.looks(ahead);
  };
  EXPECT_EQ(look(static_cast<float>(z + 0.5)), 1);   // surface behind it
  EXPECT_EQ(look(static_cast<float>(z - 0.05)), 1);  // within the margin: the surface the voxel borders
  EXPECT_EQ(look(static_cast<float>(z - 0.15)), 0);  // something 15 cm in front hid it
}

TEST(FrontierEvidence, OnlyVoxelsWithinRangeAndWellInsideTheImageCount) {
  const OccupancyMap map = freeBall();
  const PinholeCamera cam;  // hfov 62.7 deg
  const auto none = constantDepth(cam, 0.f);
  const Eigen::Vector3d ahead = frontierNear(map, {1.0, 0.0, 0.0});
  {
    FrontierEvidenceConfig c;
    c.view_range_m = 0.9;  // the shell lies 0.98 m away
    FrontierEvidence ev(c);
    ev.look(map, none.data(), cam, lookPose({0.0, 0.0, 0.0}, 0.0, 0.0));
    EXPECT_EQ(ev.looks(ahead), 0);
    EXPECT_EQ(ev.retiredCount(), 0u);
  }
  // A shell voxel 31 deg off the axis lies at the image border (half the hfov is 31.4 deg): its
  // neighbourhood leaves the image, so it is not a look; one 20 deg off the axis is.
  const double a_edge = 31.0 * M_PI / 180.0, a_in = 20.0 * M_PI / 180.0;
  const Eigen::Vector3d edge = frontierNear(map, {std::cos(a_edge), std::sin(a_edge), 0.0});
  const Eigen::Vector3d inside = frontierNear(map, {std::cos(a_in), std::sin(a_in), 0.0});
  FrontierEvidence ev(FrontierEvidenceConfig{});
  ev.look(map, none.data(), cam, lookPose({0.0, 0.0, 0.0}, 0.0, 0.0));
  EXPECT_EQ(ev.looks(edge), 0);
  EXPECT_EQ(ev.looks(inside), 1);
}

TEST(FrontierEvidence, AResolvedVoxelIsForgotten) {
  OccupancyMap map = freeBall();
  const PinholeCamera cam;
  const Eigen::Vector3d ahead = frontierNear(map, {1.0, 0.0, 0.0});
  FrontierEvidence ev(FrontierEvidenceConfig{});
  const auto none = constantDepth(cam, 0.f);
  ev.look(map, none.data(), cam, lookPose({0.0, 0.0, 0.0}, 0.0, 0.0));
  ASSERT_EQ(ev.looks(ahead), 1);
  // A wall 2.013 m ahead, seen from the ball's centre: its rays carve the space past the shell.
  semexp_test::BoxRoom room;
  room.room = {{-2.9, -2.9, -2.9}, {2.013, 2.9, 2.9}};
  const Eigen::Isometry3d T = lookPose({-0.3, 0.0, 0.0}, 0.0, 0.0);
  map.integrate(room.render(cam, T).data(), nullptr, cam, T);
  map.updateFrontiers();
  ev.look(map, room.render(cam, T).data(), cam, T);
  EXPECT_EQ(ev.looks(ahead), 0);
  EXPECT_FALSE(ev.retired(ahead));
}

// The ball's free blocks that touch unknown space stay blocks (OccupancyMap::refreshSummaries): released
// into one uniform leaf, a block's frontier voxels would become one coarse leaf at its centre, which no look
// can retire and whose voxels forget their looks when the block splits again. Every frontier leaf is one
// voxel, and they are exactly the free voxels with an unknown face neighbour.
TEST(FrontierEvidence, EveryFrontierOfAFreeBallIsAVoxelOfItsOwn) {
  OccupancyMap map = freeBall();
  std::size_t leaves = 0;
  map.forEachFrontier([&](const Eigen::Vector3d&, double) { ++leaves; });
  EXPECT_EQ(coarseFrontierLeaves(map), 0u);
  const std::size_t expected = frontierVoxelsByBruteForce(map, Eigen::Vector3d(-1.1, -1.1, -1.1),
                                                          Eigen::Vector3d(1.1, 1.1, 1.1));
  EXPECT_GT(expected, 1000u);
  EXPECT_EQ(leaves, expected);
  EXPECT_EQ(map.frontierCount(), expected);
  // Once every voxel of the map is known, no block borders unknown space: the blocks kept for their frontier
  // voxels are released (updateFrontiers), though the second sphere writes none of their voxels.
  ASSERT_GT(map.blockCount(), 0u);
  map.markFreeSphere(Eigen::Vector3d::Zero(), 6.0);  // reaches every corner of the 6 m map
  map.updateFrontiers();
  EXPECT_EQ(map.frontierCount(), 0u);
  EXPECT_EQ(map.blockCount(), 0u);
}

// The same through integration: depth frames of the standard room, whose uniform path makes whole cells free
// in one update. After each second frame the frontier leaves are voxels, exactly the brute-force set.
TEST(FrontierEvidence, FramesOfARoomLeaveEveryFrontierAVoxelOfItsOwn) {
  const semexp_test::BoxRoom room = semexp_test::standardRoom();
  const Bounds bounds = room.bounds(0.2);
  OccupancyMap map(BackgroundMapConfig{}, bounds);
  const PinholeCamera cam;
  const Eigen::Isometry3d poses[] = {lookPose({-1.5, 0.0, 1.2}, 0.0, 0.0), lookPose({-1.5, 0.0, 1.2}, 1.2, 0.0),
                                     lookPose({0.5, 0.2, 1.5}, 2.5, 0.3), lookPose({0.5, 0.2, 1.5}, -2.0, -0.3),
                                     lookPose({2.0, -0.5, 1.0}, 3.1, 0.0), lookPose({2.0, -0.5, 1.0}, -1.6, 0.2)};
  int checked = 0;
  for (int f = 0; f < 6; ++f) {
    map.integrate(room.render(cam, poses[f]).data(), nullptr, cam, poses[f]);
    map.updateFrontiers();
    if (f % 2 == 0) continue;
    ++checked;
    EXPECT_EQ(coarseFrontierLeaves(map), 0u) << "frame " << f;
    const std::size_t expected = frontierVoxelsByBruteForce(map, bounds.min_m, bounds.max_m);
    EXPECT_GT(expected, 1000u) << "frame " << f;
    EXPECT_EQ(map.frontierCount(), expected) << "frame " << f;
  }
  EXPECT_EQ(checked, 3);
}

TEST(FrontierEvidence, InvalidConfigNamesTheParameter) {
  FrontierEvidenceConfig c;
  c.looks_to_retire = 0;
  try {
    FrontierEvidence ev(c);
    FAIL() << "accepted looks_to_retire 0";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("frontier_evidence/looks_to_retire"), std::string::npos);
  }
  c = FrontierEvidenceConfig{};
  c.view_range_m = std::nan("");
  EXPECT_THROW(FrontierEvidence{c}, ConfigError);
  c = FrontierEvidenceConfig{};
  c.looks_to_retire = 256;  // counts are kept in 8 bits
  EXPECT_THROW(FrontierEvidence{c}, ConfigError);
}

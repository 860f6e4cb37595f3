// The background map against OctoMap on the same analytic frames (issue 4
// acceptance): state agreement, occupied coverage, no occupied voxel far from
// a true surface, explored volume.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <cstdio>

#include "semexp_test/box_room.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"

using namespace semexp;
using semexp_test::BoxRoom;

namespace {

struct Fixture {
  BoxRoom scene = semexp_test::standardRoom();
  PinholeCamera cam;
  BackgroundMapConfig cfg;
  Bounds bounds;
  std::vector<Eigen::Isometry3d> poses;

  Fixture() {
    cfg.free_margin_quadratic_per_m = 0.0;  // OctoMap carves free space up to the measured depth: compare like with like
    bounds = scene.bounds(0.3);
    const int n = 24;
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n;
      poses.push_back(semexp_test::lookPose({0.6 * std::cos(a), 0.6 * std::sin(a), 1.3}, 1.3 * a, 0.17 + 0.1 * std::sin(3 * a)));
    }
  }
};

}  // namespace

TEST(OccupancyMapVsOctomap, AnalyticRoomWithBoxes) {
  Fixture fx;
  OccupancyMap map(fx.cfg, fx.bounds);
  const double r = fx.cfg.resolution_m;
  octomap::OcTree tree(r);
  tree.setProbHit(1.0 / (1.0 + std::exp(-fx.cfg.log_odds_occupied)));
  tree.setProbMiss(1.0 / (1.0 + std::exp(-fx.cfg.log_odds_free)));
  tree.setClampingThresMin(1.0 / (1.0 + std::exp(-fx.cfg.log_odds_min)));
  tree.setClampingThresMax(1.0 / (1.0 + std::exp(-fx.cfg.log_odds_max)));

  for (const auto& T_WC : fx.poses) {
    const std::vector<float> depth = fx.scene.render(fx.cam, T_WC);
    map.integrate(depth.data(), nullptr, fx.cam, T_WC);
    map.updateFrontiers();
    octomap::Pointcloud cloud;
    for (int v = 0; v < fx.cam.height; ++v)
      for (int u = 0; u < fx.cam.width; ++u) {
        const float d = depth[v * fx.cam.width + u];
        if (d <= 0.f) continue;
        const Eigen::Vector3d p = T_WC * (fx.cam.ray_C(u, v).cast<double>() * d);
        cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
      }
    const Eigen::Vector3d o = T_WC.translation();
    tree.insertPointCloud(cloud, octomap::point3d(o.x(), o.y(), o.z()), fx.cam.d_max_m, false, true);
  }
  tree.updateInnerOccupancy();

  // Walk every voxel of the map's extent.
  const Eigen::Vector3d lo = map.extentMin(), hi = map.extentMax();
  const Eigen::Vector3i n = ((hi - lo) / r).array().round().cast<int>();
  std::size_t common = 0, agree = 0, oct_occ = 0, oct_occ_near = 0, ours_occ = 0, ours_far = 0;
  std::size_t ours_only = 0, theirs_only = 0;
  double worst = 0.0;
  auto ours = [&](int x, int y, int z) {
    return map.state(lo + (Eigen::Vector3d(x, y, z) + Eigen::Vector3d::Constant(0.5)) * r);
  };
  for (int z = 0; z < n.z(); ++z)
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) {
        const Eigen::Vector3d c = lo + (Eigen::Vector3d(x, y, z) + Eigen::Vector3d::Constant(0.5)) * r;
        const VoxelState s = ours(x, y, z);
        const octomap::OcTreeNode* node = tree.search(c.x(), c.y(), c.z());
        const VoxelState t = !node ? VoxelState::kUnknown
                                   : (tree.isNodeOccupied(node) ? VoxelState::kOccupied : VoxelState::kFree);
        if (s != VoxelState::kUnknown && t != VoxelState::kUnknown) {
          ++common;
          agree += s == t;
        } else if (s != VoxelState::kUnknown) {
          ++ours_only;
        } else if (t != VoxelState::kUnknown) {
          ++theirs_only;
        }
        if (t == VoxelState::kOccupied) {
          ++oct_occ;
          bool near = false;
          for (int dz = -1; dz <= 1 && !near; ++dz)
            for (int dy = -1; dy <= 1 && !near; ++dy)
              for (int dx = -1; dx <= 1 && !near; ++dx) near = ours(x + dx, y + dy, z + dz) == VoxelState::kOccupied;
          oct_occ_near += near;
        }
        if (s == VoxelState::kOccupied) {
          ++ours_occ;
          const double d = fx.scene.surfaceDistance(c);
          worst = std::max(worst, d);
          ours_far += d > 2 * r + 1e-9;
        }
      }
  double oct_explored = 0.0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const double s = it.getSize();
    const octomap::point3d c = it.getCoordinate();
    if (c.x() < lo.x() || c.y() < lo.y() || c.z() < lo.z() || c.x() > hi.x() || c.y() > hi.y() || c.z() > hi.z()) continue;
    oct_explored += s * s * s;
  }
  const double agreement = static_cast<double>(agree) / common;
  const double coverage = static_cast<double>(oct_occ_near) / oct_occ;
  const double vol_ratio = map.exploredVolume() / oct_explored;
  std::printf("common %zu agree %.4f | ours-only %zu theirs-only %zu | octomap occupied %zu covered %.4f | ours occupied %zu,"
              " far %zu (worst %.3f m) | explored ours %.3f octomap %.3f m^3 ratio %.4f | frontiers %zu\n",
              common, agreement, ours_only, theirs_only, oct_occ, coverage, ours_occ, ours_far, worst,
              map.exploredVolume(), oct_explored, vol_ratio, map.frontierCount());
  EXPECT_GT(common, 100000u);
  EXPECT_GE(agreement, 0.97);
  EXPECT_GE(coverage, 0.95);
  EXPECT_EQ(ours_far, 0u);
  EXPECT_NEAR(vol_ratio, 1.0, 0.03);
}

// The share of the background surface observed from <= d (the background half
// of the paper's termination condition, Section IV-D), on two walls seen from
// known distances.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "semexp_test/box_room.hpp"
#include "semexp_test/rendering.hpp"
#include "semantic_exploration/core/map_blocks.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"

using namespace semexp;
using semexp_test::BoxRoom;
using semexp_test::lookPose;

namespace {

// Walls facing the origin at x = 2.013 m and x = -4.013 m; floor, ceiling and
// side walls far enough to stay outside both views.
BoxRoom twoWalls() {
  BoxRoom s;
  s.room = {{-4.013, -6.0, -4.0}, {2.013, 6.0, 4.0}};
  return s;
}

Bounds twoWallBounds() {
  Bounds b;
  b.min_m = {-4.5, -3.0, -2.5};
  b.max_m = {2.5, 3.0, 2.5};
  return b;
}

// The default free margin (q = 0.006, 3 sigma of the simulator's depth noise) and a band of occupied voxels
// this deep behind each depth.
BackgroundMapConfig marginConfig(double surface_band_m) {
  BackgroundMapConfig cfg;
  cfg.surface_band_m = surface_band_m;
  cfg.free_margin_quadratic_per_m = 0.006;
  return cfg;
}

// Surface voxels counted through the public queries: (all, on the +x wall, within d_m). The rule of
// surfaceObservedWithin: a voxel is surface when free space lies next to it or, with a free margin q > 0, along
// an axis beyond unknown voxels only, at most min(32, ceil(sqrt(3) q d^2 / r)) of them, d being the distance
// the voxel was observed from. gap_q 0: a free 6-neighbour only.
struct Counts {
  std::size_t all = 0, near_wall = 0, within = 0;
};
Counts bruteForce(const OccupancyMap& map, double d_m, double gap_q = 0.0) {
  Counts c;
  const double r = map.resolution();
  map.forEachOccupied([&](const Eigen::Vector3d& centre, double size_m, const std::uint8_t*) {
    const int n = static_cast<int>(std::lround(size_m / r));
    const Eigen::Vector3d corner = centre - Eigen::Vector3d::Constant(0.5 * size_m);
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const Eigen::Vector3d p = corner + r * Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5);
          const double d = map.minObservedDistance(p);
          const int steps =
              std::isfinite(d) ? std::min(32, static_cast<int>(std::ceil(std::sqrt(3.0) * gap_q * d * d / r))) : 0;
          bool exposed = false;
          for (int a = 0; a < 3 && !exposed; ++a)
            for (int sg = -1; sg <= 1 && !exposed; sg += 2)
              for (int st = 1; st <= steps + 1; ++st) {
                Eigen::Vector3d q = p;
                q[a] += sg * st * r;
                const VoxelState v = map.state(q);
                exposed = v == VoxelState::kFree;
                if (v != VoxelState::kUnknown) break;
              }
          if (!exposed) continue;
          ++c.all;
          if (p.x() > 0) ++c.near_wall;
          if (d <= d_m + 5e-4) ++c.within;  // distances are kept in whole mm
        }
  });
  return c;
}

// Integrates the view from T with the simulator's depth noise, then asserts the tracked count (surface seen
// from <= 2 m) equals a full count.
void integrateAndCompareCounts(OccupancyMap& map, const BoxRoom& scene, const PinholeCamera& cam,
                               const Eigen::Isometry3d& T, std::mt19937& rng) {
  std::vector<float> d = scene.render(cam, T);
  cv::Mat depth(cam.height, cam.width, CV_32FC1, d.data());  // wraps d
  semexp_test::addQuadraticDepthNoise(depth, rng);
  map.integrate(d.data(), nullptr, cam, T);
  const OccupancyMap::SurfaceObservation full = map.surfaceObservedWithin(2.0);
  const OccupancyMap::SurfaceObservation tracked = map.trackSurfaceObservedWithin(2.0);
  ASSERT_EQ(tracked.occupied_voxels, full.occupied_voxels);
  ASSERT_EQ(tracked.within_voxels, full.within_voxels);
}

}  // namespace

TEST(SurfaceObservation, AWallSeenFrom2mAndAnotherFrom4m) {
  BackgroundMapConfig cfg;
  cfg.free_margin_quadratic_per_m = 0.0;  // every surface voxel has a free neighbour (bruteForce's definition)
  PinholeCamera cam;  // 320 x 240, f 262.5: the 2 m view's corner rays are 2.0 x 1.23 = 2.47 m long
  const BoxRoom scene = twoWalls();
  OccupancyMap map(cfg, twoWallBounds());
  EXPECT_EQ(map.surfaceObservedWithin(3.0).occupied_voxels, 0u);
  EXPECT_DOUBLE_EQ(map.surfaceObservedWithin(3.0).share(), 1.0);  // no surface: nothing left to see closer

  const Eigen::Isometry3d T_near = lookPose({0.0, 0.0, 0.0}, 0.0, 0.0);   // the +x wall from 2 m
  const Eigen::Isometry3d T_far = lookPose({0.0, 0.0, 0.0}, M_PI, 0.0);   // the -x wall from 4 m
  map.integrate(scene.render(cam, T_near).data(), nullptr, cam, T_near);
  map.integrate(scene.render(cam, T_far).data(), nullptr, cam, T_far);

  const Counts c = bruteForce(map, 3.0);
  ASSERT_GT(c.near_wall, 1000u);
  ASSERT_GT(c.all - c.near_wall, 1000u);
  // Every voxel of the near wall lies within 2.47 m, every voxel of the far wall beyond 4 m.
  const OccupancyMap::SurfaceObservation s = map.surfaceObservedWithin(3.0);
  EXPECT_EQ(s.occupied_voxels, c.all);
  EXPECT_EQ(s.within_voxels, c.near_wall);
  EXPECT_DOUBLE_EQ(s.share(), static_cast<double>(c.near_wall) / static_cast<double>(c.all));
  // The far wall's view covers 4x the near one's area: the share is about 1/5.
  EXPECT_NEAR(s.share(), 0.2, 0.03);
  // Everything is within 5.1 m (the far view's corner rays: 4.013 x 1.2585 = 5.05 m); nothing within 1.9 m.
  EXPECT_LT(map.surfaceObservedWithin(5.0).share(), 1.0);
  EXPECT_DOUBLE_EQ(map.surfaceObservedWithin(5.1).share(), 1.0);
  EXPECT_EQ(map.surfaceObservedWithin(1.9).within_voxels, 0u);
  // A threshold through the near wall's view (2.2 m) splits it as the per-voxel distances do.
  EXPECT_EQ(map.surfaceObservedWithin(2.2).within_voxels, bruteForce(map, 2.2).within);
  EXPECT_GT(map.surfaceObservedWithin(2.2).within_voxels, 0u);
  EXPECT_LT(map.surfaceObservedWithin(2.2).within_voxels, c.near_wall);

  // Flying to 1 m from the far wall and looking again makes its centre count.
  const Eigen::Isometry3d T_close = lookPose({-3.0, 0.0, 0.0}, M_PI, 0.0);
  map.integrate(scene.render(cam, T_close).data(), nullptr, cam, T_close);
  const OccupancyMap::SurfaceObservation after = map.surfaceObservedWithin(3.0);
  EXPECT_GT(after.within_voxels, s.within_voxels);
  EXPECT_EQ(after.within_voxels, bruteForce(map, 3.0).within);
}

// A thick occupied band (surface_band_m 0.12: 3-4 voxels behind each hit) puts occupied voxels behind the
// exposed layer; only the exposed layer counts as surface.
TEST(SurfaceObservation, OccupiedVoxelsBehindTheExposedLayerAreNotSurface) {
  BackgroundMapConfig cfg;
  cfg.free_margin_quadratic_per_m = 0.0;  // bruteForce counts free neighbours only
  cfg.surface_band_m = 0.12;
  PinholeCamera cam;
  const BoxRoom scene = twoWalls();
  OccupancyMap map(cfg, twoWallBounds());
  const Eigen::Isometry3d T_near = lookPose({0.0, 0.0, 0.0}, 0.0, 0.0);
  map.integrate(scene.render(cam, T_near).data(), nullptr, cam, T_near);
  std::size_t occupied = 0;
  map.forEachOccupied([&](const Eigen::Vector3d&, double size_m, const std::uint8_t*) {
    occupied += static_cast<std::size_t>(std::lround(std::pow(size_m / map.resolution(), 3)));
  });
  const Counts c = bruteForce(map, 3.0);
  ASSERT_GT(c.all, 1000u);
  EXPECT_GT(occupied, 2 * c.all);  // the band is at least 3 voxels deep; the exposed layer is one
  const OccupancyMap::SurfaceObservation s = map.surfaceObservedWithin(3.0);
  EXPECT_EQ(s.occupied_voxels, c.all);
  EXPECT_EQ(s.within_voxels, c.within);
}

// With the free margin on (free_margin_quadratic_per_m), carving stops q d^2 in front of each depth and leaves
// the voxels in between unknown: 9.7 cm (2-3 voxels) in front of the wall seen from 4 m. That wall still bounds
// observed free space across the gap, so it must count as surface, seen from 4 m, as it does without the margin.
TEST(SurfaceObservation, AFreeMarginGapDoesNotHideAFarWall) {
  PinholeCamera cam;
  const BoxRoom scene = twoWalls();
  const Eigen::Isometry3d T_near = lookPose({0.0, 0.0, 0.0}, 0.0, 0.0);
  const Eigen::Isometry3d T_far = lookPose({0.0, 0.0, 0.0}, M_PI, 0.0);
  BackgroundMapConfig plain_cfg, margin_cfg;
  plain_cfg.free_margin_quadratic_per_m = 0.0;
  margin_cfg.free_margin_quadratic_per_m = 0.006;
  OccupancyMap plain(plain_cfg, twoWallBounds()), margin(margin_cfg, twoWallBounds());
  for (OccupancyMap* map : {&plain, &margin}) {
    map->integrate(scene.render(cam, T_near).data(), nullptr, cam, T_near);
    map->integrate(scene.render(cam, T_far).data(), nullptr, cam, T_far);
  }
  // The gap is there: the far wall's face has no free neighbour with the margin.
  const Counts gap = bruteForce(margin, 3.0);
  const Counts ref = bruteForce(plain, 3.0);
  ASSERT_GT(ref.all - ref.near_wall, 1000u);
  EXPECT_LT(gap.all - gap.near_wall, (ref.all - ref.near_wall) / 10);
  // Across the gap, both walls count: about the same surface and the same share (about 1/5, as without it).
  const OccupancyMap::SurfaceObservation p = plain.surfaceObservedWithin(3.0);
  const OccupancyMap::SurfaceObservation s = margin.surfaceObservedWithin(3.0);
  EXPECT_NEAR(static_cast<double>(s.occupied_voxels), static_cast<double>(p.occupied_voxels), 0.05 * p.occupied_voxels);
  EXPECT_NEAR(s.share(), p.share(), 0.02);
  EXPECT_NEAR(s.share(), 0.2, 0.03);
  EXPECT_DOUBLE_EQ(margin.surfaceObservedWithin(5.1).share(), 1.0);
}

// The walk across the gap goes through unknown voxels only: with a thick occupied band and the margin on, the
// voxels behind the exposed layer (occupied in front, unknown behind the wall) still do not count.
TEST(SurfaceObservation, TheGapWalkStopsAtOccupiedVoxels) {
  const BackgroundMapConfig cfg = marginConfig(0.12);
  PinholeCamera cam;
  const BoxRoom scene = twoWalls();
  OccupancyMap map(cfg, twoWallBounds());
  const Eigen::Isometry3d T_far = lookPose({0.0, 0.0, 0.0}, M_PI, 0.0);
  map.integrate(scene.render(cam, T_far).data(), nullptr, cam, T_far);
  BackgroundMapConfig thin = cfg;
  thin.surface_band_m = 0.02;
  OccupancyMap one_layer(thin, twoWallBounds());
  one_layer.integrate(scene.render(cam, T_far).data(), nullptr, cam, T_far);
  // The same exposed face, whatever the band's depth behind it.
  const std::size_t face = one_layer.surfaceObservedWithin(5.1).occupied_voxels;
  ASSERT_GT(face, 1000u);
  EXPECT_NEAR(static_cast<double>(map.surfaceObservedWithin(5.1).occupied_voxels), static_cast<double>(face), 0.02 * face);
}

// The count walks inside a block and across block faces by different code paths (surfaceObservedWithin reads
// a block's own voxels directly); both must give exactly the voxels a walk through the public queries finds,
// on walls seen from 2 m and from 4 m through the margin's gap (9.7 cm at 4 m, across 8-voxel block faces).
TEST(SurfaceObservation, TheGapWalkCountsExactlyWhatAWalkThroughTheQueriesFinds) {
  const BackgroundMapConfig cfg = marginConfig(0.06);
  PinholeCamera cam;
  const BoxRoom scene = twoWalls();
  OccupancyMap map(cfg, twoWallBounds());
  for (const double yaw : {0.0, M_PI, 0.4, M_PI - 0.5}) {
    const Eigen::Isometry3d T = lookPose({0.0, 0.3, 0.1}, yaw, 0.1);
    map.integrate(scene.render(cam, T).data(), nullptr, cam, T);
  }
  const Counts ref = bruteForce(map, 3.0, cfg.free_margin_quadratic_per_m);
  const Counts one_step = bruteForce(map, 3.0);
  ASSERT_GT(ref.all, 2000u);
  ASSERT_GT(ref.all - ref.near_wall, 1000u);
  EXPECT_GT(ref.all, one_step.all + 1000u);  // the gap walk matters here: many voxels count only across it
  const OccupancyMap::SurfaceObservation s = map.surfaceObservedWithin(3.0);
  EXPECT_EQ(s.occupied_voxels, ref.all);
  EXPECT_EQ(s.within_voxels, ref.within);
}

// trackSurfaceObservedWithin counts again only the cells a frame can have changed; after every frame of a
// flight around the standard room with the simulator's depth noise it must give exactly the full count, with
// and without the free margin (whose gap walk reads cells up to 5 away along an axis), and count fewer cells
// than the map has once the first frame is in.
TEST(SurfaceObservation, TheTrackedCountEqualsAFullCountAfterEveryFrame) {
  PinholeCamera cam;
  const BoxRoom scene = semexp_test::standardRoom();
  for (const double q : {0.0, 0.006}) {
    SCOPED_TRACE(q);
    BackgroundMapConfig cfg;
    cfg.free_margin_quadratic_per_m = q;
    OccupancyMap map(cfg, scene.bounds(0.3));
    std::mt19937 rng(7);
    const Eigen::Vector3d cell_counts = (map.extentMax() - map.extentMin()) / (map.blockSize() * map.resolution());
    const std::size_t all_cells = static_cast<std::size_t>(std::lround(cell_counts.prod()));
    std::size_t most_counted = 0;  // the most cells one tracked count after the first frame counted
    for (int k = 0; k < 24; ++k) {
      const double a = 0.35 * k;
      const Eigen::Vector3d p(1.2 * std::cos(a), 0.9 * std::sin(a), 1.0 + 0.3 * std::sin(2.0 * a));
      const Eigen::Isometry3d T = lookPose(p, a + 1.3 * std::sin(0.7 * k), 0.15 * std::cos(a));
      ASSERT_NO_FATAL_FAILURE(integrateAndCompareCounts(map, scene, cam, T, rng)) << "frame " << k;
      if (k == 0) {
        EXPECT_EQ(map.lastSurfaceCellsCounted(), all_cells);  // the first count is a full one
        ASSERT_GT(map.surfaceObservedWithin(2.0).occupied_voxels, 1000u);
      } else {
        most_counted = std::max(most_counted, map.lastSurfaceCellsCounted());
      }
    }
    EXPECT_LT(most_counted, all_cells);
    // Another distance counts everything again, and agrees too.
    const OccupancyMap::SurfaceObservation full3 = map.surfaceObservedWithin(3.0);
    const OccupancyMap::SurfaceObservation tracked3 = map.trackSurfaceObservedWithin(3.0);
    EXPECT_EQ(map.lastSurfaceCellsCounted(), all_cells);
    EXPECT_EQ(tracked3.occupied_voxels, full3.occupied_voxels);
    EXPECT_EQ(tracked3.within_voxels, full3.within_voxels);
  }
}

// A wall seen from 4 m until its voxels sit at the log-odds clamp, then from 2 m: the second view changes the
// voxels' observed distances and no log-odds on the wall, and the tracked count must follow the distances.
TEST(SurfaceObservation, TheTrackedCountFollowsDistancesAloneSeenFromCloser) {
  BackgroundMapConfig cfg;
  cfg.free_margin_quadratic_per_m = 0.0;  // no gap to carve from closer: only the distances change
  PinholeCamera cam;
  const BoxRoom scene = twoWalls();
  OccupancyMap map(cfg, twoWallBounds());
  const Eigen::Isometry3d T_far = lookPose({-2.0, 0.0, 0.0}, 0.0, 0.0);   // the +x wall from 4 m
  const Eigen::Isometry3d T_near = lookPose({0.0, 0.0, 0.0}, 0.0, 0.0);   // and from 2 m
  // log_odds_occupied 0.85 a frame reaches the 3.5 clamp in 5 frames; 8 to be sure.
  for (int k = 0; k < 8; ++k) map.integrate(scene.render(cam, T_far).data(), nullptr, cam, T_far);
  const OccupancyMap::SurfaceObservation before = map.trackSurfaceObservedWithin(3.0);
  ASSERT_GT(before.occupied_voxels, 1000u);
  EXPECT_EQ(before.within_voxels, 0u);
  map.integrate(scene.render(cam, T_near).data(), nullptr, cam, T_near);
  const OccupancyMap::SurfaceObservation full = map.surfaceObservedWithin(3.0);
  const OccupancyMap::SurfaceObservation tracked = map.trackSurfaceObservedWithin(3.0);
  ASSERT_GT(full.within_voxels, 1000u);
  EXPECT_EQ(tracked.occupied_voxels, full.occupied_voxels);
  EXPECT_EQ(tracked.within_voxels, full.within_voxels);
}

// Uniform occupied cells only come from a restored map (applyBlocks of a compact snapshot). One that a view
// frees whole keeps a single distance; refined into a block later, it keeps its log-odds but its voxels lose
// that distance. Here a restored map holds a wrong 4 x 4 slab of uniform occupied cells across the middle of
// the room, and a flight sees through it: the tracked count must still equal a full count after every frame.
TEST(SurfaceObservation, TheTrackedCountFollowsARestoredMapsUniformOccupiedCells) {
  PinholeCamera cam;
  const BoxRoom scene = semexp_test::standardRoom();
  BackgroundMapConfig cfg;  // the free margin on
  OccupancyMap source(cfg, scene.bounds(0.3));
  const Eigen::Isometry3d T0 = lookPose({0.0, 0.0, 1.0}, 0.0, 0.0);
  source.integrate(scene.render(cam, T0).data(), nullptr, cam, T0);
  MapBlocksData restored = source.snapshot(true);
  const double cell_m = source.blockSize() * source.resolution();
  const Eigen::Vector3i c0 = ((Eigen::Vector3d(-0.6, -0.6, 1.1) - source.origin()) / cell_m).cast<int>();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      restored.uniform_coords.insert(restored.uniform_coords.end(), {c0.x() + i, c0.y() + j, c0.z()});
      restored.uniform_values.push_back(map_blocks::encodeMilli(3500));  // at the occupied clamp
    }
  OccupancyMap map(cfg, scene.bounds(0.3));
  ASSERT_TRUE(map.applyBlocks(restored));
  const std::size_t blocks_restored = map.blockCount();
  const OccupancyMap::SurfaceObservation first = map.trackSurfaceObservedWithin(2.0);
  ASSERT_EQ(first.occupied_voxels, map.surfaceObservedWithin(2.0).occupied_voxels);
  ASSERT_EQ(first.within_voxels, map.surfaceObservedWithin(2.0).within_voxels);
  std::mt19937 rng(11);
  for (int k = 0; k < 24; ++k) {
    const double a = 0.5 * k;
    const Eigen::Vector3d p(1.5 * std::cos(a), 1.2 * std::sin(a), 0.8 + 0.5 * std::sin(1.3 * a));
    const Eigen::Isometry3d T = lookPose(p, a + M_PI + 0.6 * std::sin(0.9 * k), 0.2 * std::sin(a));
    ASSERT_NO_FATAL_FAILURE(integrateAndCompareCounts(map, scene, cam, T, rng)) << "frame " << k;
  }
  // The flight saw through the slab: some of its cells were refined into blocks, some freed whole.
  const MapBlocksData after = map.snapshot(true);
  int slab_uniform_occupied = 0;
  for (std::size_t u = 0; u < after.uniform_values.size(); ++u) {
    const std::int32_t* c = &after.uniform_coords[3 * u];
    const bool in_slab = c[2] == c0.z() && c[0] >= c0.x() && c[0] < c0.x() + 4 && c[1] >= c0.y() && c[1] < c0.y() + 4;
    slab_uniform_occupied += in_slab && after.uniform_values[u] >= 0;
  }
  EXPECT_LT(slab_uniform_occupied, 16);
  EXPECT_GT(map.blockCount(), blocks_restored);
}

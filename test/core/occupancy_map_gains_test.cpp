// Hand-computed answers for the background map's view gains: Eq. 1 (the
// distance gain), the reducible entropy of a voxel, the gain images of
// computeGains against a hand-computed wall and against fine sampling along
// each ray, and the same images on any number of threads.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "semexp_test/box_room.hpp"
#include "semantic_exploration/core/gains.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"

using namespace semexp;
using semexp_test::BoxRoom;
using semexp_test::lookPose;
using semexp_test::wallScene;

TEST(DistanceGain, Eq1EachCase) {
  // d_node <= d_bg: already seen close enough.
  EXPECT_DOUBLE_EQ(distanceGain(2.0, 1.0, 3.0, 10.0), 0.0);
  EXPECT_DOUBLE_EQ(distanceGain(3.0, 1.0, 3.0, 10.0), 0.0);
  // d_node <= d_exp: the candidate would not see it closer.
  EXPECT_DOUBLE_EQ(distanceGain(5.0, 6.0, 3.0, 10.0), 0.0);
  EXPECT_DOUBLE_EQ(distanceGain(5.0, 5.0, 3.0, 10.0), 0.0);
  // otherwise (d_node - max(d_exp, d_bg)) / d_max
  EXPECT_DOUBLE_EQ(distanceGain(6.0, 2.0, 3.0, 10.0), 0.3);  // d_exp < d_bg
  EXPECT_DOUBLE_EQ(distanceGain(8.0, 5.0, 3.0, 10.0), 0.3);  // d_exp > d_bg
}

TEST(Entropy, HalfAndClamped) {
  EXPECT_DOUBLE_EQ(binaryEntropy(0.5), 1.0);
  EXPECT_DOUBLE_EQ(logOddsEntropy(0.0), 1.0);
  // clamped free voxel, l = -2: p = 1/(1+e^2) = 0.119203;
  // H = 0.119203*3.068520 + 0.880797*0.183118 = 0.365777 + 0.161290 = 0.527066 bits
  EXPECT_NEAR(logOddsEntropy(-2.0), 0.527066, 2e-6);
  // clamped occupied voxel, l = 3.5: p = 0.970688; H = 0.970688*0.042921 + 0.029312*5.092347 = 0.191...
  EXPECT_NEAR(logOddsEntropy(3.5), 0.970688 * 0.0429208 + 0.0293122 * 5.0923467, 1e-4);
}

TEST(Entropy, ReducibleIsZeroAtTheClampAndOneWhenUnknown) {
  // OctoMap's clamp [-2, 3.5]: H(-2) = 0.527066, H(3.5) = 0.190931 bits.
  EXPECT_DOUBLE_EQ(reducibleEntropy(0.0, -2.0, 3.5), 1.0);
  EXPECT_NEAR(reducibleEntropy(-2.0, -2.0, 3.5), 0.0, 1e-12);
  EXPECT_NEAR(reducibleEntropy(3.5, -2.0, 3.5), 0.0, 1e-12);
  // one free update, l = -0.4: p = 0.401312, H = 0.971713; (0.971713 - 0.527065) / (1 - 0.527065) = 0.940189
  EXPECT_NEAR(reducibleEntropy(-0.4, -2.0, 3.5), 0.940189, 2e-6);
  // two, l = -0.8: p = 0.310026, H = 0.893203; (0.893203 - 0.527065) / 0.472935 = 0.774182
  EXPECT_NEAR(reducibleEntropy(-0.8, -2.0, 3.5), 0.774182, 2e-6);
  // one occupied update, l = 0.85: p = 0.700567, H = 0.880597; (0.880597 - 0.190931) / 0.809069 = 0.852419
  EXPECT_NEAR(reducibleEntropy(0.85, -2.0, 3.5), 0.852419, 2e-6);
  // beyond the clamp (another map's values) still 0, never negative
  EXPECT_DOUBLE_EQ(reducibleEntropy(-3.0, -2.0, 3.5), 0.0);
}

TEST(Gains, EntropyOfUnknownAndOfClampedFreeSpace) {
  BackgroundMapConfig cfg;
  cfg.resolution_m = 0.2;  // large voxels: a big map stays small
  Bounds b;
  b.min_m = {-12, -12, -6};
  b.max_m = {12, 12, 6};
  OccupancyMap map(cfg, b);
  SphericalGrid grid;
  GainSettings gs;  // d_min 0.1, d_max 10
  auto g = map.computeGains({Eigen::Vector3d(0.1, 0.1, 0.1)}, grid, gs);
  ASSERT_EQ(g.size(), 1u);
  for (int i = 0; i < grid.width * grid.height; ++i) {
    EXPECT_NEAR(g[0].entropy[i], 1.0, 1e-5);   // all unknown: maximal entropy
    EXPECT_FLOAT_EQ(g[0].hit_depth_m[i], 10.f);  // nothing hit
    EXPECT_FLOAT_EQ(g[0].distance[i], 0.f);
  }
  // Everything free at the clamp (log-odds -2.0 = -20 tenths in the message encoding): nothing left to learn.
  MapBlocksData all = map.snapshot();
  all.coords.clear();
  all.payload.clear();
  const Eigen::Vector3i nb = ((map.extentMax() - map.extentMin()) / (cfg.resolution_m * cfg.block_size)).array().round().cast<int>();
  for (int z = 0; z < nb.z(); ++z)
    for (int y = 0; y < nb.y(); ++y)
      for (int x = 0; x < nb.x(); ++x) {
        all.coords.insert(all.coords.end(), {x, y, z});
        all.payload.insert(all.payload.end(), cfg.block_size * cfg.block_size * cfg.block_size, static_cast<std::int8_t>(-20));
      }
  ASSERT_TRUE(map.applyBlocks(all));
  g = map.computeGains({Eigen::Vector3d(0.1, 0.1, 0.1)}, grid, gs);
  for (int i = 0; i < grid.width * grid.height; ++i) EXPECT_NEAR(g[0].entropy[i], 0.0, 1e-6);
  // Free after two updates (-0.8, -8 tenths): reducible entropy 0.774182 per unit length.
  for (auto& v : all.payload) v = -8;
  ASSERT_TRUE(map.applyBlocks(all));
  g = map.computeGains({Eigen::Vector3d(0.1, 0.1, 0.1)}, grid, gs);
  for (int i = 0; i < grid.width * grid.height; ++i) EXPECT_NEAR(g[0].entropy[i], 0.774182, 1e-4);
  // A per-ray maximum depth of 5.05 m stops accumulation half way.
  std::vector<float> maxd(grid.width * grid.height, 5.05f);
  g = map.computeGains({Eigen::Vector3d(0.1, 0.1, 0.1)}, grid, gs, maxd);
  for (int i = 0; i < grid.width * grid.height; ++i) EXPECT_NEAR(g[0].entropy[i], 0.774182 * 0.5, 1e-4);
}

TEST(Gains, BackgroundDistanceGainOnASingleWall) {
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  const BoxRoom scene = wallScene();
  Bounds b;
  b.min_m = {-7.0, -2.0, -1.6};
  b.max_m = {3.0, 2.0, 1.6};
  OccupancyMap map(cfg, b);
  const Eigen::Isometry3d T = lookPose({-4.0, 0.0, 0.0}, 0.0, 0.0);  // 6.013 m from the wall
  map.integrate(scene.render(cam, T).data(), nullptr, cam, T);
  SphericalGrid grid;
  GainSettings gs;
  // Column 18 looks at azimuth +5 degrees, row 4 at elevation +4.3 degrees (both towards the wall).
  const int u = 18, v = 4;
  auto check = [&](const Eigen::Vector3d& pos, double expected, double tol) {
    auto g = map.computeGains({pos}, grid, gs);
    const int i = v * grid.width + u;
    const RaycastHit h = map.raycast(pos, grid.direction(u, v), gs.d_max_m);
    ASSERT_TRUE(h.hit);
    EXPECT_NEAR(g[0].hit_depth_m[i], h.distance_m, 1e-4);
    // same formula from the map's own numbers, and the hand value
    const double d_node = map.minObservedDistance(h.voxel_centre_W);
    const double d_exp = (h.voxel_centre_W - pos).norm();
    EXPECT_NEAR(g[0].distance[i], distanceGain(d_node, d_exp, gs.d_desired_m, gs.d_max_m), 1e-5);
    EXPECT_NEAR(g[0].distance[i], expected, tol);
  };
  // The hit voxel was observed from ~6.06 m (the camera at x=-4, ray 5 deg off axis).
  // From x = -1 (d_exp ~3.04 > d_bg): (6.06 - 3.04) / 10 ~ 0.30
  check({-1.0, 0.0, 0.0}, 0.30, 0.01);
  // From x = 0 (d_exp ~2.03 < d_bg = 3): (6.06 - 3) / 10 ~ 0.306
  check({0.0, 0.0, 0.0}, 0.306, 0.01);
  // From x = -6.5 (farther than it was observed from): 0
  check({-6.5, 0.0, 0.0}, 0.0, 1e-9);
  // After a close look from x = 0.5 (~1.5 m < d_bg): 0 from anywhere
  const Eigen::Isometry3d T2 = lookPose({0.5, 0.0, 0.0}, 0.0, 0.0);
  map.integrate(scene.render(cam, T2).data(), nullptr, cam, T2);
  check({-1.0, 0.0, 0.0}, 0.0, 1e-9);
}

TEST(OccupancyMap, RaycastAndEntropyGainMatchFineSampling) {
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  const BoxRoom scene = semexp_test::standardRoom();
  const Bounds b = scene.bounds(0.2);
  OccupancyMap map(cfg, b);
  for (int i = 0; i < 6; ++i) {
    const Eigen::Isometry3d T = lookPose({-1.0 + 0.4 * i, 0.2, 1.3}, 1.1 * i, 0.15);
    map.integrate(scene.render(cam, T).data(), nullptr, cam, T);
  }
  SphericalGrid grid;
  GainSettings gs;
  gs.d_max_m = 4.0;  // stay mostly inside the map
  const std::vector<Eigen::Vector3d> pos = {{0.1, 0.2, 1.2}, {-1.5, -0.5, 1.6}};
  const auto g = map.computeGains(pos, grid, gs);
  const double step = cfg.resolution_m / 50.0;
  double worst_hit = 0.0, worst_ent = 0.0;
  for (std::size_t j = 0; j < pos.size(); ++j)
    for (int v = 0; v < grid.height; ++v)
      for (int u = 0; u < grid.width; ++u) {
        const Eigen::Vector3d d = grid.direction(u, v);
        double t = 0.5 * step, ent = 0.0, hit = gs.d_max_m;
        for (; t < gs.d_max_m; t += step) {
          const Eigen::Vector3d p = pos[j] + t * d;
          double l;
          const VoxelState s = map.state(p);
          if (s == VoxelState::kOccupied) {
            hit = t;
            break;
          }
          if ((p.array() < map.extentMin().array()).any() || (p.array() >= map.extentMax().array()).any()) break;  // left the map
          const double h = s == VoxelState::kUnknown
                               ? 1.0
                               : (map.logOdds(p, l) ? reducibleEntropy(l, cfg.log_odds_min, cfg.log_odds_max) : 1.0);
          if (t >= gs.d_min_m) ent += h * step;
        }
        const int i = v * grid.width + u;
        worst_hit = std::max(worst_hit, std::abs(hit - g[j].hit_depth_m[i]));
        worst_ent = std::max(worst_ent, std::abs(ent / (gs.d_max_m - gs.d_min_m) - g[j].entropy[i]));
        const RaycastHit h = map.raycast(pos[j], d, gs.d_max_m);
        EXPECT_EQ(h.hit, hit < gs.d_max_m);
        if (h.hit) {
          EXPECT_NEAR(h.distance_m, hit, 2 * step);
        }
      }
  EXPECT_LT(worst_hit, 2 * step);
  EXPECT_LT(worst_ent, 2e-3);
}

TEST(OccupancyMap, GainsAreTheSameOnAnyNumberOfThreads) {
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  const BoxRoom scene = semexp_test::standardRoom();
  OccupancyMap map(cfg, scene.bounds(0.2));
  for (int i = 0; i < 4; ++i) {
    const Eigen::Isometry3d T = lookPose({-1.0 + 0.5 * i, 0.2, 1.3}, 1.6 * i, 0.1);
    map.integrate(scene.render(cam, T).data(), nullptr, cam, T);
  }
  SphericalGrid grid;
  GainSettings gs;
  // Positions in the part the frames saw and in the part they did not; more positions than threads and fewer.
  const std::vector<Eigen::Vector3d> pos = {{0.1, 0.2, 1.2}, {-1.5, -0.5, 1.6}, {1.0, 1.0, 0.8}, {0.0, -1.0, 2.0},
                                            {-0.5, 0.5, 1.0}};
  gs.threads = 1;
  const auto one = map.computeGains(pos, grid, gs);
  double sum = 0.0;
  for (const GainImages& g : one)
    for (std::size_t i = 0; i < g.entropy.size(); ++i) sum += g.entropy[i] + g.distance[i];
  ASSERT_GT(sum, 0.0);  // the comparison below compares something
  for (int threads : {2, 3, 8}) {
    gs.threads = threads;
    const auto many = map.computeGains(pos, grid, gs);
    ASSERT_EQ(many.size(), one.size());
    for (std::size_t j = 0; j < pos.size(); ++j) {
      EXPECT_EQ(many[j].entropy, one[j].entropy) << threads << " threads, position " << j;
      EXPECT_EQ(many[j].distance, one[j].distance) << threads << " threads, position " << j;
      EXPECT_EQ(many[j].hit_depth_m, one[j].hit_depth_m) << threads << " threads, position " << j;
    }
  }
  gs.threads = 0;
  EXPECT_THROW(map.computeGains(pos, grid, gs), std::invalid_argument);
}

TEST(OccupancyMap, GainThreadsBelowOneAreRefusedByName) {
  BackgroundMapConfig cfg;
  cfg.gain_threads = 0;
  try {
    cfg.validate();
    FAIL() << "gain_threads 0 accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("background_map/gain_threads"), std::string::npos) << e.what();
  }
}

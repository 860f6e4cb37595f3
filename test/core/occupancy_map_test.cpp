// Hand-computed answers for the background map: frontiers, colour and
// distance fusion, sphere queries, raycasts, bad input, save/load, the
// OctoMap export and the margins that keep noisy depth from carving. Gains:
// occupancy_map_gains_test.cpp.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

#include "semexp_test/box_room.hpp"
#include "semantic_exploration/core/marching_cubes.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"

using namespace semexp;
using semexp_test::BoxRoom;
using semexp_test::lookPose;
using semexp_test::wallScene;

namespace {

std::string tempPath(const std::string& name) {
  const char* d = std::getenv("TMPDIR");
  return std::string(d ? d : "/tmp") + "/semexp_occ_" + std::to_string(::getpid()) + "_" + name;
}

Bounds smallBounds() {
  Bounds b;
  b.min_m = {-4.0, -2.0, -1.6};
  b.max_m = {3.0, 2.0, 1.6};
  return b;
}

std::vector<std::uint8_t> constantRgb(const PinholeCamera& cam, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  std::vector<std::uint8_t> c(static_cast<std::size_t>(cam.width) * cam.height * 3);
  for (std::size_t i = 0; i < c.size(); i += 3) c[i] = r, c[i + 1] = g, c[i + 2] = b;
  return c;
}

std::string readFile(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

}  // namespace

TEST(OccupancyMap, StatesAndRaycastOnAWall) {
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  const BoxRoom scene = wallScene();
  OccupancyMap map(cfg, smallBounds());
  const Eigen::Isometry3d T = lookPose({0.0, 0.0, 0.0}, 0.0, 0.0);
  const IntegrationStats st = map.integrate(scene.render(cam, T).data(), nullptr, cam, T);
  EXPECT_EQ(st.invalid_pixels, 0u);
  EXPECT_EQ(map.state({1.0, 0.1, 0.1}), VoxelState::kFree);
  EXPECT_EQ(map.state({2.02, 0.1, 0.1}), VoxelState::kOccupied);  // voxel [2.00, 2.04) holds the wall
  EXPECT_EQ(map.state({2.5, 0.1, 0.1}), VoxelState::kUnknown);   // behind the wall
  EXPECT_EQ(map.state({-1.0, 0.1, 0.1}), VoxelState::kUnknown);  // behind the camera
  EXPECT_EQ(map.state({50.0, 0.0, 0.0}), VoxelState::kUnknown);  // outside the map
  double l = 0;
  ASSERT_TRUE(map.logOdds({1.0, 0.1, 0.1}, l));
  EXPECT_NEAR(l, cfg.log_odds_free, 1e-3);
  ASSERT_TRUE(map.logOdds({2.02, 0.1, 0.1}, l));
  EXPECT_NEAR(l, cfg.log_odds_occupied, 1e-3);
  const RaycastHit h = map.raycast({0.0, 0.01, 0.01}, {1.0, 0.0, 0.0}, 10.0);
  ASSERT_TRUE(h.hit);
  EXPECT_EQ(h.state, VoxelState::kOccupied);
  EXPECT_NEAR(h.distance_m, 2.0, 1e-6);
  EXPECT_NEAR(h.voxel_centre_W.x(), 2.02, 1e-9);
  // Stops on unknown space when asked (behind the camera).
  const RaycastHit hu = map.raycast({0.0, 0.01, 0.01}, {-1.0, 0.0, 0.0}, 10.0, true);
  ASSERT_TRUE(hu.hit);
  EXPECT_EQ(hu.state, VoxelState::kUnknown);
  EXPECT_LT(hu.distance_m, 0.1);
  EXPECT_FALSE(map.raycast({0.0, 0.01, 0.01}, {-1.0, 0.0, 0.0}, 10.0).hit);
  EXPECT_GT(map.freeVolume(), 1.0);
  EXPECT_GT(map.occupiedVolume(), 0.0);
  EXPECT_GT(map.memoryBytes(), 0u);
}

TEST(OccupancyMap, BadDepthIsCountedAndCarvesNothing) {
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  OccupancyMap map(cfg, smallBounds());
  std::vector<float> depth(cam.width * cam.height, 0.f);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float bad[] = {0.f, nan, inf, -inf, -1.f, 0.05f /* < d_min */, 20.f /* > d_max */};
  for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = bad[i % 7];
  const Eigen::Isometry3d T = lookPose({0.0, 0.0, 0.0}, 0.0, 0.0);
  const IntegrationStats st = map.integrate(depth.data(), nullptr, cam, T);
  EXPECT_EQ(st.invalid_pixels, depth.size());
  EXPECT_EQ(map.exploredVolume(), 0.0);
  EXPECT_EQ(map.blockCount(), 0u);
  // OpenCV input: wrong size and wrong type are rejected, 16UC1 millimetres accepted.
  cv::Mat small(10, 10, CV_32FC1, cv::Scalar(1.0));
  EXPECT_THROW(map.integrate(small, cv::Mat(), cam, T), std::invalid_argument);
  cv::Mat wrong(cam.height, cam.width, CV_8UC1, cv::Scalar(1));
  EXPECT_THROW(map.integrate(wrong, cv::Mat(), cam, T), std::invalid_argument);
  cv::Mat mm(cam.height, cam.width, CV_16UC1, cv::Scalar(1500));
  const IntegrationStats st2 = map.integrate(mm, cv::Mat(), cam, T);
  EXPECT_EQ(st2.invalid_pixels, 0u);
  EXPECT_EQ(map.state({1.0, 0.0, 0.0}), VoxelState::kFree);
  EXPECT_EQ(map.state({1.5, 0.0, 0.02}), VoxelState::kOccupied);  // voxel [1.48, 1.52)
}

TEST(OccupancyMap, ColourAndMinDistanceFuseOverTwoObservations) {
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  const BoxRoom scene = wallScene();
  OccupancyMap map(cfg, smallBounds());
  const Eigen::Vector3d voxel(2.02, 0.02, 0.02);  // voxel [2.00,2.04) x [0,0.04) x [0,0.04) holds the wall
  const Eigen::Isometry3d T1 = lookPose({0.0, 0.0, 0.0}, 0.0, 0.0);
  const Eigen::Isometry3d T2 = lookPose({1.0, 0.0, 0.0}, 0.0, 0.0);
  auto red = constantRgb(cam, 200, 0, 0), blue = constantRgb(cam, 0, 0, 100);
  map.integrate(scene.render(cam, T1).data(), red.data(), cam, T1);
  std::uint8_t c[3];
  ASSERT_TRUE(map.colour(voxel, c));
  EXPECT_EQ(c[0], 200);
  EXPECT_EQ(c[2], 0);
  EXPECT_NEAR(map.minObservedDistance(voxel), std::sqrt(2.02 * 2.02 + 2 * 0.02 * 0.02), 1e-3);
  map.integrate(scene.render(cam, T2).data(), blue.data(), cam, T2);
  ASSERT_TRUE(map.colour(voxel, c));
  EXPECT_EQ(c[0], 100);  // (200 * 1 + 0) / 2
  EXPECT_EQ(c[1], 0);
  EXPECT_EQ(c[2], 50);  // (0 * 1 + 100) / 2
  EXPECT_NEAR(map.minObservedDistance(voxel), std::sqrt(1.02 * 1.02 + 2 * 0.02 * 0.02), 1e-3);
  // A farther third look does not raise it.
  map.integrate(scene.render(cam, T1).data(), red.data(), cam, T1);
  EXPECT_NEAR(map.minObservedDistance(voxel), std::sqrt(1.02 * 1.02 + 2 * 0.02 * 0.02), 1e-3);
}

TEST(OccupancyMap, SphereFreeNearAWall) {
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  const BoxRoom scene = wallScene();
  OccupancyMap map(cfg, smallBounds());
  for (int i = 0; i < 6; ++i) {
    const Eigen::Isometry3d T = lookPose({-0.3 * i, 0.0, 0.0}, 0.0, 0.0);
    map.integrate(scene.render(cam, T).data(), nullptr, cam, T);
  }
  // Centre 0.5 m in front of the first occupied voxel face (x = 2.00).
  const Eigen::Vector3d c(1.5, 0.02, 0.02);
  EXPECT_TRUE(map.isSphereFree(c, 0.0));
  EXPECT_TRUE(map.isSphereFree(c, 0.1));
  EXPECT_TRUE(map.isSphereFree(c, 0.3));
  EXPECT_TRUE(map.isSphereFree(c, 0.49));
  EXPECT_FALSE(map.isSphereFree(c, 0.51));  // reaches into the wall voxels
  EXPECT_FALSE(map.isSphereFree(c, 1.0));
  EXPECT_FALSE(map.isSphereFree({2.5, 0.0, 0.0}, 0.1));   // unknown behind the wall
  EXPECT_FALSE(map.isSphereFree({1.5, 0.0, 1.55}, 0.1));  // leaves the map
}

TEST(OccupancyMap, FrontierAppearsAndDisappears) {
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  const BoxRoom scene = wallScene();
  OccupancyMap map(cfg, smallBounds());
  const Eigen::Isometry3d T = lookPose({-1.0, 0.0, 0.0}, 0.0, 0.0);  // image right = world -y
  std::vector<float> depth = scene.render(cam, T);
  std::vector<float> half = depth;
  for (int v = 0; v < cam.height; ++v)
    for (int u = cam.width / 2; u < cam.width; ++u) half[v * cam.width + u] = 0.f;  // world y < 0 unseen
  auto near_cut = [&] {
    int n = 0;
    map.forEachFrontier([&](const Eigen::Vector3d& p, double) {
      n += p.x() > 0.5 && p.x() < 1.5 && std::abs(p.y()) < 0.1 && std::abs(p.z()) < 0.3;
    });
    return n;
  };
  map.integrate(half.data(), nullptr, cam, T);
  map.updateFrontiers();
  EXPECT_GT(near_cut(), 20);  // free (y > 0) next to unknown (y < 0)
  const Eigen::Vector3d p(1.0, 0.06, 0.02);
  EXPECT_EQ(map.state(p), VoxelState::kFree);
  EXPECT_EQ(map.state({1.0, -0.3, 0.02}), VoxelState::kUnknown);
  map.integrate(depth.data(), nullptr, cam, T);
  map.updateFrontiers();
  EXPECT_EQ(near_cut(), 0);  // the unknown side was observed
  EXPECT_GT(map.frontierCount(), 0u);  // the frustum's outer border is still a frontier
  // Every reported frontier is free with an unknown neighbour.
  const double r = cfg.resolution_m;
  map.forEachFrontier([&](const Eigen::Vector3d& q, double size) {
    ASSERT_EQ(map.state(q), VoxelState::kFree);
    bool unk = false;
    const int k = static_cast<int>(std::lround(size / r));  // voxels per edge of the leaf
    for (int a = 0; a < 3; ++a)
      for (int s = -1; s <= 1; s += 2)
        for (int i = 0; i < k; ++i)
          for (int j = 0; j < k; ++j) {  // every voxel just across this face
            Eigen::Vector3d n = q;
            n[a] += s * 0.5 * (size + r);
            n[(a + 1) % 3] += (i - 0.5 * (k - 1)) * r;
            n[(a + 2) % 3] += (j - 0.5 * (k - 1)) * r;
            unk = unk || map.state(n) == VoxelState::kUnknown;
          }
    EXPECT_TRUE(unk) << q.transpose() << " size " << size;
  });
}

// A version-1 file (written before free_margin_quadratic_per_m existed) loads as a map without a free margin,
// whatever the default is now. Made from a version-2 file: version 1 at byte 8, and the margin's 8 bytes at
// byte 80 (after the magic, the version, resolution_m, block_size and seven doubles) removed.
TEST(OccupancyMap, AVersion1FileLoadsWithoutAFreeMargin) {
  BackgroundMapConfig cfg;
  cfg.free_margin_quadratic_per_m = 0.0;
  PinholeCamera cam;
  const BoxRoom scene = semexp_test::standardRoom();
  OccupancyMap map(cfg, scene.bounds(0.2));
  const Eigen::Isometry3d T = lookPose({0.3, 0.2, 1.2}, 0.9, 0.2);
  map.integrate(scene.render(cam, T).data(), nullptr, cam, T);
  const std::string v2 = tempPath("v2.semexpmap"), v1 = tempPath("v1.semexpmap"), again = tempPath("again.semexpmap");
  map.save(v2);
  std::string bytes = readFile(v2);
  const std::uint32_t one = 1;
  std::memcpy(&bytes[8], &one, sizeof(one));
  bytes.erase(80, 8);
  {
    std::ofstream out(v1, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  const OccupancyMap loaded = OccupancyMap::load(v1);
  EXPECT_EQ(loaded.config().free_margin_quadratic_per_m, 0.0);
  loaded.save(again);
  EXPECT_TRUE(readFile(again) == readFile(v2));  // saved as version 2, the same map
}

TEST(OccupancyMap, SaveLoadRoundTripIsBitIdentical) {
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  const BoxRoom scene = semexp_test::standardRoom();
  const Bounds b = scene.bounds(0.2);
  OccupancyMap map(cfg, b);
  auto rgb = constantRgb(cam, 10, 200, 30);
  for (int i = 0; i < 5; ++i) {
    const Eigen::Isometry3d T = lookPose({0.3 * i, 0.2, 1.2}, 0.9 * i, 0.2);
    map.integrate(scene.render(cam, T).data(), rgb.data(), cam, T);
    map.updateFrontiers();
  }
  map.takeUpdate();
  const std::string p1 = tempPath("a.semexpmap"), p2 = tempPath("b.semexpmap");
  map.save(p1);
  OccupancyMap loaded = OccupancyMap::load(p1);
  loaded.save(p2);
  const std::string a = readFile(p1), bb = readFile(p2);
  EXPECT_GT(a.size(), 1000u);
  EXPECT_TRUE(a == bb);
  EXPECT_EQ(loaded.frontierCount(), map.frontierCount());
  EXPECT_EQ(loaded.exploredVolume(), map.exploredVolume());
  EXPECT_EQ(loaded.lastSequence(), map.lastSequence());
  const MapBlocksData s1 = map.snapshot(), s2 = loaded.snapshot();
  EXPECT_EQ(s1.coords, s2.coords);
  EXPECT_EQ(s1.payload, s2.payload);
  std::uint8_t c[3], c0[3];
  std::size_t coloured = 0;
  map.forEachOccupied([&](const Eigen::Vector3d& q, double, const std::uint8_t*) {
    const bool has = map.colour(q, c0);
    ASSERT_EQ(loaded.colour(q, c), has);
    if (has) {
      EXPECT_EQ(c[1], c0[1]);
      EXPECT_EQ(c0[1], 200);
      ++coloured;
    }
    EXPECT_EQ(loaded.minObservedDistance(q), map.minObservedDistance(q));
  });
  EXPECT_GT(coloured, 1000u);
  // The OctoMap export reads back with the same occupied voxels.
  const std::string bt = tempPath("c.bt");
  map.exportOctomap(bt);
  octomap::OcTree tree(bt);
  std::size_t checked = 0, same = 0;
  map.forEachOccupied([&](const Eigen::Vector3d& q, double, const std::uint8_t*) {
    const octomap::OcTreeNode* n = tree.search(q.x(), q.y(), q.z());
    ++checked;
    same += n && tree.isNodeOccupied(n);
  });
  EXPECT_EQ(same, checked);
  // The occupied point cloud holds exactly the occupied leaves, with colour.
  const std::string ply = tempPath("d.ply");
  map.exportOccupiedPly(ply);
  Mesh cloud;
  ASSERT_TRUE(readPly(ply, cloud));
  EXPECT_EQ(cloud.vertices_W.size(), checked);
  EXPECT_TRUE(cloud.triangles.empty());
  std::size_t green = 0;
  for (std::size_t i = 0; i < cloud.vertices_W.size(); ++i) {
    EXPECT_EQ(map.state(cloud.vertices_W[i].cast<double>()), VoxelState::kOccupied);
    green += cloud.colours[i][1] == 200;
  }
  EXPECT_EQ(green, coloured);
  std::remove(ply.c_str());
  std::remove(p1.c_str());
  std::remove(p2.c_str());
  std::remove(bt.c_str());
}

TEST(OccupancyMap, IncrementalFrontiersEqualABruteForceScan) {
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  const BoxRoom scene = semexp_test::standardRoom();
  const Bounds b = scene.bounds(0.2);
  OccupancyMap map(cfg, b);
  for (int i = 0; i < 8; ++i) {
    const Eigen::Isometry3d T = lookPose({-1.5 + 0.4 * i, 0.3 * std::sin(i), 1.0 + 0.1 * i}, 0.8 * i, 0.1 * (i % 3));
    map.integrate(scene.render(cam, T).data(), nullptr, cam, T);
    map.updateFrontiers();
  }
  const double r = cfg.resolution_m;
  const Eigen::Vector3d lo = map.extentMin();
  const Eigen::Vector3i n = ((map.extentMax() - lo) / r).array().round().cast<int>();
  auto st = [&](int x, int y, int z) {
    if (x < 0 || y < 0 || z < 0 || x >= n.x() || y >= n.y() || z >= n.z()) return VoxelState::kFree;  // outside: not unknown
    return map.state(lo + (Eigen::Vector3d(x, y, z) + Eigen::Vector3d::Constant(0.5)) * r);
  };
  // Voxel-level truth.
  std::vector<std::uint8_t> truth(static_cast<std::size_t>(n.prod()), 0);
  std::size_t n_truth = 0;
  for (int z = 0; z < n.z(); ++z)
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) {
        if (st(x, y, z) != VoxelState::kFree) continue;
        const bool f = st(x + 1, y, z) == VoxelState::kUnknown || st(x - 1, y, z) == VoxelState::kUnknown ||
                       st(x, y + 1, z) == VoxelState::kUnknown || st(x, y - 1, z) == VoxelState::kUnknown ||
                       st(x, y, z + 1) == VoxelState::kUnknown || st(x, y, z - 1) == VoxelState::kUnknown;
        truth[x + n.x() * (y + n.y() * z)] = f;
        n_truth += f;
      }
  // Every reported leaf holds a true frontier voxel; every true frontier voxel lies in a reported leaf.
  std::vector<std::uint8_t> covered(truth.size(), 0);
  std::size_t empty_leaves = 0;
  map.forEachFrontier([&](const Eigen::Vector3d& c, double size) {
    const int k = static_cast<int>(std::lround(size / r));
    const Eigen::Vector3i v0 = ((c - lo) / r - Eigen::Vector3d::Constant(0.5 * k)).array().round().cast<int>();
    bool any = false;
    for (int z = v0.z(); z < v0.z() + k; ++z)
      for (int y = v0.y(); y < v0.y() + k; ++y)
        for (int x = v0.x(); x < v0.x() + k; ++x) {
          const std::size_t i = x + n.x() * (y + n.y() * z);
          covered[i] = 1;
          any = any || truth[i];
        }
    empty_leaves += !any;
  });
  std::size_t missed = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) missed += truth[i] && !covered[i];
  EXPECT_GT(n_truth, 1000u);
  EXPECT_EQ(missed, 0u);
  EXPECT_EQ(empty_leaves, 0u);
}

TEST(OccupancyMap, NoiseMarginKeepsVoxelsInFrontOfTheSurfaceFromBeingCarved) {
  PinholeCamera cam;
  const BoxRoom scene = wallScene();
  const Eigen::Isometry3d T = lookPose({0.0, 0.0, 0.0}, 0.0, 0.0);
  const std::vector<float> depth = scene.render(cam, T);
  const Eigen::Vector3d in_front(1.94, 0.02, 0.02);  // voxel [1.92, 1.96): 5.3 to 9.3 cm before the wall at 2.013
  BackgroundMapConfig plain;
  plain.free_margin_quadratic_per_m = 0.0;  // carves up to the measured depth
  OccupancyMap a(plain, smallBounds());
  a.integrate(depth.data(), nullptr, cam, T);
  EXPECT_EQ(a.state(in_front), VoxelState::kFree);
  BackgroundMapConfig noisy;
  noisy.surface_front_quadratic_per_m = 0.02;  // margin 0.02 * 2.013^2 = 8.1 cm
  OccupancyMap b(noisy, smallBounds());
  b.integrate(depth.data(), nullptr, cam, T);
  EXPECT_EQ(b.state(in_front), VoxelState::kOccupied);
  EXPECT_EQ(b.state({1.86, 0.02, 0.02}), VoxelState::kFree);  // 13 cm before the wall: beyond the margin
  EXPECT_EQ(b.state({1.0, 0.02, 0.02}), VoxelState::kFree);
}

// A frame whose depth lies 6 cm behind the wall at 2.013 m (noise), on the
// 4 cm grid of smallBounds: without a free margin it carves the voxel
// holding the wall's face, [2.00, 2.04), free; with a margin of
// 0.02 * 2.073^2 = 8.6 cm free carving stops at 1.987 m and the voxels from
// there to the measured surface keep their state.
TEST(OccupancyMap, FreeMarginKeepsNoisyDepthFromCarvingThroughAWall) {
  PinholeCamera cam;
  const BoxRoom scene = wallScene();
  const Eigen::Isometry3d T = lookPose({0.0, 0.0, 0.0}, 0.0, 0.0);
  std::vector<float> depth = scene.render(cam, T);
  for (float& d : depth)
    if (d > 0.f) d += 0.06f;
  const Eigen::Vector3d face(2.02, 0.02, 0.02);      // voxel [2.00, 2.04): the wall's face, 2.013
  const Eigen::Vector3d measured(2.06, 0.02, 0.02);  // voxel [2.04, 2.08): the measured depth, 2.073
  const Eigen::Vector3d before(1.98, 0.02, 0.02);    // voxel [1.96, 2.00): before the free limit 1.987
  BackgroundMapConfig plain;
  plain.free_margin_quadratic_per_m = 0.0;  // carves up to the measured depth
  OccupancyMap a(plain, smallBounds());
  a.integrate(depth.data(), nullptr, cam, T);
  EXPECT_EQ(a.state(face), VoxelState::kFree);  // carved through the wall's surface
  EXPECT_EQ(a.state(measured), VoxelState::kOccupied);
  BackgroundMapConfig margin;
  margin.free_margin_quadratic_per_m = 0.02;
  OccupancyMap b(margin, smallBounds());
  b.integrate(depth.data(), nullptr, cam, T);
  EXPECT_EQ(b.state(face), VoxelState::kUnknown);
  EXPECT_EQ(b.state(measured), VoxelState::kOccupied);
  EXPECT_EQ(b.state(before), VoxelState::kFree);
  // A margin not wider than the surface's front changes nothing: that band is surface.
  BackgroundMapConfig both = margin;
  both.surface_front_quadratic_per_m = 0.02;
  OccupancyMap c(both, smallBounds());
  c.integrate(depth.data(), nullptr, cam, T);
  EXPECT_EQ(c.state(face), VoxelState::kOccupied);
  EXPECT_EQ(c.state(before), VoxelState::kFree);
}

TEST(OccupancyMap, FreeSphereAtTheStartMarksOnlyUnknownVoxels) {
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  const BoxRoom scene = wallScene();
  OccupancyMap map(cfg, smallBounds());
  const Eigen::Isometry3d T = lookPose({1.7, 0.0, 0.0}, 0.0, 0.0);  // 0.31 m from the wall
  map.integrate(scene.render(cam, T).data(), nullptr, cam, T);
  EXPECT_EQ(map.state({1.7, 0.0, 0.0}), VoxelState::kUnknown);  // the camera cannot see itself
  EXPECT_FALSE(map.isSphereFree({1.7, 0.0, 0.0}, 0.125));
  map.markFreeSphere({1.7, 0.0, 0.0}, 0.5);
  map.updateFrontiers();
  EXPECT_TRUE(map.isSphereFree({1.7, 0.0, 0.0}, 0.125));
  EXPECT_TRUE(map.isSphereFree({1.5, 0.0, 0.0}, 0.25));
  EXPECT_EQ(map.state({2.02, 0.02, 0.02}), VoxelState::kOccupied);  // observed wall stays occupied
  EXPECT_EQ(map.state({2.1, 0.02, 0.02}), VoxelState::kFree);      // unknown behind it within 0.5 m: assumed free
  EXPECT_EQ(map.state({1.0, 0.02, 0.02}), VoxelState::kUnknown);   // outside the sphere
  const MapBlocksData u = map.takeUpdate();
  EXPECT_GT(u.blockCount(), 0u);
}

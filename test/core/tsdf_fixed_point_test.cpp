// Fixed-point voxel against the float layout: size, inline rounding, voxel-by-voxel
// and mesh difference on the same data; marching-cubes table and PLY round trip.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>
#include <set>
#include <unistd.h>

#include "semantic_exploration/core/tsdf.hpp"
#include "semexp_test/cameras.hpp"
#include "semexp_test/object_scenes.hpp"
#include "semexp_test/rendering.hpp"

using namespace semexp;
using namespace semexp_test;

namespace {

TEST(TsdfFixedPoint, VoxelAtLeast35PercentSmallerThanFloatLayout) {
  const double saving = 1.0 - static_cast<double>(sizeof(TsdfVoxel)) / sizeof(TsdfVoxelFloat);
  std::printf("voxel bytes: fixed %zu, float %zu (%.0f%% smaller)\n", sizeof(TsdfVoxel), sizeof(TsdfVoxelFloat),
              100 * saving);
  EXPECT_GE(saving, 0.35);
}

TEST(TsdfFixedPoint, QuantisationRoundTrips) {
  TsdfVoxel v;
  const float trunc = 0.08f;
  for (float s : {-0.08f, -0.0123f, 0.f, 0.0456f, 0.08f}) {
    v.setSdf(s, trunc);
    EXPECT_NEAR(v.sdf(trunc), s, trunc / 32767.f);
  }
  v.setSdf(1.f, trunc);  // clamped
  EXPECT_FLOAT_EQ(v.sdf(trunc), trunc);
  v.setForeground(0.5f);
  EXPECT_EQ(v.foreground(), 0.5f);  // exact: q / 254
  EXPECT_EQ(TsdfVoxel().foreground(), 0.5f);
  v.setForeground(0.73f);
  EXPECT_NEAR(v.foreground(), 0.73f, 0.5f / 254);
  v.setWeight(37.3f);
  EXPECT_NEAR(v.weight(), 37.3f, 1.f / 32);
  EXPECT_TRUE(std::isinf(TsdfVoxel().minDistance()));
  v.setMinDistance(1.2345f);
  EXPECT_NEAR(v.minDistance(), 1.2345f, 0.0005f);
}

// fuseSdf averages in the stored units: the same value as setSdf of the mean in metres to within one step
// (the two round differently in the last bit), the same sign flag, the same clamping, and NaN stored as the
// upper bound as setSdf stores it.
TEST(TsdfFixedPoint, FusingInStoredUnitsMatchesTheMeanInMetres) {
  const float trunc = 0.08f, to_q = 32767.f / trunc;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> sdf(-trunc, trunc), weight(0.f, 100.f), obs(1.f / 16.f, 1.f);
  int flagged = 0;
  for (int i = 0; i < 200000; ++i) {
    TsdfVoxel a, b;
    a.setSdf(sdf(rng), trunc);
    b = a;
    const float w = (i % 10 == 0) ? 0.f : weight(rng), w_obs = obs(rng), w_new = w + w_obs;
    const float s = (i % 1000 == 1) ? trunc : sdf(rng);  // the clamped end now and then
    const float mean_m = (a.sdf(trunc) * w + s * w_obs) / w_new;
    b.setSdf(mean_m, trunc);
    const bool negative = a.fuseSdf(s, w, w_obs, w_new, trunc, to_q);
    ASSERT_LE(std::abs(a.sdf_q - b.sdf_q), 1) << "mean " << mean_m;
    // The flag is the mean's sign; the two means can differ in sign only within rounding of 0.
    if (std::abs(mean_m) > 1e-6f) {
      ASSERT_EQ(negative, mean_m < 0.f) << "mean " << mean_m;
    }
    flagged += negative;
  }
  EXPECT_GT(flagged, 50000);
  TsdfVoxel v;
  v.setSdf(trunc, trunc);
  v.fuseSdf(trunc, 10.f, 1.f, 11.f, trunc, to_q);
  EXPECT_EQ(v.sdf_q, 32767);  // at the bound, not past it
  v.fuseSdf(std::numeric_limits<float>::quiet_NaN(), 10.f, 1.f, 11.f, trunc, to_q);
  TsdfVoxel u;
  u.setSdf(std::numeric_limits<float>::quiet_NaN(), trunc);
  EXPECT_EQ(v.sdf_q, u.sdf_q);
}

TEST(TsdfFixedPoint, MeshDiffersFromFloatLayoutByLessThanQuarterVoxel) {
  PinholeCamera cam;
  const TsdfParams p = objectTsdfParams();
  TsdfMap fixed(p);
  TsdfMapFloat flt(p);
  const Sphere sphere(Eigen::Vector3d(0.0, 0.0, 0.0), 0.25);
  const Box box = Box::around(Eigen::Vector3d(0.0, 0.0, -0.4), Eigen::Vector3d(0.3, 0.3, 0.15));
  for (const auto& T_WC : ring(Eigen::Vector3d(0, 0, -0.2), 1.2, 0.6, 12)) {
    cv::Mat depth, labels;
    renderShapes(cam, T_WC, {&sphere, &box}, depth, labels);
    const cv::Mat mask = labels > 0;
    fixed.integrate(cam, T_WC, depth, cv::Mat(), mask, true);
    flt.integrate(cam, T_WC, depth, cv::Mat(), mask, true);
  }
  const Mesh a = fixed.extractMesh(), b = flt.extractMesh();
  ASSERT_GT(a.vertices_W.size(), 1000u);
  ASSERT_GT(b.vertices_W.size(), 1000u);
  // RMS distance of every fixed-point vertex to the nearest float-layout vertex (hash grid search).
  const float cell = static_cast<float>(p.resolution_m);
  std::unordered_map<Eigen::Vector3i, std::vector<Eigen::Vector3f>, VoxelIndexHash> grid;
  for (const auto& v : b.vertices_W) grid[(v / cell).array().floor().cast<int>()].push_back(v);
  double sq = 0;
  for (const auto& v : a.vertices_W) {
    const Eigen::Vector3i c = (v / cell).array().floor().cast<int>();
    float best = 2 * cell;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = grid.find(c + Eigen::Vector3i(dx, dy, dz));
          if (it == grid.end()) continue;
          for (const auto& w : it->second) best = std::min(best, (w - v).norm());
        }
    sq += best * best;
  }
  const double rms = std::sqrt(sq / a.vertices_W.size());
  std::printf("fixed %zu / float %zu vertices, RMS distance %.6f m (voxel %.3f m); voxel bytes %zu vs %zu\n",
              a.vertices_W.size(), b.vertices_W.size(), rms, p.resolution_m, fixed.voxelBytes(), flt.voxelBytes());
  EXPECT_LT(rms, 0.25 * p.resolution_m);
  EXPECT_EQ(fixed.blockCount(), flt.blockCount());
  EXPECT_LT(fixed.voxelBytes(), 0.65 * flt.voxelBytes());
}

// Calls check(x) for every integer and half-integer x in [-max, max] and the three values of T on either side.
template <class T, class F>
void aroundHalfIntegers(T max, F&& check) {
  const int n = static_cast<int>(2 * max);
  for (int k = -n; k <= n; ++k) {
    T lo = static_cast<T>(0.5) * static_cast<T>(k), hi = lo;
    check(lo);
    for (int j = 0; j < 3; ++j) {
      lo = std::nextafter(lo, static_cast<T>(-1e9));
      hi = std::nextafter(hi, static_cast<T>(1e9));
      check(lo);
      check(hi);
    }
  }
}

// The voxel setters round inline instead of calling std::nearbyint: halfway cases to even, the same result for
// every input they get (the stored ranges, either sign).
TEST(TsdfFixedPoint, InlineRoundingMatchesNearbyint) {
  std::size_t checked = 0;
  const auto check = [&](float x) {
    ASSERT_EQ(tsdf_fixed::roundHalfEvenToInt(x), static_cast<int>(std::nearbyint(x))) << x;
    ++checked;
  };
  // Around every integer and half-integer of the stored ranges, three floats on either side.
  aroundHalfIntegers(70000.f, check);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> uni(-70000.f, 70000.f);
  for (int i = 0; i < 200000; ++i) check(uni(rng));
  EXPECT_GT(checked, 1000000u);
  // Halfway cases by hand: to the even neighbour, either sign.
  EXPECT_EQ(tsdf_fixed::roundHalfEvenToInt(0.5f), 0);
  EXPECT_EQ(tsdf_fixed::roundHalfEvenToInt(1.5f), 2);
  EXPECT_EQ(tsdf_fixed::roundHalfEvenToInt(2.5f), 2);
  EXPECT_EQ(tsdf_fixed::roundHalfEvenToInt(-2.5f), -2);
  EXPECT_EQ(tsdf_fixed::roundHalfEvenToInt(-32766.5f), -32766);
  EXPECT_EQ(tsdf_fixed::roundHalfEvenToInt(65533.5f), 65534);
  // Near the top of the stored ranges, not halfway.
  EXPECT_EQ(tsdf_fixed::roundHalfEvenToInt(65534.4f), 65534);
  EXPECT_EQ(tsdf_fixed::roundHalfEvenToInt(-32767.f), -32767);
}

// The colour's rounding (both layouts) is std::round's, inline.
TEST(TsdfFixedPoint, InlineColourRoundingMatchesStdRound) {
  const auto check = [&](float x) {
    if (x >= 0.f) {
      ASSERT_EQ(tsdf_fixed::roundNonNegativeToInt(x), static_cast<int>(std::round(x))) << x;
    }
  };
  // (the cases a shortcut like (int)(x + 0.5f) gets wrong, e.g. 0.49999997f)
  aroundHalfIntegers(300.f, check);
  EXPECT_EQ(tsdf_fixed::roundNonNegativeToInt(0.49999997f), 0);
  EXPECT_EQ(tsdf_fixed::roundNonNegativeToInt(2.5f), 3);
}

// The double overload rounds the integration's pixel coordinates as std::lround did: around every integer and
// half-integer of +-5000 px, and the 0.49999999999999994 that x + 0.5 gets wrong.
TEST(TsdfFixedPoint, InlinePixelRoundingMatchesStdLround) {
  std::size_t wrong = 0;
  const auto check = [&](double x) {
    if (tsdf_fixed::roundToInt(x) != std::lround(x) && ++wrong <= 5) ADD_FAILURE() << x;
  };
  check(0.49999999999999994);
  check(-0.49999999999999994);
  aroundHalfIntegers(5000.0, check);
  EXPECT_EQ(wrong, 0u);
}

// A wall 1 m in front of the camera, integrated three times from the same pose into both layouts: every
// fixed-point voxel is the float voxel quantised (SDF within half a step, min distance exactly its rounding,
// weight within one 1/16 rounding per frame), and one voxel is checked by hand.
TEST(TsdfFixedPoint, WallMatchesFloatLayoutVoxelByVoxel) {
  const PinholeCamera cam;
  const TsdfParams p = objectTsdfParams();
  TsdfMap fixed(p);
  TsdfMapFloat flt(p);
  const Box wall = Box::around(Eigen::Vector3d(1.1, 0.0, 0.0), Eigen::Vector3d(0.1, 5.0, 5.0));
  const Eigen::Isometry3d T_WC = lookAt(Eigen::Vector3d::Zero(), Eigen::Vector3d(1.0, 0.0, 0.0));
  cv::Mat depth, labels;
  renderShapes(cam, T_WC, {&wall}, depth, labels);
  const int frames = 3;
  for (int k = 0; k < frames; ++k) {
    EXPECT_GT(fixed.integrate(cam, T_WC, depth, cv::Mat(), labels > 0, true), 10000u);
    flt.integrate(cam, T_WC, depth, cv::Mat(), labels > 0, true);
  }
  ASSERT_EQ(fixed.blockCount(), flt.blockCount());
  const float trunc = static_cast<float>(p.truncation_m);
  std::size_t observed = 0;
  fixed.forEachVoxel([&](const Eigen::Vector3i& index, const TsdfVoxel& a) {
    const TsdfVoxelFloat* b = flt.voxel(index);
    ASSERT_NE(b, nullptr);
    // Weights below 1/32 (far behind the wall) round to "never observed".
    EXPECT_LE(std::abs(a.weight() - b->weight()), frames / 32.f + 1e-5f) << index.transpose();
    if (a.weight_q == 0) return;
    ++observed;
    EXPECT_LE(std::abs(a.sdf_q - b->sdf(trunc) / trunc * 32767.f), 0.52f) << index.transpose();
    EXPECT_EQ(a.foreground_q, 254);  // every observation inside the mask: p = 1
    EXPECT_EQ(b->foreground(), 1.f);
    if (std::isfinite(b->minDistance())) {
      EXPECT_EQ(a.min_distance_mm, static_cast<int>(std::nearbyint(b->minDistance() * 1e3f))) << index.transpose();
    } else {
      EXPECT_EQ(a.min_distance_mm, 65535);
    }
  });
  EXPECT_GT(observed, 10000u);
  // Voxel centre (0.99, -0.01, -0.01) m is 0.99 m deep, 1 cm in front of the wall, 0.990101 m from the camera.
  // Along its pixel's ray the wall is 0.01 * 0.990101 / 0.99 m = 0.0100010 m away:
  // 0.0100010 / 0.08 * 32767 = 4096.3 -> 4096; three unit weights -> 48 / 16; 990.101 mm -> 990 mm.
  const TsdfVoxel* v = fixed.voxel(Eigen::Vector3i(49, -1, -1));
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->sdf_q, 4096);
  EXPECT_EQ(v->weight_q, 48);
  EXPECT_EQ(v->min_distance_mm, 990);
  EXPECT_NEAR(flt.voxel(Eigen::Vector3i(49, -1, -1))->sdf(trunc), 0.0100010f, 2e-6f);
}

TEST(MarchingCubesTable, TrianglesUseExactlyTheCrossedEdges) {
  const auto& table = MarchingCubesTable::get();
  for (int c = 0; c < 256; ++c) {
    std::set<int> crossed, used;
    for (int e = 0; e < 12; ++e) {
      const int a = MarchingCubesTable::kEdgeCorners[e][0], b = MarchingCubesTable::kEdgeCorners[e][1];
      if (((c >> a) & 1) != ((c >> b) & 1)) crossed.insert(e);
    }
    int n = 0;
    for (; table.triangles[c][n] >= 0; ++n) used.insert(table.triangles[c][n]);
    EXPECT_EQ(n % 3, 0);
    EXPECT_EQ(crossed, used) << "case " << c;
  }
  // One corner inside: one triangle whose normal points away from that corner.
  const auto& t = table.triangles[1];
  EXPECT_EQ(t[3], -1);
  Eigen::Vector3f p[3];
  for (int j = 0; j < 3; ++j) {
    const int a = MarchingCubesTable::kEdgeCorners[t[j]][0], b = MarchingCubesTable::kEdgeCorners[t[j]][1];
    const Eigen::Vector3f ca(a & 1, (a >> 1) & 1, (a >> 2) & 1), cb(b & 1, (b >> 1) & 1, (b >> 2) & 1);
    p[j] = 0.5f * (ca + cb);
  }
  EXPECT_GT((p[1] - p[0]).cross(p[2] - p[0]).dot(Eigen::Vector3f(1, 1, 1)), 0.f);
}

TEST(Ply, BinaryRoundTrip) {
  Mesh m;
  m.vertices_W = {{0, 0, 0}, {1, 0, 0}, {0, 1.5f, -2}};
  m.colours = {{{255, 0, 0}}, {{0, 255, 0}}, {{1, 2, 3}}};
  m.triangles = {{{0, 1, 2}}};
  const auto dir = std::filesystem::temp_directory_path() / ("semexp_ply_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "m.ply").string();
  ASSERT_TRUE(writePly(m, path));
  Mesh r;
  ASSERT_TRUE(readPly(path, r));
  ASSERT_EQ(r.vertices_W.size(), 3u);
  EXPECT_EQ(r.vertices_W[2], m.vertices_W[2]);
  EXPECT_EQ(r.colours[2], m.colours[2]);
  ASSERT_EQ(r.triangles.size(), 1u);
  EXPECT_EQ(r.triangles[0], m.triangles[0]);
  std::filesystem::remove_all(dir);
}

}  // namespace

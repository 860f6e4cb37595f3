// Foreground probability, colour, minimum observed distance and summary of
// the object TSDF on analytic scenes.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "semantic_exploration/core/tsdf.hpp"
#include "semexp_test/cameras.hpp"
#include "semexp_test/object_scenes.hpp"
#include "semexp_test/rendering.hpp"

using namespace semexp;
using namespace semexp_test;

namespace {

TsdfParams params() { return objectTsdfParams(); }

const Sphere kSphere(Eigen::Vector3d(0.1, -0.05, 0.02), 0.25);

TEST(TsdfUpdate, UndetectedUpdatesGeometryButNotForeground) {
  PinholeCamera cam;
  TsdfMap map(params());
  const auto poses = ring(kSphere.centre, 1.0, 0.3, 8);
  for (const auto& T_WC : poses) {
    cv::Mat depth, labels;
    renderShapes(cam, T_WC, {&kSphere}, depth, labels);
    EXPECT_GT(map.integrate(cam, T_WC, depth, cv::Mat(), labels > 0, false), 1000u);
  }
  EXPECT_TRUE(map.extractMesh().empty());  // foreground probability stays 0.5
  EXPECT_EQ(map.summarize(1.0).voxel_count, 0u);
  size_t observed = 0;
  map.forEachVoxel([&](const Eigen::Vector3i&, const TsdfVoxel& v) {
    observed += v.weight() > 0;
    EXPECT_EQ(v.foreground(), 0.5f);
  });
  EXPECT_GT(observed, 1000u);

  cv::Mat depth, labels;
  renderShapes(cam, poses[0], {&kSphere}, depth, labels);
  map.integrate(cam, poses[0], depth, cv::Mat(), labels > 0, true);
  EXPECT_FALSE(map.extractMesh().empty());
}

// revision() keys per-object caches (the object map node's summaries): it must change with every call that
// can change a voxel, stay with the ones that read, and differ between maps.
TEST(TsdfUpdate, RevisionChangesWithEveryChangeAndDiffersBetweenMaps) {
  const WallAhead view;
  TsdfMap a(params()), b(params());
  EXPECT_NE(a.revision(), b.revision());
  std::uint64_t r = a.revision();
  view.into(a, 255, true);
  EXPECT_NE(a.revision(), r);
  r = a.revision();
  view.into(b, 255, true);
  EXPECT_NE(b.revision(), a.revision());
  a.mergeFrom(b);
  EXPECT_NE(a.revision(), r);
  r = a.revision();
  a.dropForegroundBeyond(Eigen::Vector3f::UnitX(), 0.5f);
  EXPECT_NE(a.revision(), r);
  r = b.revision();
  TsdfMap::SavedBlock loaded;  // a block loaded from a saved map (tsdf_io.hpp)
  loaded.index = Eigen::Vector3i(5, 5, 5);
  loaded.voxels.resize(512);
  b.loadBlocks({loaded});
  EXPECT_NE(b.revision(), r);
  r = a.revision();
  TsdfMap moved(std::move(a));
  EXPECT_EQ(moved.revision(), r);  // the same state, moved
  EXPECT_NE(a.revision(), r);      // the moved-from map holds another (empty) state
  const std::uint64_t r_moved = moved.revision();
  b = std::move(moved);
  EXPECT_EQ(b.revision(), r_moved);
  EXPECT_NE(moved.revision(), r_moved);
}

TEST(TsdfUpdate, ColourMinDistanceAndSummary) {
  PinholeCamera cam;
  TsdfMap map(params());
  const cv::Mat rgb(cam.height, cam.width, CV_8UC3, cv::Scalar(10, 200, 30));
  for (const auto& T_WC : ring(kSphere.centre, 1.0, 0.0, 12)) {
    cv::Mat depth, labels;
    renderShapes(cam, T_WC, {&kSphere}, depth, labels);
    map.integrate(cam, T_WC, depth, rgb, labels > 0, true);
  }
  const Mesh mesh = map.extractMesh();
  ASSERT_GT(mesh.vertices_W.size(), 500u);
  for (const auto& c : mesh.colours) {
    EXPECT_NEAR(c[0], 10, 1);
    EXPECT_NEAR(c[1], 200, 1);
    EXPECT_NEAR(c[2], 30, 1);
  }
  // Surface seen from 0.75 m (+ a few cm at the rim): all observed from <= 1 m, none from <= 0.6 m.
  const TsdfSummary s = map.summarize(1.0);
  EXPECT_GT(s.voxel_count, 500u);
  EXPECT_DOUBLE_EQ(s.observed_fraction, 1.0);
  EXPECT_DOUBLE_EQ(map.summarize(0.6).observed_fraction, 0.0);
  EXPECT_LT((s.centroid_W - kSphere.centre).head<2>().norm(), 0.01);
  for (int i = 0; i < 2; ++i) {  // horizontal extent of a sphere seen all round
    EXPECT_NEAR(s.bbox_min_W[i], kSphere.centre[i] - kSphere.radius, 0.03);
    EXPECT_NEAR(s.bbox_max_W[i], kSphere.centre[i] + kSphere.radius, 0.03);
  }
}

TEST(TsdfUpdate, BledMaskLosesForegroundWhenSeenOutsideTheMask) {
  PinholeCamera cam;
  TsdfMap map(params());
  const Box table = Box::around(Eigen::Vector3d(0.1, -0.05, -0.45), Eigen::Vector3d(0.5, 0.5, 0.2));
  const auto poses = ring(kSphere.centre, 1.2, 0.5, 8);
  for (size_t i = 0; i < poses.size(); ++i) {
    cv::Mat depth, labels;
    renderShapes(cam, poses[i], {&kSphere, &table}, depth, labels);
    // First frame: the detection bleeds onto the table; later frames are clean.
    const cv::Mat mask = i == 0 ? labels > 0 : labels == 1;
    map.integrate(cam, poses[i], depth, cv::Mat(), mask, true);
  }
  const Mesh mesh = map.extractMesh();
  ASSERT_GT(mesh.vertices_W.size(), 500u);
  size_t off = 0;
  for (const auto& v : mesh.vertices_W) off += std::abs(kSphere.sdf(v.cast<double>())) > 0.02;
  EXPECT_LT(off, mesh.vertices_W.size() / 100) << off << " of " << mesh.vertices_W.size() << " vertices off the sphere";
}

// The band behind the surface is max(behind_surface_m, q d^2): for a wall 3 m ahead and q = 0.006 that is
// 0.054 m, so the voxel centred 5 cm behind the wall is updated with weight (0.054 - 0.05) / (0.054 - 0.02) =
// 0.118 (one voxel behind the weight is 1, falling linearly to 0 at the band's end), while the fixed 4 cm band
// leaves it unseen. A wall 4 m ahead has q d^2 = 0.096 m > the 0.08 m truncation: not integrated at all.
TEST(TsdfUpdate, BandBehindTheSurfaceFollowsTheDepthNoise) {
  const PinholeCamera cam = tinyCamera();
  const Eigen::Isometry3d T_WC = lookAlong(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  auto weightBehind = [&](double wall_x, double q, std::size_t* updated) {
    const Box wall(Eigen::Vector3d(wall_x, -2.0, -2.0), Eigen::Vector3d(wall_x + 0.5, 2.0, 2.0));
    TsdfParams p = params();
    p.behind_surface_quadratic_per_m = q;
    TsdfMap map(p);
    cv::Mat depth, labels;
    renderShapes(cam, T_WC, {&wall}, depth, labels);
    *updated = map.integrate(cam, T_WC, depth, cv::Mat(), labels > 0, true);
    float w = 0.f;
    map.forEachVoxel([&](const Eigen::Vector3i& idx, const TsdfVoxel& vx) {
      if (map.voxelCentre(idx).isApprox(Eigen::Vector3f(static_cast<float>(wall_x) + 0.05f, 0.01f, 0.01f), 1e-4f))
        w = vx.weight();
    });
    return w;
  };
  std::size_t updated = 0;
  EXPECT_NEAR(weightBehind(3.0, 0.006, &updated), 0.118, 1.0 / 32.0);  // fixed point: weight in steps of 1/16
  EXPECT_GT(updated, 0u);
  EXPECT_EQ(weightBehind(3.0, 0.0, &updated), 0.f);
  EXPECT_GT(updated, 0u);
  EXPECT_EQ(weightBehind(4.0, 0.006, &updated), 0.f);
  EXPECT_EQ(updated, 0u);
  EXPECT_EQ(weightBehind(4.0, 0.0, &updated), 0.f);  // 5 cm behind: outside the fixed 4 cm band
  EXPECT_GT(updated, 0u);
}

// A wall 3 m ahead of the origin seen once from 1 m with the true depth and once from 3 m with its depth read
// 3 cm too near. The voxel centred 1 cm in front of the wall, near the optical axis, gets SDF 0.01 m from the
// near view and -0.02 m from the far one (a hair past one voxel behind: behind-surface weight 0.99994).
// Every observation counting 1: the mean, -0.005 m. With full_weight_depth_m = 1 m the near view (depth
// 1 m) counts 1 and the far one (1/2.97)^2 = 0.1134, rounded to the 1/16 step: 0.125, so
// (0.01 - 0.02 * 0.125) / 1.125 = 0.006667 m, and the voxel's weight is 1.125 (18 steps of 1/16).
// Seen again from 3 m outside the mask, its foreground probability falls by w / (w + 0.125), not w / (w + 1).
template <class Map>
void checkDepthWeighting() {
  const PinholeCamera cam = tinyCamera();
  const Box wall(Eigen::Vector3d(3.0, -2.0, -2.0), Eigen::Vector3d(3.5, 2.0, 2.0));
  struct Result {
    float sdf = NAN, weight = 0.f, foreground = NAN, foreground_after_outside_view = NAN;
  };
  auto fuse = [&](double full_weight_depth_m) {
    TsdfParams p = params();
    p.full_weight_depth_m = full_weight_depth_m;
    Map map(p);
    Result r;
    auto readVoxel = [&](auto&& use) {
      map.forEachVoxel([&](const Eigen::Vector3i& idx, const typename Map::Voxel& vx) {
        if (map.voxelCentre(idx).isApprox(Eigen::Vector3f(2.99f, 0.01f, 0.01f), 1e-4f)) use(vx);
      });
    };
    const std::pair<double, float> views[] = {{2.0, 0.0f}, {0.0, -0.03f}};  // camera x (m), depth error (m)
    for (const auto& [x, error] : views) {
      const Eigen::Isometry3d T_WC = lookAlong(Eigen::Vector3d(x, 0, 0), Eigen::Vector3d::UnitX());
      cv::Mat depth, labels;
      renderShapes(cam, T_WC, {&wall}, depth, labels);
      depth.setTo(cv::Scalar(3.0 - x + error), depth > 0);
      map.integrate(cam, T_WC, depth, cv::Mat(), labels > 0, true);
    }
    readVoxel([&](const auto& vx) {
      r.sdf = vx.sdf(static_cast<float>(p.truncation_m));
      r.weight = vx.weight();
      r.foreground = vx.foreground();
    });
    const Eigen::Isometry3d T_WC = lookAlong(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
    cv::Mat depth, labels;
    renderShapes(cam, T_WC, {&wall}, depth, labels);
    map.integrate(cam, T_WC, depth, cv::Mat(), cv::Mat::zeros(depth.size(), CV_8U), true);  // outside the mask
    readVoxel([&](const auto& vx) { r.foreground_after_outside_view = vx.foreground(); });
    return r;
  };
  const Result flat = fuse(0.0), weighted = fuse(1.0);
  EXPECT_NEAR(flat.sdf, -0.005, 1e-4);
  EXPECT_NEAR(flat.weight, 2.0, 1.0 / 32.0);
  EXPECT_NEAR(flat.foreground_after_outside_view / flat.foreground, flat.weight / (flat.weight + 1.0), 2.0 / 254.0);
  EXPECT_NEAR(weighted.sdf, 0.006667, 1e-4);
  EXPECT_NEAR(weighted.weight, 1.125, 1e-4);
  EXPECT_NEAR(weighted.foreground_after_outside_view / weighted.foreground, 1.125 / 1.25, 2.0 / 254.0);
}

TEST(TsdfUpdate, NearViewsOutweighFarOnesBeyondTheFullWeightDepth) {
  checkDepthWeighting<TsdfMap>();       // the fixed-point map the object map uses
  checkDepthWeighting<TsdfMapFloat>();  // the float reference layout

  TsdfParams p;
  p.full_weight_depth_m = 1.0;
  EXPECT_EQ(p.depthWeight(0.5f), 1.f);
  EXPECT_EQ(p.depthWeight(2.0f), 0.25f);
  EXPECT_EQ(p.depthWeight(2.97f), 0.125f);    // (1/2.97)^2 = 0.113 rounds to 2/16
  EXPECT_EQ(p.depthWeight(5.0f), 1.f / 16.f);  // (1/5)^2 = 0.04 is under one step
}

// Foreground prior 0.3 with weight 2 (object_map/foreground_prior): the voxel centred 1 cm in front of a
// wall 1 m ahead, seen by a sequence of views, each one full-weight observation (weight 1 at the surface):
//  - once inside the mask (evidence 1): (0.3 * 2 + 1) / (0 + 2 + 1) = 0.5333; the paper's update: 1;
//  - then once outside it: 0.5333 * (1 + 2) / (1 + 2 + 1) = 0.4; the paper's: 1 * 1 / 2 = 0.5;
//  - then inside again (a view outside the mask adds no weight): (0.4 * (1 + 2) + 1) / (1 + 2 + 1) = 0.55;
//  - once at a mask's border (mask value 179, evidence 0.5 + 0.5 * 51 / 127 = 0.70079): (0.6 + 0.70079) / 3 =
//    0.43360, under 0.5 (the paper's: 0.70079);
//  - once as an undetected object (SDF only), then inside: the first sets the prior, (0.3 * 3 + 1) / 4 = 0.475.
// The fixed-point voxel stores q / 254: each step is within half a step (1/508) of the float one.
template <class Map>
void checkForegroundPrior() {
  const WallAhead wall;
  struct View {
    std::uint8_t mask;
    bool detected;
  };
  // Foreground after each view of `views`, prior (p0, w0).
  auto fuse = [&](double p0, double w0, const std::vector<View>& views) {
    TsdfParams p = params();
    p.foreground_prior = p0;
    p.foreground_prior_weight = w0;
    Map map(p);
    std::vector<float> fg;
    for (const View& view : views) {
      wall.into(map, view.mask, view.detected);
      float f = NAN;
      map.forEachVoxel([&](const Eigen::Vector3i& idx, const typename Map::Voxel& vx) {
        if (map.voxelCentre(idx).isApprox(Eigen::Vector3f(0.99f, 0.01f, 0.01f), 1e-4f)) f = vx.foreground();
      });
      fg.push_back(f);
    }
    return fg;
  };
  const double tol = 1.0 / 508.0 + 1e-6;
  const std::vector<float> prior = fuse(0.3, 2.0, {{255, true}, {0, true}, {255, true}});
  ASSERT_EQ(prior.size(), 3u);
  EXPECT_NEAR(prior[0], 1.6 / 3.0, tol);
  EXPECT_NEAR(prior[1], 0.4, 2 * tol);
  EXPECT_NEAR(prior[2], 0.55, 3 * tol);
  const std::vector<float> paper = fuse(0.5, 0.0, {{255, true}, {0, true}});
  EXPECT_NEAR(paper[0], 1.0, tol);
  EXPECT_NEAR(paper[1], 0.5, 2 * tol);
  EXPECT_NEAR(fuse(0.3, 2.0, {{179, true}})[0], 0.43360, tol);
  EXPECT_NEAR(fuse(0.5, 0.0, {{179, true}})[0], 0.70079, tol);
  const std::vector<float> undetected_first = fuse(0.3, 2.0, {{255, false}, {255, true}});
  EXPECT_NEAR(undetected_first[0], 0.3, tol);
  EXPECT_NEAR(undetected_first[1], 0.475, 2 * tol);
}

TEST(TsdfUpdate, ForegroundPriorNeedsMoreThanOneBorderDetection) {
  checkForegroundPrior<TsdfMap>();
  checkForegroundPrior<TsdfMapFloat>();
}

// The tracked surface (rendered, ray cast, kept) is every voxel a detection lifted above the prior; the
// mesh needs 0.5. The wall of checkForegroundPrior seen once at a mask's border: 0.43360 with the prior
// (0.3, weight 2; the fixed-point voxel stores 110 / 254 = 0.43307), tracked but not meshed; then outside the
// mask once, 0.43307 * 3 / 4 = 0.3248 (stored 0.3228 or 0.3268), still tracked; twice, about 0.244, no
// longer. With the paper's update, 0.70079: both.
TEST(TsdfUpdate, TrackedSurfaceIsWhatADetectionLiftedAboveThePrior) {
  TsdfParams p = params();
  EXPECT_EQ(p.trackedForeground(), 0.5f);  // the paper's update
  p.foreground_prior = 0.3;
  EXPECT_EQ(p.trackedForeground(), 0.5f);  // a prior without weight is no prior
  p.foreground_prior_weight = 2.0;
  EXPECT_EQ(p.trackedForeground(), 0.3f);
  p.foreground_prior = 0.7;
  EXPECT_EQ(p.trackedForeground(), 0.5f);  // a prior over 0.5 tracks what the mesh holds

  const WallAhead wall;
  const auto hits = [](const TsdfMap& map) {
    TsdfRayHit hit;
    return map.castRay(Eigen::Vector3f(0.f, 0.01f, 0.01f), Eigen::Vector3f::UnitX(), 0.f, 3.f, hit) &&
           std::abs(hit.distance_m - 1.f) < 0.02f;
  };
  for (const bool with_prior : {true, false}) {
    TsdfParams q = params();
    q.foreground_prior = with_prior ? 0.3 : 0.5;
    q.foreground_prior_weight = with_prior ? 2.0 : 0.0;
    TsdfMap map(q);
    wall.into(map, 179, true);
    EXPECT_EQ(map.extractMesh().empty(), with_prior);
    EXPECT_EQ(map.summarize(1.0).voxel_count == 0, with_prior);
    EXPECT_GT(map.summarize(1.0, true).voxel_count, 0u);
    EXPECT_TRUE(map.hasSurface());
    EXPECT_TRUE(hits(map)) << "prior " << with_prior;
    if (!with_prior) continue;
    wall.into(map, 0, true);
    EXPECT_TRUE(map.hasSurface());
    EXPECT_TRUE(hits(map));
    wall.into(map, 0, true);
    EXPECT_FALSE(map.hasSurface());
    EXPECT_FALSE(hits(map));
    EXPECT_EQ(map.summarize(1.0, true).voxel_count, 0u);
  }
}

// A voxel updated only as an undetected object keeps the prior it was given, as its layout stores it: never
// tracked. The fixed-point voxel stores 0.25 as 64 / 254 = 0.25197 (above the prior) and 0.3 as 76 / 254 =
// 0.29921 (below), so the map compares with the larger of the two.
template <class Map>
void checkPriorAloneIsNotTracked() {
  const WallAhead wall;
  for (const double prior : {0.25, 0.3}) {
    TsdfParams p = params();
    p.foreground_prior = prior;
    p.foreground_prior_weight = 2.0;
    Map map(p);
    for (int i = 0; i < 3; ++i)
      wall.into(map, 255, false);
    EXPECT_GT(map.summarize(1.0, false).weight_sum, 0.0);
    EXPECT_FALSE(map.hasSurface()) << "prior " << prior;
    EXPECT_EQ(map.summarize(1.0, true).voxel_count, 0u) << "prior " << prior;
    TsdfRayHit hit;
    EXPECT_FALSE(map.castRay(Eigen::Vector3f(0.f, 0.01f, 0.01f), Eigen::Vector3f::UnitX(), 0.f, 3.f, hit));
  }
}

TEST(TsdfUpdate, VoxelHoldingThePriorIsNotTracked) {
  checkPriorAloneIsNotTracked<TsdfMap>();
  checkPriorAloneIsNotTracked<TsdfMapFloat>();
  TsdfParams p = params();
  p.foreground_prior_weight = 2.0;
  p.foreground_prior = 0.25;
  EXPECT_FLOAT_EQ(TsdfMap(p).trackedForeground(), 64.f / 254.f);
  EXPECT_FLOAT_EQ(TsdfMapFloat(p).trackedForeground(), 0.25f);
  p.foreground_prior = 0.3;
  EXPECT_FLOAT_EQ(TsdfMap(p).trackedForeground(), 0.3f);
}

TEST(TsdfUpdate, RayCastHitsTheSurface) {
  PinholeCamera cam;
  TsdfMap map(params());
  for (const auto& T_WC : ring(kSphere.centre, 1.0, 0.0, 12)) {
    cv::Mat depth, labels;
    renderShapes(cam, T_WC, {&kSphere}, depth, labels);
    map.integrate(cam, T_WC, depth, cv::Mat(), labels > 0, true);
  }
  const Eigen::Vector3f o = kSphere.centre.cast<float>() + Eigen::Vector3f(-2.f, 0.01f, 0.f);
  TsdfRayHit hit;
  ASSERT_TRUE(map.castRay(o, Eigen::Vector3f::UnitX(), 0.f, 10.f, hit));
  EXPECT_NEAR(hit.distance_m, 2.f - kSphere.radius, 0.01f);
  EXPECT_NEAR(hit.min_distance_m, 0.75f, 0.03f);
  EXPECT_FALSE(map.castRay(o, Eigen::Vector3f::UnitX(), 0.f, 1.5f, hit));  // stops before the surface
  EXPECT_FALSE(map.castRay(o, -Eigen::Vector3f::UnitX(), 0.f, 10.f, hit)); // looks away
}

}  // namespace

// Object map: frame integration (new / detected / undetected objects, bad
// detections), rendering with occlusion by depth and by other objects,
// object gain images and saving.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <unistd.h>
#include <vector>

#include "semantic_exploration/core/int_math.hpp"
#include "semantic_exploration/core/object_map.hpp"
#include "semexp_test/cameras.hpp"
#include "semexp_test/object_scenes.hpp"
#include "semexp_test/rendering.hpp"

using namespace semexp;
using namespace semexp_test;

namespace {

const Sphere kA(Eigen::Vector3d(0.0, 0.0, 1.0), 0.25);
const Sphere kB(Eigen::Vector3d(0.0, 0.9, 1.0), 0.2);
constexpr int kChair = 1;  // "chair" in the default class table

// With the foreground prior: what these tests were written for.
ObjectMapConfig config() { return objectMapConfigWithPrior(); }

// Builds a map holding A (id 1) and B (id 2), each seen all round.
ObjectMap twoObjects(const PinholeCamera& cam, const ObjectMapConfig& c = config()) {
  ObjectMap map(c, ClassTable());
  for (int k = 0; k < 2; ++k) {
    const Sphere& s = k == 0 ? kA : kB;
    bool first = true;
    for (const auto& T_WC : ring(s.centre, 0.9, 0.3, 10)) {
      cv::Mat depth, labels;
      renderShapes(cam, T_WC, {&s}, depth, labels);
      const std::uint32_t id = first ? 0u : static_cast<std::uint32_t>(k + 1);
      map.integrateFrame(cam, T_WC, depth, cv::Mat(), labels, {{1, id, kChair}});
      first = false;
    }
  }
  return map;
}

// A detected as a new object (it becomes id 2) from poses[0], then tracked as 2 over poses[1 .. n): the merges.
using Merges = std::vector<std::pair<std::uint32_t, std::uint32_t>>;  // (merged id, into id)
Merges trackAAsObject2(ObjectMap& map, const PinholeCamera& cam, const std::vector<Eigen::Isometry3d>& poses,
                       size_t n) {
  Merges merged;
  cv::Mat depth, labels;
  for (size_t i = 0; i < n; ++i) {
    renderShapes(cam, poses[i], {&kA}, depth, labels);
    const FrameIntegration r =
        map.integrateFrame(cam, poses[i], depth, cv::Mat(), labels, {{1, i == 0 ? 0u : 2u, kChair}});
    merged.insert(merged.end(), r.merged.begin(), r.merged.end());
  }
  return merged;
}

// IoU of the pixels showing object `id` in the rendering and in the truth.
double iou(const cv::Mat& ids, const cv::Mat& expected, int id) {
  const cv::Mat a = ids == id, b = expected == id;
  return static_cast<double>(cv::countNonZero(a & b)) / std::max(1, cv::countNonZero(a | b));
}

TEST(ObjectMap, DetectionsCreateObjectsAtClassResolution) {
  PinholeCamera cam;
  ClassTable classes;
  classes.of_interest = {"chair", "table"};
  classes.resolution_m["table"] = 0.04;
  ObjectMap map(config(), classes);
  const auto T_WC = lookAt(Eigen::Vector3d(-1.2, 0.4, 1.3), Eigen::Vector3d(0, 0.45, 1.0));
  cv::Mat depth, labels;
  renderShapes(cam, T_WC, {&kA, &kB}, depth, labels);
  const int table = classes.id("table"), sofa = classes.id("sofa");
  const FrameIntegration r = map.integrateFrame(
      cam, T_WC, depth, cv::Mat(), labels,
      {{1, 0, kChair}, {2, 0, table}, {1, 0, sofa}, {2, 0, 999}, {2, 42, table}});
  ASSERT_EQ(r.created.size(), 2u);
  EXPECT_EQ(r.dropped_not_of_interest, 1u);
  EXPECT_EQ(r.dropped_unknown_class, 1u);
  EXPECT_EQ(r.dropped_unknown_object, 1u);
  ASSERT_EQ(map.objects().size(), 2u);
  EXPECT_EQ(map.object(1)->class_name, "chair");
  EXPECT_DOUBLE_EQ(map.object(1)->resolution_m, 0.02);
  EXPECT_EQ(map.object(2)->class_name, "table");
  EXPECT_DOUBLE_EQ(map.object(2)->resolution_m, 0.04);
  EXPECT_EQ(map.object(1)->detection_count, 1u);
  EXPECT_GT(map.object(1)->tsdf.summarize(1.0).voxel_count, 100u);
  // A new detection lying wholly on a known object, or without depth, makes no object.
  cv::Mat no_depth = cv::Mat::zeros(depth.size(), CV_32FC1);
  const FrameIntegration e = map.integrateFrame(cam, T_WC, no_depth, cv::Mat(), labels, {{1, 0, kChair}});
  EXPECT_TRUE(e.created.empty());
  EXPECT_EQ(e.dropped_empty, 1u);
  EXPECT_EQ(map.objects().size(), 2u);
  EXPECT_THROW(map.integrateFrame(cam, T_WC, depth, cv::Mat(), cv::Mat::zeros(10, 10, CV_16UC1), {}),
               std::invalid_argument);
}

TEST(ObjectMap, RenderMatchesTheTrueObjectsAndOcclusionByEachOther) {
  PinholeCamera cam;
  const ObjectMap map = twoObjects(cam);
  // B partly in front of A.
  const auto T_WC = lookAt(Eigen::Vector3d(-0.3, 2.0, 1.1), kA.centre);
  cv::Mat depth, labels, ids, rendered_depth;
  renderShapes(cam, T_WC, {&kA, &kB}, depth, labels);
  ASSERT_GT(cv::countNonZero(labels == 1), 1000);
  ASSERT_GT(cv::countNonZero(labels == 2), 1000);
  map.render(cam, T_WC, cv::Mat(), ids, &rendered_depth);
  // Silhouettes are good to about a voxel (2 cm = 2.6 px at 2 m).
  EXPECT_GT(iou(ids, labels, 1), 0.9);
  EXPECT_GT(iou(ids, labels, 2), 0.9);
  // Rendered depth agrees with the true depth on the objects.
  double err = 0;
  int n = 0;
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u)
      if (ids.at<std::uint16_t>(v, u) && labels.at<std::uint16_t>(v, u) == ids.at<std::uint16_t>(v, u)) {
        err += std::abs(rendered_depth.at<float>(v, u) - depth.at<float>(v, u));
        ++n;
      }
  EXPECT_LT(err / n, 0.01);
  EXPECT_EQ(ObjectMap::visibleIds(ids), (std::vector<std::uint32_t>{1, 2}));
}

TEST(ObjectMap, RenderOccludedByMeasuredDepth) {
  PinholeCamera cam;
  const ObjectMap map = twoObjects(cam);
  const auto T_WC = lookAt(Eigen::Vector3d(-1.5, 0.0, 1.0), kA.centre);
  cv::Mat depth, labels, ids;
  renderShapes(cam, T_WC, {&kA}, depth, labels);
  // A wall 0.8 m in front of the camera covers the left half; invalid depth (0) elsewhere does not occlude.
  cv::Mat wall = cv::Mat::zeros(cam.height, cam.width, CV_32FC1);
  wall.colRange(0, cam.width / 2).setTo(0.8f);
  map.render(cam, T_WC, wall, ids);
  EXPECT_EQ(cv::countNonZero(ids.colRange(0, cam.width / 2)), 0);
  cv::Mat right_labels = labels.clone();
  right_labels.colRange(0, cam.width / 2).setTo(0);
  EXPECT_GT(iou(ids, right_labels, 1), 0.9);
  // The measured depth of the object itself does not hide it.
  map.render(cam, T_WC, depth, ids);
  EXPECT_GT(iou(ids, labels, 1), 0.9);
  // Objects in front of the camera but beside the image render nothing.
  const Eigen::Vector3d eye(-1.5, 0.0, 1.0);
  map.render(cam, lookAt(eye, eye + Eigen::Vector3d(1.0, -1.5, 0.0)), cv::Mat(), ids);
  EXPECT_EQ(cv::countNonZero(ids), 0);
  map.render(cam, lookAt(eye, eye + Eigen::Vector3d(1.0, 0.0, 2.0)), cv::Mat(), ids);
  EXPECT_EQ(cv::countNonZero(ids), 0);
}

TEST(ObjectMap, VisibleUndetectedObjectGainsDataWithoutForeground) {
  PinholeCamera cam;
  ObjectMap map = twoObjects(cam);
  const auto T_WC = lookAt(Eigen::Vector3d(-1.0, 0.45, 1.6), Eigen::Vector3d(0, 0.45, 1.0));
  cv::Mat depth, labels;
  renderShapes(cam, T_WC, {&kA, &kB}, depth, labels);
  double weight_before = 0, weight_after = 0;
  const std::uint32_t undetected_a = map.object(1)->undetected_count, undetected_b = map.object(2)->undetected_count;
  map.object(2)->tsdf.forEachVoxel([&](const Eigen::Vector3i&, const TsdfVoxel& v) { weight_before += v.weight(); });
  // Only A is detected; B is visible.
  cv::Mat only_a = labels.clone();
  only_a.setTo(0, labels == 2);
  const FrameIntegration r = map.integrateFrame(cam, T_WC, depth, cv::Mat(), only_a, {{1, 1, kChair}});
  EXPECT_EQ(r.detected, (std::vector<std::uint32_t>{1}));
  EXPECT_EQ(r.undetected, (std::vector<std::uint32_t>{2}));
  map.object(2)->tsdf.forEachVoxel([&](const Eigen::Vector3i&, const TsdfVoxel& v) { weight_after += v.weight(); });
  EXPECT_GT(weight_after, weight_before + 100);
  EXPECT_NEAR(map.object(2)->tsdf.summarize(1.0).weight_sum, weight_after, 1e-6 * weight_after);
  EXPECT_EQ(map.object(1)->detection_count, 11u);
  EXPECT_EQ(map.object(2)->detection_count, 10u);
  EXPECT_EQ(map.object(1)->undetected_count, undetected_a);
  EXPECT_EQ(map.object(2)->undetected_count, undetected_b + 1);
}

TEST(ObjectMap, DetectionSpanningTwoObjectsOnlyFeedsTheMatchedOne) {
  PinholeCamera cam;
  ObjectMap map = twoObjects(cam);
  const auto T_WC = lookAt(Eigen::Vector3d(-1.0, 0.45, 1.6), Eigen::Vector3d(0, 0.45, 1.0));
  cv::Mat depth, labels;
  renderShapes(cam, T_WC, {&kA, &kB}, depth, labels);
  const cv::Mat merged = cv::Mat(labels > 0) / 255;  // one detection (id 1) over A and B
  cv::Mat merged16;
  merged.convertTo(merged16, CV_16UC1);
  for (int i = 0; i < 5; ++i) map.integrateFrame(cam, T_WC, depth, cv::Mat(), merged16, {{1, 1, kChair}});
  // B's surface did not become part of A (rendered silhouettes are good to a
  // pixel or two, so a few rim pixels may still allocate blocks there).
  const Mesh mesh = map.object(1)->tsdf.extractMesh();
  ASSERT_GT(mesh.vertices_W.size(), 1000u);
  for (const auto& v : mesh.vertices_W) ASSERT_LT(std::abs(kA.sdf(v.cast<double>())), 0.02);
}

TEST(ObjectMap, PieceOfAnObjectIsMergedIntoIt) {
  PinholeCamera cam;
  ObjectMap map(config(), ClassTable());
  const auto poses = ring(kA.centre, 0.9, 0.3, 10);
  cv::Mat depth, labels;
  // A first detection saw only a patch of A: object 1.
  renderShapes(cam, poses[0], {&kA}, depth, labels);
  cv::Mat patch = cv::Mat::zeros(labels.size(), CV_16UC1);
  labels(cv::Rect(150, 100, 20, 20)).copyTo(patch(cv::Rect(150, 100, 20, 20)));
  map.integrateFrame(cam, poses[0], depth, cv::Mat(), patch, {{1, 0, kChair}});
  ASSERT_EQ(map.objects().size(), 1u);
  // Later A is taken for a new object (2) and tracked all round: the patch is part of it.
  EXPECT_EQ(trackAAsObject2(map, cam, poses, poses.size()), (Merges{{1, 2}}));
  ASSERT_EQ(map.objects().size(), 1u);
  EXPECT_EQ(map.objects().begin()->first, 2u);
  for (const auto& v : map.object(2)->tsdf.extractMesh().vertices_W) ASSERT_LT(std::abs(kA.sdf(v.cast<double>())), 0.02);
}

TEST(ObjectMap, PieceNeverSeenAgainIsMergedIntoTheObjectHoldingIt) {
  PinholeCamera cam;
  ObjectMapConfig cfg = config();
  cfg.min_new_object_pixels = 1;  // let a detection of a few pixels make an object
  ObjectMap map(cfg, ClassTable());
  const auto poses = ring(kA.centre, 0.9, 0.3, 10);
  cv::Mat depth, labels, ids;
  // A first detection saw a 7 x 7 px speck of A (2.4 cm at 0.9 m): object 1, of two voxels.
  renderShapes(cam, poses[0], {&kA}, depth, labels);
  cv::Mat speck = cv::Mat::zeros(labels.size(), CV_16UC1);
  labels(cv::Rect(157, 117, 7, 7)).copyTo(speck(cv::Rect(157, 117, 7, 7)));
  const FrameIntegration first = map.integrateFrame(cam, poses[0], depth, cv::Mat(), speck, {{1, 0, kChair}});
  ASSERT_EQ(first.created, std::vector<std::uint32_t>{1u});
  // It hardly renders (a few pixels from one of the ten views round A), so the merge by rendered pixels
  // does not see it from the views below.
  for (size_t i = 0; i < 3; ++i) {
    renderShapes(cam, poses[i], {&kA}, depth, labels);
    map.render(cam, poses[i], depth, ids);
    ASSERT_EQ(cv::countNonZero(ids == 1), 0);
  }
  // A is then taken for a new object (2) and tracked: the speck lies inside it and joins it.
  EXPECT_EQ(trackAAsObject2(map, cam, poses, 3), (Merges{{1, 2}}));
  ASSERT_EQ(map.objects().size(), 1u);
  EXPECT_EQ(map.objects().begin()->first, 2u);
}

TEST(ObjectMap, OnceSeenObjectOutsideADetectedOneStays) {
  PinholeCamera cam;
  ObjectMapConfig cfg = config();
  cfg.min_new_object_pixels = 1;
  ObjectMap map(cfg, ClassTable());
  // A speck of B, then A tracked: B's speck is not inside A's box and stays an object of its own.
  const auto poses_a = ring(kA.centre, 0.9, 0.3, 10);
  const auto T_B = lookAt(kB.centre + Eigen::Vector3d(-0.9, 0.0, 0.3), kB.centre);
  cv::Mat depth, labels;
  renderShapes(cam, T_B, {&kB}, depth, labels);
  cv::Mat speck = cv::Mat::zeros(labels.size(), CV_16UC1);
  labels(cv::Rect(157, 117, 7, 7)).copyTo(speck(cv::Rect(157, 117, 7, 7)));
  ASSERT_EQ(map.integrateFrame(cam, T_B, depth, cv::Mat(), speck, {{1, 0, kChair}}).created.size(), 1u);
  cv::Mat ids;
  for (size_t i = 0; i < 3; ++i) {  // unrendered from A's views: only the box rule could merge it
    renderShapes(cam, poses_a[i], {&kA}, depth, labels);
    map.render(cam, poses_a[i], depth, ids);
    ASSERT_EQ(cv::countNonZero(ids == 1), 0);
  }
  EXPECT_TRUE(trackAAsObject2(map, cam, poses_a, 3).empty());
  EXPECT_EQ(map.objects().size(), 2u);
}

TEST(ObjectMap, NewDetectionWithFewPixelsBesideKnownObjectsMakesNoObject) {
  PinholeCamera cam;
  ObjectMap map = twoObjects(cam);
  // A in front of a wall; the detection covers A plus a blob of wall beside it.
  const Box wall = Box::around(Eigen::Vector3d(0.8, 0.0, 1.0), Eigen::Vector3d(0.05, 3.0, 3.0));
  const auto T_WC = lookAt(Eigen::Vector3d(-1.0, 0.0, 1.2), kA.centre);
  cv::Mat depth, labels, ids;
  renderShapes(cam, T_WC, {&kA, &wall}, depth, labels);
  map.render(cam, T_WC, depth, ids);
  const cv::Rect a_box = cv::boundingRect(ids == 1);
  const auto detection = [&](int blob_px) {
    cv::Mat mask = cv::Mat::zeros(labels.size(), CV_16UC1);
    mask.setTo(1, ids == 1);
    // A blob_px x blob_px patch of wall 12 px right of A's render: beyond the 2 px that renders are grown by,
    // and beyond the 8 px within which mask pixels far behind A's are taken for a mask bled past A
    // (ObjectMapConfig::mask_depth_edge_window_px).
    mask(cv::Rect(a_box.x + a_box.width + 12, a_box.y + a_box.height / 2, blob_px, blob_px)).setTo(1);
    return mask;
  };
  // Taken for a new object (as matching does when the IoU with A's render is low): 8 x 8 = 64 px of wall
  // outside A's render are too few for an object.
  FrameIntegration r = map.integrateFrame(cam, T_WC, depth, cv::Mat(), detection(8), {{1, 0, kChair}});
  EXPECT_TRUE(r.created.empty());
  EXPECT_EQ(r.dropped_empty, 1u);
  EXPECT_EQ(map.objects().size(), 2u);
  // 12 x 12 = 144 px are a detection of their own: a new object on the wall patch.
  r = map.integrateFrame(cam, T_WC, depth, cv::Mat(), detection(12), {{1, 0, kChair}});
  ASSERT_EQ(r.created.size(), 1u);
  EXPECT_EQ(r.dropped_empty, 0u);
  // Every pixel of the patch lies k <= 6 px inside its border: evidence at most 0.5 + 0.5 * 6 / 9 = 0.83, and
  // under the foreground prior (0.3, weight 2) a foreground of at most (2 * 0.3 + 0.83) / 3 = 0.48 after one
  // detection. The object has no mesh surface yet; it is kept, and summarised, by its tracked surface.
  const MappedObject& o = *map.object(r.created[0]);
  ASSERT_DOUBLE_EQ(o.tsdf.params().foreground_prior, 0.3);
  EXPECT_EQ(o.tsdf.summarize(1.0).voxel_count, 0u);
  EXPECT_TRUE(o.tsdf.hasSurface());
  const TsdfSummary s = map.summarize(o, 1.0);
  EXPECT_EQ(s.voxel_count, o.tsdf.summarize(1.0, true).voxel_count);
  EXPECT_GT(s.voxel_count, 10u);
  EXPECT_NEAR(s.centroid_W.x(), 0.75, 0.03);  // on the wall's front face
}

// The chair TSDF integrates depths up to sqrt(0.08 m / 0.006 1/m) = 3.65 m (the default noise band). A chair
// whose near side is 3.38 m and far side 3.82 m away reaches past that: its near part alone would make an object
// that whole views later fail to match, so no object is made. From 2.5 m the whole chair is integrated.
TEST(ObjectMap, NewObjectWaitsForADetectionWithinTheIntegratedDepth) {
  const PinholeCamera cam;
  ObjectMapConfig c = config();
  ASSERT_DOUBLE_EQ(c.behind_surface_quadratic_per_m, 0.006);
  const Eigen::Isometry3d T_WC = levelCameraPose(Eigen::Vector3d(0.0, 0.0, 0.6), 0.0);
  for (const double x : {3.6, 2.5}) {
    ObjectMap map(c, ClassTable());
    const BoxUnion chair = semexp_test::chair(x, 0.0);
    cv::Mat depth, labels;
    renderShapes(cam, T_WC, {&chair}, depth, labels);
    const FrameIntegration r = map.integrateFrame(cam, T_WC, depth, cv::Mat(), labels, {{1, 0u, kChair}});
    EXPECT_EQ(map.objects().size(), x < 3.0 ? 1u : 0u) << "chair at x = " << x;
    EXPECT_EQ(r.created.size(), x < 3.0 ? 1u : 0u);
  }
  c.behind_surface_quadratic_per_m = 0.0;  // no noise band: every depth is integrated
  ObjectMap map(c, ClassTable());
  const BoxUnion chair = semexp_test::chair(3.6, 0.0);
  cv::Mat depth, labels;
  renderShapes(cam, T_WC, {&chair}, depth, labels);
  map.integrateFrame(cam, T_WC, depth, cv::Mat(), labels, {{1, 0u, kChair}});
  EXPECT_EQ(map.objects().size(), 1u);
}

// sqrt(truncation / q): 2 cm chairs (8 cm truncation) reach 3.65 m >= d_bg = 3 m; 1 cm chairs only 2.58 m.
TEST(ObjectMap, IntegratedDepthMustReachTheBackgroundDistance) {
  ClassTable classes;
  EXPECT_EQ(ObjectMap(config(), classes).checkIntegratedDepth(3.0), "");
  classes.resolution_m["chair"] = 0.01;
  const std::string why = ObjectMap(config(), classes).checkIntegratedDepth(3.0);
  EXPECT_NE(why.find("chair"), std::string::npos) << why;
  EXPECT_NE(why.find("2.58"), std::string::npos) << why;
  EXPECT_EQ(ObjectMap(config(), classes).checkIntegratedDepth(2.5), "");
  ObjectMapConfig no_band = config();
  no_band.behind_surface_quadratic_per_m = 0.0;
  EXPECT_EQ(ObjectMap(no_band, classes).checkIntegratedDepth(3.0), "");
}

TEST(ObjectMap, GainImagesFollowEquationOne) {
  PinholeCamera cam;
  const ObjectMap map = twoObjects(cam);  // surfaces seen from ~0.65-0.75 m
  SphericalGrid grid;
  grid.width = 36;
  grid.height = 10;
  // Ray u = 18 points at azimuth +5 deg; place positions on it towards A's centre.
  const Eigen::Vector3d dir = grid.direction(18, 5);
  const Eigen::Vector3d far = kA.centre - 3.0 * dir, near = kA.centre - 0.8 * dir;
  std::vector<cv::Mat> gains, hits;
  map.computeGains({far, near}, grid, {}, 0.5, 10.0, gains, hits);
  ASSERT_EQ(gains.size(), 2u);
  ASSERT_EQ(gains[0].rows, 10);
  ASSERT_EQ(gains[0].cols, 36);
  EXPECT_NEAR(hits[0].at<float>(5, 18), 3.0 - kA.radius, 0.01);
  EXPECT_FLOAT_EQ(gains[0].at<float>(5, 18), 0.f);  // already seen from closer than 2.75 m
  EXPECT_NEAR(hits[1].at<float>(5, 18), 0.8 - kA.radius, 0.01);
  float d_node = 0.f;
  {
    TsdfRayHit h;
    ASSERT_TRUE(map.object(1)->tsdf.castRay(near.cast<float>(), dir.cast<float>(), 0.f, 10.f, h));
    d_node = h.min_distance_m;
  }
  EXPECT_GT(d_node, 0.55f);
  EXPECT_NEAR(gains[1].at<float>(5, 18), (d_node - 0.55) / 10.0, 0.002);
  EXPECT_FLOAT_EQ(hits[1].at<float>(0, 0), 10.f);  // a ray that misses everything
  // A caller-given occluder at 0.3 m hides the object.
  std::vector<float> max_depth(2 * 360, std::numeric_limits<float>::quiet_NaN());
  max_depth[360 + 5 * 36 + 18] = 0.3f;
  map.computeGains({far, near}, grid, max_depth, 0.5, 10.0, gains, hits);
  EXPECT_FLOAT_EQ(gains[1].at<float>(5, 18), 0.f);
  EXPECT_FLOAT_EQ(hits[1].at<float>(5, 18), 10.f);
  EXPECT_NEAR(hits[0].at<float>(5, 18), 3.0 - kA.radius, 0.01);
  EXPECT_DOUBLE_EQ(objectDistanceGain(2.0, 1.0, 0.5, 10.0), 0.1);
  EXPECT_DOUBLE_EQ(objectDistanceGain(2.0, 0.2, 0.5, 10.0), 0.15);
  EXPECT_DOUBLE_EQ(objectDistanceGain(0.4, 0.2, 0.5, 10.0), 0.0);
  EXPECT_DOUBLE_EQ(objectDistanceGain(2.0, 2.5, 0.5, 10.0), 0.0);
}

// A (r 0.25 m) and B (r 0.2 m) have centres 0.9 m apart: their surfaces lie 0.45 m apart, and the nearest
// centres of their surface voxels (2 cm, |sdf| under one voxel) within a voxel either side of that.
TEST(ObjectMap, TrackedSurfaceDistanceBetweenTwoSpheres) {
  PinholeCamera cam;
  const ObjectMap map = twoObjects(cam);
  const TsdfMap &a = map.object(1)->tsdf, &b = map.object(2)->tsdf;
  const double d = trackedSurfaceDistance(a, b, 0.6);
  EXPECT_NEAR(d, 0.45, 0.04);
  EXPECT_DOUBLE_EQ(trackedSurfaceDistance(b, a, 0.6), d);  // the same pairs of voxels either way
  EXPECT_TRUE(std::isinf(trackedSurfaceDistance(a, b, 0.4)));  // none under max_m
  EXPECT_DOUBLE_EQ(trackedSurfaceDistance(a, a, 0.1), 0.0);
  TsdfParams coarse = a.params();
  coarse.resolution_m = 0.04;
  EXPECT_THROW(trackedSurfaceDistance(a, TsdfMap(coarse), 0.6), std::invalid_argument);
}

// The binned search compares exactly the pairs the definition names: its answer equals a scan of every pair
// of tracked surface voxels (within max_m / resolution voxels per axis), at bounds that cut between the two
// spheres, reach just past them and take in everything.
TEST(ObjectMap, TrackedSurfaceDistanceIsTheNearestPairOfAllPairs) {
  PinholeCamera cam;
  const ObjectMap map = twoObjects(cam);
  const TsdfMap &a = map.object(1)->tsdf, &b = map.object(2)->tsdf;  // b lies along +y of a; a straddles 0
  const double res_m = a.params().resolution_m;
  const auto surface = [](const TsdfMap& m) {
    std::vector<Eigen::Vector3i> out;
    m.forEachVoxel([&](const Eigen::Vector3i& i, const TsdfVoxel& v) {
      if (m.isSurfaceVoxel(v, true)) out.push_back(i);
    });
    return out;
  };
  const std::vector<Eigen::Vector3i> sa = surface(a), sb = surface(b);
  ASSERT_GT(sa.size(), 100u);
  ASSERT_GT(sb.size(), 100u);
  // One scan of all pairs: the nearest pair at each Chebyshev distance c (voxels); a bound of r voxels per
  // axis admits the pairs of c <= r.
  std::vector<int> nearest_sq_at(1, std::numeric_limits<int>::max());
  for (const auto& i : sa)
    for (const auto& j : sb) {
      const Eigen::Vector3i d = j - i;
      const auto c = static_cast<std::size_t>(d.cwiseAbs().maxCoeff());
      if (c >= nearest_sq_at.size()) nearest_sq_at.resize(c + 1, std::numeric_limits<int>::max());
      nearest_sq_at[c] = std::min(nearest_sq_at[c], d.squaredNorm());
    }
  // -1 and 0: no pair; 0.1: the piece rule's default (none that close here); 0.45-0.6: around the gap.
  for (const double max_m : {-1.0, 0.0, 0.1, 0.3, 0.45, 0.5, 0.6, 2.0}) {
    const int r = static_cast<int>(std::ceil(max_m / res_m));
    int best_sq = std::numeric_limits<int>::max();
    for (int c = 0; c <= r && c < static_cast<int>(nearest_sq_at.size()); ++c)
      best_sq = std::min(best_sq, nearest_sq_at[static_cast<std::size_t>(c)]);
    const double d_m = std::sqrt(static_cast<double>(best_sq)) * res_m;
    const double expected = d_m < max_m ? d_m : std::numeric_limits<double>::infinity();
    EXPECT_EQ(trackedSurfaceDistance(a, b, max_m), expected) << "a to b, max_m " << max_m;
    EXPECT_EQ(trackedSurfaceDistance(b, a, max_m), expected) << "b to a, max_m " << max_m;
  }
}

TEST(ObjectMap, FloorDivRoundsTowardsMinusInfinity) {
  for (int b : {1, 2, 5, 16})
    for (int a = -40; a <= 40; ++a)
      EXPECT_EQ(floorDiv(a, b), static_cast<int>(std::floor(static_cast<double>(a) / b))) << a << " / " << b;
  EXPECT_EQ(floorDiv(std::numeric_limits<int>::min(), 16), std::numeric_limits<int>::min() / 16);
  EXPECT_EQ(floorDiv(std::numeric_limits<int>::min() + 1, 16), std::numeric_limits<int>::min() / 16);
  EXPECT_EQ(floorDiv(std::numeric_limits<int>::max(), 16), std::numeric_limits<int>::max() / 16);
}

// cellKey21 and pointCellKey21 (int_math.hpp), the keys of frontier retirement's cubes, frontier evidence's
// voxels and the way-out search's lattice: hand-packed keys, distinct keys for neighbouring cells on both sides
// of the origin, a point's key is its cell's, and index 2^20 wraps onto -2^20.
TEST(ObjectMap, CellKeysPackTwentyOneBitsPerAxis) {
  EXPECT_EQ(cellKey21(0, 0, 0), (std::uint64_t{1} << 20) | (std::uint64_t{1} << 41) | (std::uint64_t{1} << 62));
  EXPECT_EQ(cellKey21(-(1 << 20), -(1 << 20), -(1 << 20)), 0u);
  EXPECT_EQ(cellKey21(1, -1, 2), (std::uint64_t{(1 << 20) + 1}) | (std::uint64_t{(1 << 20) - 1} << 21) |
                                     (std::uint64_t{(1 << 20) + 2} << 42));
  std::set<std::uint64_t> keys;
  for (int x = -3; x <= 3; ++x)
    for (int y = -3; y <= 3; ++y)
      for (int z = -3; z <= 3; ++z) keys.insert(cellKey21(x, y, z));
  EXPECT_EQ(keys.size(), 343u);
  // 0.5 m cells: -0.01 m lies in cell -1, 0.49 m in cell 0, 1.0 m in cell 2.
  EXPECT_EQ(pointCellKey21(-0.01, 0.49, 1.0, 0.5), cellKey21(-1, 0, 2));
  EXPECT_EQ(cellKey21(1 << 20, 0, 0), cellKey21(-(1 << 20), 0, 0));
}

TEST(ObjectMap, SaveWritesMeshesAndIndex) {
  PinholeCamera cam;
  // Ten views of each sphere see each surface voxel three or four times: with mesh_min_weight 4 little
  // of it is meshed, with 0 all of it.
  ObjectMapConfig every_voxel = config();
  every_voxel.mesh_min_weight = 0.0;
  const ObjectMap map = twoObjects(cam, every_voxel);
  const auto dir = std::filesystem::temp_directory_path() / ("semexp_objmap_" + std::to_string(::getpid()));
  std::string error;
  const auto files = map.save((dir / "run").string(), 1.0, &error);
  EXPECT_EQ(error, "");
  ASSERT_EQ(files.size(), 3u);
  Mesh m;
  ASSERT_TRUE(readPly(files[0], m));
  EXPECT_GT(m.triangles.size(), 100u);
  // The saved mesh is the one the map gives (and publishes), under the configured minimum weight and under
  // the configured SDF error gate (asking w >= 4.5 of voxels seen at the noise floor, 5 mm).
  ObjectMapConfig four = config(), gated = config();
  four.mesh_min_weight = 4.0;
  gated.mesh_max_sdf_std_m = 0.005 / std::sqrt(4.5);
  for (const auto& [name, c] : {std::make_pair("sparse", four), std::make_pair("gated", gated)}) {
    const ObjectMap sparse = twoObjects(cam, c);
    const auto sparse_files = sparse.save((dir / name).string(), 1.0, &error);
    ASSERT_EQ(sparse_files.size(), 3u) << name;
    Mesh s;
    ASSERT_TRUE(readPly(sparse_files[0], s)) << name;
    EXPECT_EQ(s.triangles.size(), sparse.mesh(*sparse.object(1)).triangles.size()) << name;
    EXPECT_LT(s.triangles.size(), m.triangles.size() / 2) << name;
  }
  std::ifstream f(files[2]);
  const std::string json((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_NE(json.find("\"class_name\": \"chair\""), std::string::npos);
  EXPECT_NE(json.find("object_2_chair.ply"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(ObjectMap, BoundsMustFitTheVoxelKeys) {
  const ObjectMap map{ObjectMapConfig(), ClassTable()};  // chairs at 2 cm: 10485.74 m
  Bounds b;
  EXPECT_EQ(map.checkBounds(b, 10.0), "");
  b.max_m = {5e5, 5e6, 3.0};  // UTM-like
  const std::string why = map.checkBounds(b, 10.0);
  EXPECT_NE(why.find("chair map at 0.020000 m holds at most 10485.740000 m"), std::string::npos) << why;
  b.max_m = {10470.0, 10.0, 3.0};
  EXPECT_NE(map.checkBounds(b, 16.0), "");  // 10486 m with the sensor range
  EXPECT_EQ(map.checkBounds(b, 15.0), "");
}

}  // namespace

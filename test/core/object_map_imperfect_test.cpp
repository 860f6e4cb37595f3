// Object maps from imperfect detections on constructed frames (issue 13):
// masks that bleed onto the background, detections missed in every second
// frame, and a bled mask that covers two neighbouring chairs. Each frame runs
// as the nodes run it (render, match, integrate: runFrame).

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "semexp_test/object_scenes.hpp"

using namespace semexp;
using namespace semexp_test;

namespace {

constexpr int kChair = 1;  // "chair" in the default class table
const Eigen::Vector3d kTarget(0.0, 0.0, 0.5);

// n poses on an arc of `radius` round `target` in front of it (-x side), from azimuth 180 - half_deg to
// 180 + half_deg, at height 1.2 m.
std::vector<Eigen::Isometry3d> arc(const Eigen::Vector3d& target, double radius, double half_deg, int n) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < n; ++i) {
    const double a = M_PI + (-half_deg + 2.0 * half_deg * i / (n - 1)) * M_PI / 180.0;
    poses.push_back(lookAt(Eigen::Vector3d(target.x() + radius * std::cos(a), target.y() + radius * std::sin(a), 1.2),
                           target));
  }
  return poses;
}

// The mask of `labels == label` grown by `px` pixels (a detector's mask bleeding over the object's border).
cv::Mat bled(const cv::Mat& labels, int label, int px) {
  cv::Mat mask = labels == label;
  if (px > 0) cv::dilate(mask, mask, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * px + 1, 2 * px + 1)));
  return mask;
}

cv::Mat instances(const std::vector<std::pair<cv::Mat, std::uint16_t>>& masks, cv::Size size) {
  cv::Mat image = cv::Mat::zeros(size, CV_16UC1);
  for (const auto& m : masks) image.setTo(m.second, m.first);
  return image;
}

// Share of the vertices within `tol_m` of the shape.
double shareOn(const std::vector<Eigen::Vector3f>& vertices_W, const Shape& shape, double tol_m) {
  size_t on = 0;
  for (const auto& v : vertices_W) on += std::abs(shape.sdf(v.cast<double>())) < tol_m;
  return vertices_W.empty() ? 0.0 : static_cast<double>(on) / vertices_W.size();
}

// Share of the tracked surface voxels (foreground over TsdfParams::trackedForeground(): what the render shows)
// whose centres lie within `tol_m` of the shape.
double trackedShareOn(const TsdfMap& tsdf, const Shape& shape, double tol_m) {
  size_t all = 0, on = 0;
  tsdf.forEachVoxel([&](const Eigen::Vector3i& index, const TsdfVoxel& vx) {
    if (!tsdf.isSurfaceVoxel(vx, true)) return;
    ++all;
    on += std::abs(shape.sdf(tsdf.voxelCentre(index).cast<double>())) < tol_m;
  });
  return all == 0 ? 0.0 : static_cast<double>(on) / all;
}

// A wall 1 m behind the back of a chair standing at the origin.
const Box kWall(Eigen::Vector3d(1.22, -3.0, -1.0), Eigen::Vector3d(1.32, 3.0, 3.0));

TEST(ObjectMapImperfect, MaskBledOntoAWallBehindLeavesTheChairsMeshOnTheChair) {
  PinholeCamera cam;
  const BoxUnion c = chair(0.0, 0.0);
  // The chair's mesh from exact masks (bleed 0 px), then from masks grown by 5 px: a ring of them lies on the
  // wall 1 m behind the chair.
  std::vector<Mesh> meshes;
  for (const int bleed_px : {0, 5}) {
    ObjectMap map{objectMapConfigWithPrior(), ClassTable()};
    for (const auto& T_WC : arc(kTarget, 1.5, 50.0, 9)) {
      cv::Mat depth, labels;
      renderShapes(cam, T_WC, {&c, &kWall}, depth, labels);
      ASSERT_GT(cv::countNonZero(labels == 1), 2000);
      runFrame(map, cam, T_WC, depth, instances({{bled(labels, 1, bleed_px), 1}}, depth.size()), {1}, kChair);
    }
    ASSERT_EQ(map.objects().size(), 1u);
    meshes.push_back(map.objects().begin()->second->tsdf.extractMesh());
  }
  const Mesh& exact = meshes[0];
  const Mesh& mesh = meshes[1];
  ASSERT_GT(exact.vertices_W.size(), 1500u);
  EXPECT_LT(rmse(exact.vertices_W, c), 0.01);
  size_t on_wall = 0;
  for (const auto& v : mesh.vertices_W) on_wall += kWall.sdf(v.cast<double>()) < 0.1;
  EXPECT_EQ(on_wall, 0u) << "of " << mesh.vertices_W.size() << " vertices";
  EXPECT_LT(rmse(mesh.vertices_W, c), 0.02);
  // The pixels behind the mask's depth edges are left out, not the chair: near all of it is there.
  EXPECT_GT(mesh.vertices_W.size(), 0.9 * exact.vertices_W.size()) << exact.vertices_W.size() << " from exact masks";
}

// A chair on a floor, detected in every frame; every second mask bleeds 5 px
// (a bleed probability of 0.5). Round the legs the bled ring lies on the floor
// at the chair's own depth: no depth edge keeps it out. Inside the mask in
// half the detections only, and at the mask's border when it is, the ring must
// stay under foreground 0.5 (object_map/foreground_border_px).
struct FloorBleed {
  size_t vertices = 0, on_floor = 0, ring = 0;
  double rmse_m = NAN;
};
FloorBleed chairOnFloorBledInHalfTheFrames(const ObjectMapConfig& config) {
  PinholeCamera cam;
  const BoxUnion c = chair(0.0, 0.0);
  const Box floor(Eigen::Vector3d(-3.0, -3.0, -0.1), Eigen::Vector3d(3.0, 3.0, 0.0));
  ObjectMap map{config, ClassTable()};
  const auto poses = arc(kTarget, 2.0, 60.0, 16);
  for (size_t i = 0; i < poses.size(); ++i) {
    cv::Mat depth, labels;
    renderShapes(cam, poses[i], {&c, &floor}, depth, labels);
    EXPECT_GT(cv::countNonZero(labels == 1), 1500);
    runFrame(map, cam, poses[i], depth, instances({{bled(labels, 1, i % 2 ? 5 : 0), 1}}, depth.size()), {1}, kChair);
  }
  FloorBleed r;
  EXPECT_EQ(map.objects().size(), 1u);
  if (map.objects().size() != 1u) return r;
  const Mesh mesh = map.objects().begin()->second->tsdf.extractMesh();
  // Floor vertices more than 3 cm (1.5 voxels) from the chair; the ring: those within 10 cm of it.
  for (const auto& v : mesh.vertices_W) {
    const double d = c.sdf(v.cast<double>());
    if (std::abs(floor.sdf(v.cast<double>())) >= 0.02 || d <= 0.03) continue;
    ++r.on_floor;
    r.ring += d < 0.1;
  }
  r.vertices = mesh.vertices_W.size();
  r.rmse_m = rmse(mesh.vertices_W, c);
  return r;
}

TEST(ObjectMapImperfect, MaskBledOntoTheFloorInHalfTheFramesLeavesNoRingInTheMesh) {
  ObjectMapConfig paper;  // the paper's foreground update (no prior)
  paper.foreground_prior = 0.5;
  paper.foreground_prior_weight = 0.0;
  const FloorBleed r = chairOnFloorBledInHalfTheFrames(paper);
  ASSERT_GT(r.vertices, 2000u);
  // With full evidence at the border (foreground_border_px 0): 215 ring and 421 floor vertices of 2691, 5.4 cm
  // RMSE; now 39 and 195 of 2444, 4.6 cm. What is left lies under the seat, 10-40 cm from the legs: floor
  // seen through the gap between the legs in a few (bled) frames only, which later frames never contradict.
  EXPECT_LT(r.ring, r.vertices / 50) << "of " << r.vertices << " vertices";
  EXPECT_LT(r.on_floor, r.vertices / 10) << "of " << r.vertices << " vertices";
  EXPECT_LT(r.rmse_m, 0.05);
}

// The floor seen in a few bled detections only: a foreground prior of 0.3
// with the weight of 2 observations (object_map/foreground_prior) needs more
// than those to lift it over 0.5. Measured: no floor vertex of 2204, 3.5 mm
// RMSE (prior weight 1: 38 floor vertices, 2.3 cm).
TEST(ObjectMapImperfect, ForegroundPriorKeepsFloorSeenInFewBledFramesOutOfTheMesh) {
  const FloorBleed r = chairOnFloorBledInHalfTheFrames(objectMapConfigWithPrior());
  ASSERT_GT(r.vertices, 2000u);
  EXPECT_LT(r.on_floor, r.vertices / 200) << "of " << r.vertices << " vertices";
  EXPECT_EQ(r.ring, 0u) << "of " << r.vertices << " vertices";
  EXPECT_LT(r.rmse_m, 0.01);
}

TEST(ObjectMapImperfect, DetectionMissedInEverySecondFrameIsOneObject) {
  PinholeCamera cam;
  const BoxUnion c = chair(0.0, 0.0);
  // Round the chair in 30 deg steps; detected in every frame, or in every second frame only (60 deg apart),
  // where the frames between update the object as a visible undetected one.
  const auto poses = ring(kTarget, 1.5, 0.7, 12);
  const auto fly = [&](bool every_second) {
    ObjectMap map{objectMapConfigWithPrior(), ClassTable()};
    for (size_t i = 0; i < poses.size(); ++i) {
      cv::Mat depth, labels;
      renderShapes(cam, poses[i], {&c}, depth, labels);
      const bool detected = !every_second || i % 2 == 0;
      const cv::Mat image = detected ? instances({{labels == 1, 1}}, depth.size()) : instances({}, depth.size());
      const FrameIntegration r = runFrame(map, cam, poses[i], depth, image,
                                          detected ? std::vector<std::uint16_t>{1} : std::vector<std::uint16_t>{},
                                          kChair);
      if (i > 0) {
        EXPECT_TRUE(r.created.empty()) << "frame " << i;
      }
      EXPECT_EQ(map.objects().size(), 1u) << "frame " << i;
    }
    return map;
  };
  const ObjectMap map = fly(true);
  ASSERT_EQ(map.objects().size(), 1u);
  const MappedObject& o = *map.objects().begin()->second;
  EXPECT_EQ(o.detection_count, 6u);
  EXPECT_EQ(o.undetected_count, 6u);
  const Mesh mesh = o.tsdf.extractMesh();
  EXPECT_LT(rmse(mesh.vertices_W, c), 0.02);
  // Most of the chair's mesh, not a fragment: the undetected frames lower the foreground of what they see
  // (the paper's update), so the mesh keeps fewer vertices than the same frames give when every one is
  // detected (73% when this was written: 2,000 of 2,757); at least 70% is asked.
  const ObjectMap every = fly(false);
  ASSERT_EQ(every.objects().size(), 1u);
  const std::size_t all = every.objects().begin()->second->tsdf.extractMesh().vertices_W.size();
  EXPECT_GT(all, 2000u);
  EXPECT_GE(mesh.vertices_W.size(), 0.7 * all);
}

// The pixels of `mask` whose depth puts them above (z_W > z_m) or below the height z_m.
cv::Mat aboveOrBelow(const cv::Mat& mask, const cv::Mat& depth_m, const PinholeCamera& cam, const Eigen::Isometry3d& T_WC,
                     double z_m, bool above) {
  cv::Mat out = cv::Mat::zeros(mask.size(), CV_8UC1);
  for (int v = 0; v < mask.rows; ++v)
    for (int u = 0; u < mask.cols; ++u) {
      const float d = depth_m.at<float>(v, u);
      if (!mask.at<std::uint8_t>(v, u) || !(d > 0)) continue;
      const Eigen::Vector3d p_C((u - cam.cx) / cam.fx * d, (v - cam.cy) / cam.fy * d, d);
      if (((T_WC * p_C).z() > z_m) == above) out.at<std::uint8_t>(v, u) = 255;
    }
  return out;
}

// The object map with the foreground prior and object_map/piece_max_share = share.
ObjectMapConfig withPieceShare(double share) {
  ObjectMapConfig config = objectMapConfigWithPrior();
  config.piece_max_share = share;
  return config;
}

// A chair first detected without the top of its back (object 1: the back
// was hidden, say, by a table), then from a view where only that top showed:
// the detection matches nothing rendered and makes object 2. In the frames
// after, the whole chair is detected: matched to object 1 as a matcher would,
// or (match_to_piece) to object 2, the piece. The other object renders inside
// the mask but sticks out of the detected one's box, so the box rule does not
// merge them, while its pixels keep the detected object from growing there.
// Their surfaces touch, and the top holds a small share of the chair's voxels.
struct PieceRun {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> merged;  // (merged, into) over all frames
  std::vector<std::string> reasons;                             // FrameIntegration::merge_reasons, likewise
  std::vector<std::uint32_t> ids;                               // the objects left
  double rmse_m = NAN, top_m = -1.0;                            // the mesh of the first object left
};
PieceRun chairFoundInTwoPieces(double piece_max_share, bool match_to_piece) {
  PinholeCamera cam;
  const BoxUnion c = chair(0.0, 0.0);
  ObjectMap map{withPieceShare(piece_max_share), ClassTable()};
  PieceRun run;
  const auto poses = arc(kTarget, 1.8, 40.0, 9);
  for (size_t i = 0; i < poses.size(); ++i) {
    cv::Mat depth, labels;
    renderShapes(cam, poses[i], {&c}, depth, labels);
    cv::Mat mask = labels == 1;
    if (i == 0) mask = aboveOrBelow(mask, depth, cam, poses[i], 0.8, false);
    if (i == 1) mask = aboveOrBelow(mask, depth, cam, poses[i], 0.8, true);
    EXPECT_GT(cv::countNonZero(mask), 500) << "frame " << i;
    const cv::Mat image = instances({{mask, 1}}, depth.size());
    FrameIntegration r;
    if (i >= 2 && match_to_piece && map.object(2)) {
      cv::Mat rendered;
      map.render(cam, poses[i], depth, rendered);
      r = map.integrateFrame(cam, poses[i], depth, cv::Mat(), image, {{1, 2u, kChair}}, &rendered);
    } else {
      r = runFrame(map, cam, poses[i], depth, image, {1}, kChair);
    }
    if (i == 1) {
      EXPECT_EQ(r.created, std::vector<std::uint32_t>{2u}) << "the top alone did not make an object of its own";
    }
    run.merged.insert(run.merged.end(), r.merged.begin(), r.merged.end());
    run.reasons.insert(run.reasons.end(), r.merge_reasons.begin(), r.merge_reasons.end());
  }
  for (const auto& kv : map.objects()) run.ids.push_back(kv.first);
  if (run.ids.empty()) return run;
  const Mesh mesh = map.objects().begin()->second->tsdf.extractMesh();
  run.rmse_m = rmse(mesh.vertices_W, c);
  for (const auto& v : mesh.vertices_W) run.top_m = std::max(run.top_m, static_cast<double>(v.z()));
  return run;
}

TEST(ObjectMapImperfect, PieceOutsideTheObjectsBoxThatTouchesItIsMergedIntoIt) {
  const PieceRun on = chairFoundInTwoPieces(0.3, false);
  // The top (object 2) joined the chair's object (1), not the other way round.
  ASSERT_EQ(on.merged, (std::vector<std::pair<std::uint32_t, std::uint32_t>>{{2u, 1u}}));
  ASSERT_EQ(on.ids, std::vector<std::uint32_t>{1u});
  ASSERT_EQ(on.reasons.size(), 1u);
  EXPECT_EQ(on.reasons[0].rfind("a piece: ", 0), 0u) << on.reasons[0];
  EXPECT_LT(on.rmse_m, 0.02);
  EXPECT_GT(on.top_m, 0.9) << "the merged object holds the top of the back";
  // With the rule off (share 0) the same frames leave the top an object of its own: the box rule does not merge it.
  const PieceRun off = chairFoundInTwoPieces(0.0, false);
  EXPECT_TRUE(off.merged.empty());
  EXPECT_EQ(off.ids, (std::vector<std::uint32_t>{1u, 2u}));
}

// The same frames with the whole chair's detections matched to the piece: the
// chair's object is the larger one and keeps its id; the piece joins it.
TEST(ObjectMapImperfect, WholeObjectsDetectionMatchedToItsPieceKeepsTheWholeObjectsId) {
  const PieceRun r = chairFoundInTwoPieces(0.3, true);
  ASSERT_EQ(r.merged, (std::vector<std::pair<std::uint32_t, std::uint32_t>>{{2u, 1u}}));
  ASSERT_EQ(r.reasons.size(), 1u);
  EXPECT_NE(r.reasons[0].find("the larger keeps its id"), std::string::npos) << r.reasons[0];
  ASSERT_EQ(r.ids, std::vector<std::uint32_t>{1u});
  EXPECT_LT(r.rmse_m, 0.02);
  EXPECT_GT(r.top_m, 0.9);
}

// A bench 1.7 m long and a 14 cm cube `gap_m` in front of it (towards the
// cameras), 0.45 m in from the bench's left end, each detected alone in four
// frames, then under one mask bled over both, which matches the bench. The
// cube renders inside that mask, past the bench's box, and is small. From the
// cube the bench reaches both ways along the line between their centroids,
// so the mask gap (separateMasks) is negative whether the cube touches the
// bench or stands apart (-0.39 and -0.06 m when this test was written): the
// distance between their surfaces in 3D (object_map/piece_max_distance_m)
// tells them apart.
std::vector<std::pair<std::uint32_t, std::uint32_t>> cubeInFrontOfABench(double gap_m,
                                                                          double piece_max_distance_m = 0.1) {
  PinholeCamera cam;
  const Box bench(Eigen::Vector3d(0.0, -0.8, 0.4), Eigen::Vector3d(0.1, 0.9, 0.7));
  const Box cube = Box::around(Eigen::Vector3d(-gap_m - 0.07, -0.35, 0.55), Eigen::Vector3d(0.07, 0.07, 0.07));
  ObjectMapConfig config = objectMapConfigWithPrior();
  config.piece_max_distance_m = piece_max_distance_m;
  ObjectMap map{config, ClassTable()};
  const auto poses = arc(Eigen::Vector3d(0.0, 0.05, 0.55), 1.8, 30.0, 5);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> merged;
  for (size_t i = 0; i < poses.size(); ++i) {
    cv::Mat depth, labels;
    renderShapes(cam, poses[i], {&bench, &cube}, depth, labels);
    EXPECT_GT(cv::countNonZero(labels == 2), 150) << "frame " << i;
    const bool bled_frame = i + 1 == poses.size();
    const cv::Mat masks = bled_frame ? instances({{bled(labels, 1, 5) | bled(labels, 2, 5), 1}}, depth.size())
                                     : instances({{labels == 1, 1}, {labels == 2, 2}}, depth.size());
    const FrameIntegration r = runFrame(map, cam, poses[i], depth, masks,
                                        bled_frame ? std::vector<std::uint16_t>{1} : std::vector<std::uint16_t>{1, 2},
                                        kChair);
    if (bled_frame) {
      EXPECT_EQ(r.detected, std::vector<std::uint32_t>{1u}) << "the bled mask matched the bench's object";
      const bool cube_seen = std::find(r.undetected.begin(), r.undetected.end(), 2u) != r.undetected.end();
      EXPECT_TRUE(cube_seen || !r.merged.empty()) << "the cube renders (undetected or merged)";
    } else {
      EXPECT_EQ(map.objects().size(), 2u) << "frame " << i;
    }
    merged.insert(merged.end(), r.merged.begin(), r.merged.end());
  }
  return merged;
}

TEST(ObjectMapImperfect, SmallObjectApartFromTheDetectedOneIsNotMergedAsAPiece) {
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> cube_into_bench{{2u, 1u}};
  // 20 cm apart in 3D: two objects.
  EXPECT_TRUE(cubeInFrontOfABench(0.2).empty());
  // With the 3D test widened past 20 cm the same frames merge them: every other test of the piece rule
  // passed, the 3D distance is what kept them apart.
  EXPECT_EQ(cubeInFrontOfABench(0.2, 0.3), cube_into_bench);
  // Touching: a piece of the bench.
  EXPECT_EQ(cubeInFrontOfABench(0.0), cube_into_bench);
}

// Two chairs side by side 1 cm apart (their seats nearly touch), each
// detected with its own mask but in one frame, where a single mask bled over
// both is matched to chair a's object. Chair b's object renders inside that
// mask and reaches past a's box, and their surfaces touch: only their sizes
// tell them from a piece and its object (object_map/piece_max_share).
TEST(ObjectMapImperfect, TouchingNeighbourUnderABledMaskIsNotMergedAsAPiece) {
  PinholeCamera cam;
  const BoxUnion a = chair(0.0, -0.225), b = chair(0.0, 0.225);
  const auto poses = arc(kTarget, 1.8, 40.0, 9);
  for (const double share : {0.3, 0.99}) {
    SCOPED_TRACE("piece_max_share " + std::to_string(share));
    ObjectMap map{withPieceShare(share), ClassTable()};
    size_t merged = 0;
    for (size_t i = 0; i < poses.size(); ++i) {
      cv::Mat depth, labels;
      renderShapes(cam, poses[i], {&a, &b, &kWall}, depth, labels);
      ASSERT_GT(cv::countNonZero(labels == 1), 1500);
      ASSERT_GT(cv::countNonZero(labels == 2), 1500);
      const cv::Mat masks = i == 4 ? instances({{bled(labels, 1, 5) | bled(labels, 2, 5), 1}}, depth.size())
                                   : instances({{labels == 1, 1}, {labels == 2, 2}}, depth.size());
      const FrameIntegration r = runFrame(map, cam, poses[i], depth, masks, i == 4 ? std::vector<std::uint16_t>{1}
                                                                                   : std::vector<std::uint16_t>{1, 2},
                                          kChair);
      merged += r.merged.size();
      if (i == 3) {
        ASSERT_EQ(map.objects().size(), 2u) << "each chair has its object before the bled frame";
      }
    }
    if (share < 0.5) {
      EXPECT_EQ(merged, 0u);
      EXPECT_EQ(map.objects().size(), 2u);
    } else {
      // A share that admits objects of a size takes the two chairs for one: the sizes are what keeps them apart.
      EXPECT_EQ(merged, 1u);
      EXPECT_EQ(map.objects().size(), 1u);
    }
  }
}

// Two chairs side by side, 16 cm apart, in front of the wall. One frame has a
// single mask over both (bled 5 px, across the gap); the others one mask per
// chair. The bled frame comes first (one object is made of both chairs) or
// after four clean frames.
TEST(ObjectMapImperfect, BledMaskOverTwoChairsEndsAsTwoObjects) {
  PinholeCamera cam;
  const BoxUnion a = chair(0.0, -0.3), b = chair(0.0, 0.3);
  const auto poses = arc(kTarget, 1.8, 40.0, 9);
  for (const size_t bled_frame : {size_t{0}, size_t{4}}) {
    SCOPED_TRACE("bled frame " + std::to_string(bled_frame));
    ObjectMap map{objectMapConfigWithPrior(), ClassTable()};
    for (size_t i = 0; i < poses.size(); ++i) {
      cv::Mat depth, labels;
      renderShapes(cam, poses[i], {&a, &b, &kWall}, depth, labels);
      ASSERT_GT(cv::countNonZero(labels == 1), 1500);
      ASSERT_GT(cv::countNonZero(labels == 2), 1500);
      if (i == bled_frame) {
        const cv::Mat both = bled(labels, 1, 5) | bled(labels, 2, 5);
        runFrame(map, cam, poses[i], depth, instances({{both, 1}}, depth.size()), {1}, kChair);
      } else {
        const FrameIntegration r = runFrame(
            map, cam, poses[i], depth, instances({{labels == 1, 1}, {labels == 2, 2}}, depth.size()), {1, 2}, kChair);
        // After a first bled frame, the first frame with two masks splits the object made of both chairs.
        if (bled_frame == 0 && i == 1) {
          EXPECT_EQ(r.split.size(), 1u);
        } else {
          EXPECT_TRUE(r.split.empty()) << "frame " << i;
        }
      }
    }
    EXPECT_EQ(map.objects().size(), 2u);
    if (map.objects().size() != 2u) continue;
    // Each object lies on one chair, and each chair holds one object.
    int on_a = 0, on_b = 0;
    for (const auto& kv : map.objects()) {
      const Mesh mesh = kv.second->tsdf.extractMesh();
      ASSERT_GT(mesh.vertices_W.size(), 1000u) << "object " << kv.first;
      const double share_a = shareOn(mesh.vertices_W, a, 0.03), share_b = shareOn(mesh.vertices_W, b, 0.03);
      EXPECT_GT(std::max(share_a, share_b), 0.98) << "object " << kv.first << ": " << share_a << " on a, "
                                                  << share_b << " on b";
      on_a += share_a > share_b;
      on_b += share_b > share_a;
      EXPECT_LT(rmse(mesh.vertices_W, share_a > share_b ? a : b), 0.02) << "object " << kv.first;
    }
    EXPECT_EQ(on_a, 1);
    EXPECT_EQ(on_b, 1);
  }
}

// The object made of both chairs (a first, bled frame) is seen next with a
// mask of chair a and a 7 x 7 px patch of chair b: the patch lies apart, so
// it would start an object of its own, but 49 px are too few to keep one
// (object_map/min_new_object_pixels 100). The map's object must then keep
// chair b's surface: it forgets that side only for a split-off object it keeps.
TEST(ObjectMapImperfect, SplitOffTooSmallToKeepLeavesTheObjectWhole) {
  PinholeCamera cam;
  const BoxUnion a = chair(0.0, -0.3), b = chair(0.0, 0.3);
  const auto poses = arc(kTarget, 1.8, 40.0, 9);
  ObjectMap map{objectMapConfigWithPrior(), ClassTable()};
  MatchingConfig matching;
  matching.min_mask_pixels = 20;  // lets the patch through matching to the object map
  cv::Mat depth, labels;
  renderShapes(cam, poses[0], {&a, &b, &kWall}, depth, labels);
  runFrame(map, cam, poses[0], depth, instances({{bled(labels, 1, 5) | bled(labels, 2, 5), 1}}, depth.size()), {1},
           kChair, matching);
  ASSERT_EQ(map.objects().size(), 1u);
  const std::uint32_t id = map.objects().begin()->first;
  // The tracked surface, not the mesh: with the foreground prior one frame outside the mask already takes
  // chair b's surface out of the mesh, but it stays rendered (and matched) as the object's until forgotten.
  const auto on_b = [&] { return trackedShareOn(map.objects().at(id)->tsdf, b, 0.03); };
  const double before = on_b();
  ASSERT_GT(before, 0.2);  // the object holds chair b's surface

  renderShapes(cam, poses[1], {&a, &b, &kWall}, depth, labels);
  cv::Mat patch = cv::Mat::zeros(labels.size(), CV_8UC1);
  cv::Moments m = cv::moments(labels == 2, true);
  ASSERT_GT(m.m00, 1500);
  const cv::Point c(static_cast<int>(m.m10 / m.m00), static_cast<int>(m.m01 / m.m00));
  patch(cv::Rect(c.x - 3, c.y - 3, 7, 7)).setTo(255);
  patch &= (labels == 2);
  ASSERT_EQ(cv::countNonZero(patch), 49);
  const FrameIntegration r =
      runFrame(map, cam, poses[1], depth, instances({{labels == 1, 1}, {patch, 2}}, depth.size()), {1, 2}, kChair,
               matching);
  EXPECT_TRUE(r.split.empty());
  EXPECT_EQ(r.dropped_empty, 1u);
  ASSERT_EQ(map.objects().size(), 1u);
  // Chair b's tracked surface is still the object's: 0.474 of its tracked voxels lie on b, against 0.485
  // before (this frame's mask of chair a lowers the foreground of the rest of the object's render, but one
  // such frame leaves it above the prior). Dropping the side for the erased split-off object leaves 0.121.
  EXPECT_GT(on_b(), 0.8 * before);
}

}  // namespace

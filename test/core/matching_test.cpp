// Instance matching on synthetic masks (policy in instance_matching.hpp).

#include <gtest/gtest.h>

#include <stdexcept>

#include "semantic_exploration/core/instance_matching.hpp"

using namespace semexp;

namespace {

cv::Mat blank() { return cv::Mat::zeros(100, 100, CV_16UC1); }
void fill(cv::Mat& img, int col0, int col1, int row0, int row1, std::uint16_t value) {  // inclusive ranges
  img(cv::Range(row0, row1 + 1), cv::Range(col0, col1 + 1)).setTo(value);
}

struct Scene {
  cv::Mat det = blank(), obj = blank();
  Scene() { fill(obj, 10, 29, 10, 29, 5); }  // object 5: 20 x 20 = 400 px
};

MatchingConfig config() {
  MatchingConfig c;
  c.iou_threshold = 0.25;
  c.min_mask_pixels = 100;
  c.fragment_fraction = 0.8;
  return c;
}

TEST(Matching, ExactOverlap) {
  Scene s;
  fill(s.det, 10, 29, 10, 29, 1);
  const auto out = matchDetections(s.det, {1}, s.obj, config());
  ASSERT_EQ(out.detections.size(), 1u);
  EXPECT_EQ(out.detections[0].object_id, 5u);
  EXPECT_FLOAT_EQ(out.detections[0].iou, 1.f);
  EXPECT_EQ(out.detections[0].mask_pixels, 400u);
  EXPECT_FALSE(out.detections[0].dropped);
  EXPECT_FALSE(out.detections[0].fragment);
}

TEST(Matching, PartialOverlapAboveThreshold) {
  Scene s;
  fill(s.det, 15, 34, 10, 29, 1);  // 15 of 20 columns overlap: 300 / 500
  const auto r = matchDetections(s.det, {1}, s.obj, config()).detections[0];
  EXPECT_EQ(r.object_id, 5u);
  EXPECT_FLOAT_EQ(r.iou, 0.6f);
}

TEST(Matching, PartialOverlapBelowThresholdIsNew) {
  Scene s;
  fill(s.det, 26, 45, 10, 29, 1);  // 4 columns overlap: 80 / 720
  const auto r = matchDetections(s.det, {1}, s.obj, config()).detections[0];
  EXPECT_EQ(r.object_id, 0u);
  EXPECT_FLOAT_EQ(r.iou, 0.f);
  EXPECT_EQ(r.mask_pixels, 400u);
}

TEST(Matching, TwoDetectionsCompeteHigherIouWinsLoserIsNew) {
  Scene s;
  fill(s.det, 10, 19, 10, 29, 1);  // left half of object 5: IoU 200/400 = 0.5
  fill(s.det, 20, 37, 10, 29, 2);  // right half + 8 columns outside: IoU 200/560 = 0.357, 56% on it
  const auto out = matchDetections(s.det, {2, 1}, s.obj, config());
  ASSERT_EQ(out.detections.size(), 2u);
  EXPECT_EQ(out.detections[0].instance_id, 2);  // input order kept
  EXPECT_EQ(out.detections[1].object_id, 5u);
  EXPECT_FLOAT_EQ(out.detections[1].iou, 0.5f);
  EXPECT_EQ(out.detections[0].object_id, 0u);
  EXPECT_FALSE(out.detections[0].fragment);
}

TEST(Matching, CompetitionLoserFallsBackToItsNextBestObject) {
  Scene s;
  fill(s.obj, 30, 49, 10, 29, 7);  // object 7 right of object 5
  fill(s.det, 10, 19, 10, 29, 1);  // IoU with 5: 0.5
  fill(s.det, 20, 37, 10, 29, 2);  // IoU with 5: 200/560 = 0.357, with 7: 160/600 = 0.267
  const auto out = matchDetections(s.det, {1, 2}, s.obj, config());
  EXPECT_EQ(out.detections[0].object_id, 5u);
  EXPECT_EQ(out.detections[1].object_id, 7u);
  EXPECT_NEAR(out.detections[1].iou, 160.0 / 600.0, 1e-6);
}

TEST(Matching, CompetitionLoserLyingOnTheObjectIsAFragmentOfIt) {
  Scene s;
  fill(s.det, 10, 21, 10, 29, 1);  // 240 px, IoU 0.6
  fill(s.det, 22, 29, 10, 29, 2);  // 160 px wholly on object 5, IoU 0.4
  const auto out = matchDetections(s.det, {1, 2}, s.obj, config());
  EXPECT_EQ(out.detections[0].object_id, 5u);
  EXPECT_FALSE(out.detections[0].fragment);
  EXPECT_EQ(out.detections[1].object_id, 5u);
  EXPECT_TRUE(out.detections[1].fragment);
  EXPECT_FLOAT_EQ(out.detections[1].iou, 0.4f);
}

TEST(Matching, SmallDetectionWhollyOnAnObjectIsAFragmentEvenBelowThreshold) {
  Scene s;
  fill(s.det, 12, 16, 12, 31, 1);  // 100 px, 80 on the object: IoU 80/420 < 0.25, 80% on it
  const auto r = matchDetections(s.det, {1}, s.obj, config()).detections[0];
  EXPECT_EQ(r.object_id, 5u);
  EXPECT_TRUE(r.fragment);
}

TEST(Matching, DetectionOnAnObjectRenderedInPiecesGoesToTheLargestPiece) {
  cv::Mat obj = blank(), det = blank();
  fill(obj, 10, 21, 10, 29, 3);  // one object rendered as two ids (e.g. duplicates): 240 + 160 px
  fill(obj, 22, 29, 10, 29, 4);
  fill(det, 10, 29, 10, 31, 1);  // 440 px, 91% on rendered objects; IoU with 3: 240/440
  auto r = matchDetections(det, {1}, obj, config()).detections[0];
  EXPECT_EQ(r.object_id, 3u);
  EXPECT_FALSE(r.fragment);
  MatchingConfig strict = config();
  strict.iou_threshold = 0.6;  // now no IoU match: the coverage rule takes it to the larger piece
  r = matchDetections(det, {1}, obj, strict).detections[0];
  EXPECT_EQ(r.object_id, 3u);
  EXPECT_TRUE(r.fragment);
  EXPECT_NEAR(r.iou, 240.0 / 440.0, 1e-6);
}

TEST(Matching, ObjectSeenOnlyInPartIsMatchedByADetectionCoveringItsRender) {
  cv::Mat obj = blank(), det = blank();
  fill(obj, 20, 29, 20, 29, 6);  // 100 px rendered (the part seen so far)
  fill(det, 10, 39, 10, 39, 1);  // 900 px detection around it: IoU 0.11
  const auto r = matchDetections(det, {1}, obj, config()).detections[0];
  EXPECT_EQ(r.object_id, 6u);
  EXPECT_TRUE(r.fragment);
  EXPECT_NEAR(r.iou, 100.0 / 900.0, 1e-6);
  cv::Mat tiny = blank();
  fill(tiny, 20, 23, 20, 23, 6);  // 16 px < min_mask_pixels / 4: too small to tell
  EXPECT_EQ(matchDetections(det, {1}, tiny, config()).detections[0].object_id, 0u);
}

TEST(Matching, DetectionSplitAcrossTwoObjectsGoesToHigherIou) {
  Scene s;
  fill(s.obj, 30, 39, 10, 29, 7);  // object 7: 200 px
  fill(s.det, 10, 39, 10, 29, 1);  // covers both: IoU 400/600 with 5, 200/600 with 7
  const auto r = matchDetections(s.det, {1}, s.obj, config()).detections[0];
  EXPECT_EQ(r.object_id, 5u);
  EXPECT_NEAR(r.iou, 2.0 / 3.0, 1e-6);
}

TEST(Matching, TinyMasksDroppedAndRemoved) {
  Scene s;
  fill(s.det, 10, 18, 10, 20, 1);  // 99 px, exactly on object 5
  fill(s.det, 50, 69, 50, 69, 2);  // 400 px on nothing
  fill(s.det, 80, 89, 80, 89, 9);  // not listed
  cv::Mat cleaned;
  const auto out = matchDetections(s.det, {1, 2}, s.obj, config(), &cleaned);
  EXPECT_TRUE(out.detections[0].dropped);
  EXPECT_EQ(out.detections[0].object_id, 0u);
  EXPECT_EQ(out.detections[0].mask_pixels, 99u);
  EXPECT_FALSE(out.detections[1].dropped);
  EXPECT_EQ(out.detections[1].object_id, 0u);
  EXPECT_EQ(out.unlisted_pixels, 100u);
  EXPECT_EQ(cv::countNonZero(cleaned == 1), 0);
  EXPECT_EQ(cv::countNonZero(cleaned == 9), 0);
  EXPECT_EQ(cv::countNonZero(cleaned == 2), 400);
}

TEST(Matching, BadInput) {
  Scene s;
  fill(s.det, 10, 29, 10, 29, 1);
  EXPECT_THROW(matchDetections(cv::Mat::zeros(50, 100, CV_16UC1), {1}, s.obj, config()), std::invalid_argument);
  EXPECT_THROW(matchDetections(cv::Mat::zeros(100, 100, CV_8UC1), {1}, s.obj, config()), std::invalid_argument);
  const auto out = matchDetections(s.det, {1, 1, 0}, s.obj, config());
  EXPECT_EQ(out.detections.size(), 1u);
  EXPECT_EQ(out.duplicate_ids, 2u);
  EXPECT_EQ(matchDetections(s.det, {}, s.obj, config()).unlisted_pixels, 400u);
}

}  // namespace

// Object ids: 16-bit, so ids of objects that are gone come back (ObjectIdPool),
// and a long run with one empty candidate per frame still creates objects.

#include <gtest/gtest.h>

#include "semantic_exploration/core/object_id_pool.hpp"
#include "semantic_exploration/core/object_map.hpp"
#include "semexp_test/cameras.hpp"
#include "semexp_test/rendering.hpp"

using namespace semexp;
using namespace semexp_test;

TEST(ObjectIdPool, UnpublishedIdsComeBackAtOncePublishedOnesAfterTheDelay) {
  ObjectIdPool ids(3, 10);  // ids 1 .. 3, published ids rest 10 frames
  EXPECT_EQ(ids.acquire(0), 1u);
  EXPECT_EQ(ids.acquire(0), 2u);
  ids.releaseUnpublished(2);      // a candidate erased in its own frame
  EXPECT_EQ(ids.acquire(1), 2u);  // the next frame has it again
  EXPECT_EQ(ids.acquire(1), 3u);
  EXPECT_EQ(ids.acquire(1), 0u);  // all three in use
  ids.release(1, 5);              // object 1 merged into another at frame 5
  EXPECT_EQ(ids.acquire(14), 0u);  // a detection matched against an older render may still name 1
  EXPECT_EQ(ids.acquire(15), 1u);
  EXPECT_EQ(ids.acquire(15), 0u);
}

TEST(ObjectIdPool, FreshIdsGoFirstThenTheOldestReleased) {
  ObjectIdPool ids(4, 0);
  EXPECT_EQ(ids.acquire(0), 1u);
  EXPECT_EQ(ids.acquire(0), 2u);
  ids.release(2, 0);
  ids.release(1, 0);
  EXPECT_EQ(ids.acquire(0), 3u);  // ids never used come before released ones
  EXPECT_EQ(ids.acquire(0), 4u);
  EXPECT_EQ(ids.acquire(0), 2u);  // then in the order of release
  EXPECT_EQ(ids.acquire(0), 1u);
  EXPECT_EQ(ids.acquire(0), 0u);
}

TEST(ObjectMap, EmptyCandidatesInEveryFrameDoNotUseUpTheIds) {
  // A small camera keeps 65535 frames fast; a chair mask over all-zero depth (no valid pixel) is a candidate
  // that is erased in its own frame, as an out-of-range detection would be.
  const PinholeCamera cam = tinyCamera();
  ObjectMap map{ObjectMapConfig(), ClassTable()};
  constexpr int kChair = 1;
  const Sphere chair(Eigen::Vector3d(0.0, 0.0, 1.0), 0.25);
  const Eigen::Isometry3d T_WC = lookAt(Eigen::Vector3d(-0.9, 0.0, 1.0), chair.centre);
  cv::Mat depth, labels;
  renderShapes(cam, T_WC, {&chair}, depth, labels);
  ASSERT_GT(cv::countNonZero(labels), 400);
  const cv::Mat no_depth = cv::Mat::zeros(cam.height, cam.width, CV_32FC1);
  for (int k = 0; k < 65535; ++k) {
    const FrameIntegration r = map.integrateFrame(cam, T_WC, no_depth, cv::Mat(), labels, {{1, 0, kChair}});
    ASSERT_EQ(r.dropped_empty, 1u) << "frame " << k;
    ASSERT_EQ(r.dropped_full, 0u) << "frame " << k;
  }
  EXPECT_TRUE(map.objects().empty());
  const FrameIntegration r = map.integrateFrame(cam, T_WC, depth, cv::Mat(), labels, {{1, 0, kChair}});
  EXPECT_EQ(r.dropped_full, 0u);
  ASSERT_EQ(r.created.size(), 1u);
  EXPECT_EQ(r.created[0], 1u);  // the id no candidate kept
  ASSERT_NE(map.object(1), nullptr);
  EXPECT_EQ(map.object(1)->class_name, "chair");
}

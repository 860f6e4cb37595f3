// Eq. 2, sliding-window yaw (incl. the +-pi seam) and utility, against
// hand-computed answers.
#include <gtest/gtest.h>

#include <cmath>

#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/planning/candidate_evaluation.hpp"

namespace semexp {
namespace {

TEST(CombineGains, Eq2WithHistoryMask) {
  // 3 x 1 images; weights 0.5 / 0.3 / 0.2.
  GainSet g;
  g.entropy = GainImage(3, 1);
  g.entropy.values = {1.0f, 0.5f, 0.0f};
  g.background = GainImage(3, 1);
  g.background.values = {0.0f, 1.0f, 0.5f};
  g.object = GainImage(3, 1);
  g.object.values = {0.5f, 0.0f, 1.0f};
  GainWeights w{0.5, 0.3, 0.2};
  const std::vector<std::uint8_t> mask = {1, 0, 1};
  const GainImage G = combineGains(w, g, mask, 3, 1);
  // pixel 0: 0.5*1 + 0.3*0 + 0.2*0.5 = 0.6; pixel 1 masked; pixel 2: 0 + 0.15 + 0.2 = 0.35.
  EXPECT_NEAR(G.values[0], 0.6, 1e-6);
  EXPECT_EQ(G.values[1], 0.0f);
  EXPECT_NEAR(G.values[2], 0.35, 1e-6);
  // No mask: pixel 1 = 0.25 + 0.3 = 0.55.
  EXPECT_NEAR(combineGains(w, g, {}, 3, 1).values[1], 0.55, 1e-6);
  // A missing image (e.g. no object map) counts as zeros.
  g.object = GainImage();
  EXPECT_NEAR(combineGains(w, g, mask, 3, 1).values[0], 0.5, 1e-6);
  g.background = GainImage(2, 1);
  EXPECT_THROW(combineGains(w, g, mask, 3, 1), std::invalid_argument);
}

TEST(SlidingWindow, WidthFromCameraFov) {
  PinholeCamera cam;  // hfov = 2 atan(160 / 262.5) = 1.0974 rad -> 36 * 1.0974 / 2 pi = 6.29
  EXPECT_EQ(windowColumns(cam.hfov_rad(), 36), 6);
  EXPECT_EQ(windowColumns(0.01, 36), 1);
  EXPECT_EQ(windowColumns(7.0, 36), 36);
}

TEST(SlidingWindow, PicksKnownBestYaw) {
  GainImage img(36, 10, 0.1f);
  for (int u = 10; u <= 15; ++u)
    for (int v = 0; v < 10; ++v) img.at(u, v) = 0.9f;
  img.at(20, 3) = 1.0f;  // a lone bright pixel must not win
  const YawWindow w = bestYaw(img, 6);
  EXPECT_EQ(w.first_column, 10);
  // Centre at column coordinate 13: -pi + 2 pi * 13 / 36 = -50 degrees.
  EXPECT_NEAR(w.yaw_rad, -50.0 * M_PI / 180.0, 1e-9);
  EXPECT_NEAR(w.gain, 0.9, 1e-6);
  EXPECT_NEAR(windowMean(img, 10, 6), 0.9, 1e-6);
  // Shifted by one column: five bright columns and one dim one.
  EXPECT_NEAR(windowMean(img, 11, 6), (5 * 0.9 + 0.1) / 6.0, 1e-6);
}

TEST(SlidingWindow, WrapsAcrossTheSeam) {
  GainImage img(36, 10, 0.0f);
  for (int u : {34, 35, 0, 1, 2, 3})
    for (int v = 0; v < 10; ++v) img.at(u, v) = 0.5f;
  YawWindow w = bestYaw(img, 6);
  EXPECT_EQ(w.first_column, 34);
  // Centre at column coordinate 37 = 1 past the seam: -pi + 2 pi / 36 = -170 degrees.
  EXPECT_NEAR(w.yaw_rad, -170.0 * M_PI / 180.0, 1e-9);
  EXPECT_NEAR(w.gain, 0.5, 1e-6);

  // Centred exactly on the seam: columns 33..35 and 0..2 -> yaw pi (not -pi).
  GainImage seam(36, 2, 0.0f);
  for (int u : {33, 34, 35, 0, 1, 2}) seam.at(u, 0) = seam.at(u, 1) = 1.0f;
  w = bestYaw(seam, 6);
  EXPECT_EQ(w.first_column, 33);
  EXPECT_NEAR(w.yaw_rad, M_PI, 1e-9);
  EXPECT_NEAR(w.gain, 1.0, 1e-6);
  // Rows are averaged too: one row only half bright in the window.
  seam.at(33, 1) = 0.0f;
  w = bestYaw(seam, 6);
  EXPECT_NEAR(w.gain, 11.0 / 12.0, 1e-6);
}

TEST(Utility, TimeAndOrderingOfTwoCandidates) {
  const std::vector<Eigen::Vector3d> a = {{0, 0, 1}, {3, 0, 1}};             // 3 m
  const std::vector<Eigen::Vector3d> b = {{0, 0, 1}, {1.5, 0, 1}};           // 1.5 m
  const std::vector<Eigen::Vector3d> c = {{0, 0, 1}, {0, 3, 1}, {4, 3, 1}};  // 3 + 4 = 7 m
  EXPECT_NEAR(pathLength_m(c), 7.0, 1e-12);
  // A: 3 m at 1.5 m/s = 2 s, no turn. B: 1 s flying but pi/2 at 0.75 rad/s = 2.094 s.
  const double ta = pathTime_s(a, 0.0, 0.0, 1.5, 0.75);
  const double tb = pathTime_s(b, 0.0, M_PI / 2, 1.5, 0.75);
  EXPECT_NEAR(ta, 2.0, 1e-12);
  EXPECT_NEAR(tb, (M_PI / 2) / 0.75, 1e-12);
  // Gains 0.5 and 0.3: u_A = 0.25 > u_B = 0.1432.
  EXPECT_NEAR(utility(0.5, ta, 0.1), 0.25, 1e-12);
  EXPECT_NEAR(utility(0.3, tb, 0.1), 0.3 / 2.0943951, 1e-6);
  EXPECT_GT(utility(0.5, ta, 0.1), utility(0.3, tb, 0.1));
  // Turning from 3.0 to -3.0 rad is 0.283 rad through the seam, not 6 rad.
  EXPECT_NEAR(yawDifference_rad(3.0, -3.0), 2 * M_PI - 6.0, 1e-12);
  EXPECT_NEAR(pathTime_s({{0, 0, 0}}, 3.0, -3.0, 1.5, 0.75), (2 * M_PI - 6.0) / 0.75, 1e-12);
  // Zero time: the floor applies.
  EXPECT_NEAR(utility(0.2, 0.0, 0.1), 2.0, 1e-12);
}

}  // namespace
}  // namespace semexp

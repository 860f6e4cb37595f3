// DepthPyramid: validation, free limits, min/max levels and rectangle queries
// against values worked out by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "semantic_exploration/core/occupancy/depth_pyramid.hpp"

using semexp::occupancy::DepthPyramid;

TEST(DepthPyramid, ValidatesDepthAndBuildsMinMaxLevels) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // 4 x 2 px; NaN and 20 m (> d_max) are invalid.
  const std::vector<float> d = {1.f, 2.f, nan, 4.f,  //
                                0.5f, 3.f, 5.f, 20.f};
  DepthPyramid p;
  EXPECT_EQ(p.build(d.data(), 4, 2, 0.1f, 10.f, 0.1f, 0.f), 2u);
  // free limit = d - 0.1 m (front margin), 0 where invalid
  const float fl[8] = {0.9f, 1.9f, 0.f, 3.9f, 0.4f, 2.9f, 4.9f, 0.f};
  const float dv[8] = {1.f, 2.f, 0.f, 4.f, 0.5f, 3.f, 5.f, 0.f};
  for (int i = 0; i < 8; ++i) {
    EXPECT_FLOAT_EQ(p.freeLimit()[i], fl[i]) << i;
    EXPECT_FLOAT_EQ(p.depth()[i], dv[i]) << i;
  }
  ASSERT_EQ(p.levelCount(), 3u);  // 4x2, 2x1, 1x1
  EXPECT_EQ(p.levelDims(1), Eigen::Vector2i(2, 1));
  // level 1 node 0: pixels (0..1, 0..1): min free 0.4, max depth 3
  EXPECT_FLOAT_EQ(p.levelMin(1, 0, 0), 0.4f);
  EXPECT_FLOAT_EQ(p.levelMax(1, 0, 0), 3.f);
  // node 1 holds the two invalid pixels: min 0 (not carvable), max 5
  EXPECT_FLOAT_EQ(p.levelMin(1, 1, 0), 0.f);
  EXPECT_FLOAT_EQ(p.levelMax(1, 1, 0), 5.f);
  EXPECT_FLOAT_EQ(p.levelMin(2, 0, 0), 0.f);
  EXPECT_FLOAT_EQ(p.levelMax(2, 0, 0), 5.f);
  float mn, mx;
  p.query(0, 1, 0, 1, mn, mx);
  EXPECT_FLOAT_EQ(mn, 0.4f);
  EXPECT_FLOAT_EQ(mx, 3.f);
  p.query(1, 1, 0, 0, mn, mx);  // one pixel
  EXPECT_FLOAT_EQ(mn, 1.9f);
  EXPECT_FLOAT_EQ(mx, 2.f);
}

TEST(DepthPyramid, QuadraticMarginAndZeroFloor) {
  const std::vector<float> d = {2.f, 0.2f};
  DepthPyramid p;
  EXPECT_EQ(p.build(d.data(), 2, 1, 0.1f, 10.f, 0.05f, 0.1f), 0u);
  EXPECT_FLOAT_EQ(p.freeLimit()[0], 2.f - 0.4f);  // max(0.05, 0.1 * 2^2) = 0.4
  EXPECT_FLOAT_EQ(p.freeLimit()[1], 0.15f);       // max(0.05, 0.004) = 0.05
  const std::vector<float> near = {0.02f};
  p.build(near.data(), 1, 1, 0.01f, 10.f, 0.05f, 0.f);
  EXPECT_FLOAT_EQ(p.freeLimit()[0], 0.f);  // the margin reaches the camera: nothing carved
}

TEST(DepthPyramid, WideQueriesReadACoarserLevelAndStayConservative) {
  std::vector<float> d(8);
  for (int i = 0; i < 8; ++i) d[i] = static_cast<float>(i + 1);  // 1..8 m in one row
  DepthPyramid p;
  p.build(d.data(), 8, 1, 0.1f, 10.f, 0.f, 0.f);
  float mn, mx;
  // pixels 1..6 span 6 > 4 pixels: read from level 1 (pairs 0-1 .. 6-7): bounds 1 and 8,
  // looser than the rectangle's own 2 and 7, never tighter
  p.query(1, 6, 0, 0, mn, mx);
  EXPECT_FLOAT_EQ(mn, 1.f);
  EXPECT_FLOAT_EQ(mx, 8.f);
  p.query(2, 5, 0, 0, mn, mx);  // 4 pixels: level 0, exact
  EXPECT_FLOAT_EQ(mn, 3.f);
  EXPECT_FLOAT_EQ(mx, 6.f);
}

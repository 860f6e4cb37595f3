// Invalid-depth history: exact pixels for invalid depth at known poses.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "semantic_exploration/core/depth_history.hpp"
#include "semexp_test/cameras.hpp"

namespace semexp {
namespace {

using semexp_test::levelCameraPose;

struct DepthHistoryTest : ::testing::Test {
  Bounds bounds;
  PinholeCamera camera;
  DepthHistoryConfig config;
  DepthHistoryTest() {
    bounds.min_m = {-2.0, -2.0, 0.0};
    bounds.max_m = {2.0, 2.0, 2.0};
  }
  cv::Mat all_valid() const { return cv::Mat(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f)); }
  static int zeros(const std::vector<std::uint8_t>& m) {
    int z = 0;
    for (auto x : m) z += x == 0;
    return z;
  }
};

TEST_F(DepthHistoryTest, StartsAllValid) {
  DepthHistory h(config, bounds, camera);
  const auto m = h.mask({0.1, 0.2, 1.0});
  ASSERT_EQ(m.size(), 36u * 10u);
  EXPECT_EQ(zeros(m), 0);
  EXPECT_TRUE(h.invalid_cells().empty());
  EXPECT_EQ(h.integrate(all_valid(), levelCameraPose({0.1, 0.1, 1.1}, 0.3)), 0u);
  EXPECT_TRUE(h.invalid_cells().empty());
}

// Camera looking along +x; pixel (159, 119) lies half a pixel left of and
// above the principal point (159.5, 119.5): world direction (1, +0.0019,
// +0.0019), azimuth just above 0 -> column 18 (columns 17/18 meet at 0),
// elevation just above 0 -> row 4 (rows 4/5 meet at 0).
TEST_F(DepthHistoryTest, MarksExactPixelLookingAlongX) {
  DepthHistory h(config, bounds, camera);
  cv::Mat d = all_valid();
  d.at<float>(119, 159) = 0.f;
  EXPECT_EQ(h.integrate(d, levelCameraPose({0.1, 0.1, 1.1}, 0.0)), 1u);
  const auto m = h.mask({0.1, 0.1, 1.1});
  EXPECT_EQ(zeros(m), 1);
  EXPECT_EQ(m[4 * 36 + 18], 0);
}

// Left image edge u = 0: x_C = -159.5 / 262.5 = -0.6076 -> world direction
// (1, 0.6076, ~0): azimuth atan(0.6076) = 0.5460 rad -> column
// floor((0.5460 + pi) / (2 pi) * 36) = floor(21.13) = 21. NaN depth.
TEST_F(DepthHistoryTest, MarksExactPixelAtImageEdge) {
  DepthHistory h(config, bounds, camera);
  cv::Mat d = all_valid();
  d.at<float>(119, 0) = std::numeric_limits<float>::quiet_NaN();
  h.integrate(d, levelCameraPose({0.1, 0.1, 1.1}, 0.0));
  const auto m = h.mask({0.1, 0.1, 1.1});
  EXPECT_EQ(zeros(m), 1);
  EXPECT_EQ(m[4 * 36 + 21], 0);
}

// Looking along -x, half a pixel left = world -y: azimuth -pi + 0.0019 ->
// column 0 (across the +-pi seam from column 35). Depth beyond d_max.
TEST_F(DepthHistoryTest, MarksPixelAtTheSeam) {
  DepthHistory h(config, bounds, camera);
  cv::Mat d = all_valid();
  d.at<float>(119, 159) = 11.f;
  h.integrate(d, levelCameraPose({0.1, 0.1, 1.1}, M_PI));
  const auto m = h.mask({0.1, 0.1, 1.1});
  EXPECT_EQ(zeros(m), 1);
  EXPECT_EQ(m[4 * 36 + 0], 0);
}

// Camera looking along +y. Pixel (159, 230): elevation -atan(110.5 / 262.5)
// = -0.3982 rad -> row floor((0.42875 + 0.3982) / 0.8575 * 10) = floor(9.64)
// = 9; half a pixel left of the axis = world -x: azimuth pi/2 + 0.0019 ->
// column floor((pi/2 + 0.0019 + pi) / (2 pi) * 36) = 27. Pitched down by
// 0.2 rad, the bottom row (elevation -0.4272 - 0.2) leaves the band
// [-0.42875, 0.42875] and marks nothing.
TEST_F(DepthHistoryTest, ElevationRowsAndBand) {
  DepthHistory h(config, bounds, camera);
  cv::Mat d = all_valid();
  d.at<float>(239, 159) = 0.05f;  // below d_min: invalid
  Eigen::Isometry3d pitched = levelCameraPose({0.1, 0.1, 1.1}, M_PI / 2);
  pitched.linear() = pitched.linear() * Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_EQ(h.integrate(d, pitched), 1u);
  EXPECT_EQ(zeros(h.mask({0.1, 0.1, 1.1})), 0);
  d.at<float>(239, 159) = 2.f;
  d.at<float>(230, 159) = std::numeric_limits<float>::infinity();
  EXPECT_EQ(h.integrate(d, levelCameraPose({0.1, 0.1, 1.1}, M_PI / 2)), 1u);
  const auto m = h.mask({0.1, 0.1, 1.1});
  EXPECT_EQ(zeros(m), 1);
  EXPECT_EQ(m[9 * 36 + 27], 0);
}

TEST_F(DepthHistoryTest, OnlyTheCameraCellAndBatchMasks) {
  DepthHistory h(config, bounds, camera);
  cv::Mat d(camera.height, camera.width, CV_16UC1, cv::Scalar(2000));
  d.at<std::uint16_t>(119, 159) = 0;  // 16UC1 millimetres, 0 = invalid
  h.integrate(d, levelCameraPose({0.1, 0.1, 1.1}, 0.0));
  // Cells are 0.5 m from bounds.min (-2, -2, 0): (0.1, 0.1, 1.1) is cell
  // (4, 4, 2) with centre (0.25, 0.25, 1.25).
  const auto cells = h.invalid_cells();
  ASSERT_EQ(cells.size(), 1u);
  EXPECT_TRUE(cells[0].center_W.isApprox(Eigen::Vector3d(0.25, 0.25, 1.25)));
  EXPECT_EQ(cells[0].invalid_pixels, 1);
  const auto ms = h.masks({{0.4, 0.01, 1.01}, {0.6, 0.1, 1.1}, {5.0, 0.0, 1.0}});
  ASSERT_EQ(ms.size(), 3u);
  EXPECT_EQ(zeros(ms[0]), 1);  // same cell
  EXPECT_EQ(zeros(ms[1]), 0);  // neighbour cell
  EXPECT_EQ(zeros(ms[2]), 0);  // outside the bounds: all valid
}

TEST_F(DepthHistoryTest, CameraOutsideBoundsAndBadInput) {
  DepthHistory h(config, bounds, camera);
  cv::Mat d = all_valid();
  d.at<float>(10, 10) = 0.f;
  EXPECT_EQ(h.integrate(d, levelCameraPose({3.0, 0.0, 1.0}, 0.0)), 0u);
  EXPECT_TRUE(h.invalid_cells().empty());
  EXPECT_THROW(h.integrate(cv::Mat(10, 10, CV_32FC1), levelCameraPose({0, 0, 1}, 0.0)), std::invalid_argument);
  EXPECT_THROW(h.integrate(cv::Mat(camera.height, camera.width, CV_8UC1), levelCameraPose({0, 0, 1}, 0.0)),
               std::invalid_argument);
  DepthHistoryConfig bad;
  bad.cell_size_m = 0.0;
  EXPECT_THROW(DepthHistory(bad, bounds, camera), ConfigError);
}

}  // namespace
}  // namespace semexp

// The 360-degree image layout shared by gains and history masks.
#include <gtest/gtest.h>

#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/spherical_grid.hpp"

using semexp::SphericalGrid;

TEST(SphericalGrid, ColumnsAndRowsHaveTheDocumentedAngles) {
  SphericalGrid g;
  g.width = 4;
  g.height = 2;
  g.vfov_rad = 1.0;
  EXPECT_NEAR(g.azimuth(0), -M_PI + M_PI / 4, 1e-12);  // centre of the first quarter
  EXPECT_NEAR(g.azimuth(3), M_PI - M_PI / 4, 1e-12);
  EXPECT_NEAR(g.elevation(0), 0.25, 1e-12);  // row 0 looks up
  EXPECT_NEAR(g.elevation(1), -0.25, 1e-12);
  const Eigen::Vector3d d = g.direction(2, 0);  // azimuth pi/4, elevation 0.25
  EXPECT_NEAR(d.norm(), 1.0, 1e-12);
  EXPECT_NEAR(std::atan2(d.y(), d.x()), M_PI / 4, 1e-12);
  EXPECT_NEAR(std::asin(d.z()), 0.25, 1e-12);
}

TEST(SphericalGrid, PixelInvertsDirection) {
  SphericalGrid g;  // 36 x 10
  for (int v = 0; v < g.height; ++v)
    for (int u = 0; u < g.width; ++u) {
      int uu = -1, vv = -1;
      ASSERT_TRUE(g.pixel(3.0 * g.direction(u, v), uu, vv));
      EXPECT_EQ(uu, u);
      EXPECT_EQ(vv, v);
    }
}

TEST(SphericalGrid, SeamAndOutOfBand) {
  SphericalGrid g;
  int u, v;
  ASSERT_TRUE(g.pixel(Eigen::Vector3d(-1, 0, 0), u, v));  // azimuth pi is -pi: first column
  EXPECT_EQ(u, 0);
  ASSERT_TRUE(g.pixel(Eigen::Vector3d(-1, 1e-9, 0), u, v));  // just below +pi: last column
  EXPECT_EQ(u, g.width - 1);
  ASSERT_TRUE(g.pixel(Eigen::Vector3d(-1, -1e-9, 0), u, v));  // just above -pi: first column
  EXPECT_EQ(u, 0);
  EXPECT_FALSE(g.pixel(Eigen::Vector3d(0, 0, 1), u, v));  // straight up is outside the band
  EXPECT_FALSE(g.pixel(Eigen::Vector3d(0.1, 0, -1), u, v));
}

TEST(SphericalGrid, DefaultBandIsTheCameraVerticalFov) {
  semexp::PinholeCamera cam;
  EXPECT_NEAR(SphericalGrid().vfov_rad, cam.vfov_rad(), 1e-4);
}

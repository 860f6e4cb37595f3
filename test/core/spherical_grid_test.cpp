// The 360-degree image layout shared by gains and history masks.
#include <gtest/gtest.h>

#include <stdexcept>

#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/object_map.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"
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

TEST(SphericalGrid, RequestLimitsAreNamed) {
  EXPECT_EQ(SphericalGrid::checkRequest(20, 36, 10), "");                 // the planner's request
  EXPECT_EQ(SphericalGrid::checkRequest(4, 360, 180), "");                // 4 x 64800 = 259200 rays
  EXPECT_EQ(SphericalGrid::checkRequest(1, 20000, 20000),
            "20000 x 20000 px per image is over the limit of 64800 px (SphericalGrid::kMaxPixels)");
  // uint16 sizes whose product overflows an int are refused, not wrapped.
  EXPECT_NE(SphericalGrid::checkRequest(1, 65535, 65535).find("over the limit of 64800 px"), std::string::npos);
  EXPECT_EQ(SphericalGrid::checkRequest(2000, 36, 10),
            "2000 positions are over the limit of 1024 per request (SphericalGrid::kMaxPositions)");
  EXPECT_EQ(SphericalGrid::checkRequest(1000, 36, 10),
            "1000 positions x 360 px = 360000 rays are over the limit of 262144 per request (SphericalGrid::kMaxRays)");
  EXPECT_EQ(SphericalGrid::checkRequest(1, 0, 10), "width and height must be > 0");
}

TEST(SphericalGrid, MapsRefuseTooLargeGainRequests) {
  // The core refuses them too (before allocating anything), whoever calls it.
  semexp::OccupancyMap map(semexp::BackgroundMapConfig{}, semexp::Bounds{});
  SphericalGrid grid;
  grid.width = grid.height = 20000;
  EXPECT_THROW(map.computeGains({Eigen::Vector3d(0.0, 0.0, 1.0)}, grid, semexp::GainSettings{}), std::invalid_argument);
  semexp::ObjectMap objects(semexp::ObjectMapConfig{}, semexp::ClassTable{});
  std::vector<cv::Mat> gains, hits;
  EXPECT_THROW(objects.computeGains({Eigen::Vector3d(0.0, 0.0, 1.0)}, grid, {}, 1.0, 10.0, gains, hits),
               std::invalid_argument);
}

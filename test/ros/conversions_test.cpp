// Message <-> core conversions of the planner (ros/conversions.hpp), without
// a running node: well-formed messages convert to known values, malformed
// ones are refused with a reason instead of being read past their end.
#include <gtest/gtest.h>
#include <sensor_msgs/image_encodings.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "semantic_exploration/ros/conversions.hpp"
#include "semantic_exploration/ros/node_common.hpp"

using namespace semexp_ros;

namespace {

// A cloud of float32 x, y, z at point_step 12, one row.
sensor_msgs::PointCloud2 cloud(const std::vector<Eigen::Vector3f>& pts) {
  sensor_msgs::PointCloud2 c;
  c.height = 1;
  c.width = static_cast<uint32_t>(pts.size());
  const char* names[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    sensor_msgs::PointField f;
    f.name = names[k];
    f.offset = 4 * k;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    c.fields.push_back(f);
  }
  c.point_step = 12;
  c.row_step = 12 * c.width;
  c.data.resize(c.row_step);
  std::memcpy(c.data.data(), pts.data(), c.data.size());  // Vector3f is 3 packed floats
  return c;
}

}  // namespace

TEST(FrontiersFromCloud, ReadsFinitePoints) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto c = cloud({{1, 2, 3}, {nan, 0, 0}, {-1, 0.5f, 2}});
  std::vector<Eigen::Vector3d> pts;
  EXPECT_EQ(frontiersFromCloud(c, pts), "");
  ASSERT_EQ(pts.size(), 2u);  // the NaN point is left out
  EXPECT_EQ(pts[0], Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(pts[1], Eigen::Vector3d(-1, 0.5, 2));
}

TEST(FrontiersFromCloud, RefusesAZeroPointStep) {
  // With point_step 0 an iterator over the cloud never advances (the planner hung).
  auto c = cloud({{1, 2, 3}});
  c.point_step = 0;
  c.row_step = 0;
  std::vector<Eigen::Vector3d> pts{{9, 9, 9}};
  const std::string why = frontiersFromCloud(c, pts);
  EXPECT_NE(why.find("point_step 0"), std::string::npos) << why;
  ASSERT_EQ(pts.size(), 1u);  // untouched
  EXPECT_EQ(pts[0], Eigen::Vector3d(9, 9, 9));
}

TEST(FrontiersFromCloud, RefusesDataThatIsNotRowStepTimesHeight) {
  // 13 bytes at point_step 12: an iterator would step from byte 12 past the end.
  auto c = cloud({{1, 2, 3}});
  c.data.push_back(0);
  std::vector<Eigen::Vector3d> pts;
  EXPECT_NE(frontiersFromCloud(c, pts).find("13 bytes"), std::string::npos);
  // Too short for the points it claims.
  c = cloud({{1, 2, 3}, {4, 5, 6}});
  c.data.resize(13);
  EXPECT_NE(frontiersFromCloud(c, pts), "");
  EXPECT_TRUE(pts.empty());
}

TEST(FrontiersFromCloud, RefusesMissingFieldsAndShortRows) {
  auto c = cloud({{1, 2, 3}});
  c.fields[2].datatype = sensor_msgs::PointField::FLOAT64;  // z not float32
  std::vector<Eigen::Vector3d> pts;
  EXPECT_NE(frontiersFromCloud(c, pts).find("float32 x, y and z"), std::string::npos);
  c = cloud({{1, 2, 3}, {4, 5, 6}});
  c.row_step = 12;  // two points need 24 bytes per row
  c.data.resize(12);
  EXPECT_NE(frontiersFromCloud(c, pts).find("row_step"), std::string::npos);
  c = cloud({{1, 2, 3}});
  c.fields[2].offset = 10;  // z would end at byte 14 of a 12-byte point
  EXPECT_NE(frontiersFromCloud(c, pts).find("does not hold"), std::string::npos);
}

TEST(FrontiersFromCloud, AnEmptyCloudIsNoFrontier) {
  auto c = cloud({});
  std::vector<Eigen::Vector3d> pts{{1, 1, 1}};
  EXPECT_EQ(frontiersFromCloud(c, pts), "");
  EXPECT_TRUE(pts.empty());
}

TEST(ToGainImage, ConvertsAndRefusesOtherSizes) {
  const std::vector<float> v{0.f, 0.25f, 0.5f, 1.f, 0.f, 0.75f};
  std_msgs::Header h;
  const sensor_msgs::Image img = floatImageMsg(h, v, 3, 2);
  const semexp::GainImage g = toGainImage(img, 3, 2, "test");
  EXPECT_EQ(g.values, v);
  EXPECT_TRUE(toGainImage(sensor_msgs::Image(), 3, 2, "test").empty());  // 0 x 0: no such gain
  EXPECT_THROW(toGainImage(img, 2, 3, "test"), std::runtime_error);
  sensor_msgs::Image short_img = img;
  short_img.data.resize(8);
  EXPECT_THROW(toGainImage(short_img, 3, 2, "test"), std::runtime_error);
}

TEST(ToObjectSummaries, CountsObjectsWithNonFiniteGeometry) {
  semantic_exploration::ObjectArray arr;
  arr.objects.resize(3);
  arr.objects[2].id = 6;
  arr.objects[2].observed_fraction = std::numeric_limits<float>::quiet_NaN();
  arr.objects[0].id = 4;
  arr.objects[0].bbox_max.x = 1.0;
  arr.objects[0].observed_fraction = 0.5f;
  arr.objects[1].id = 5;
  arr.objects[1].centroid.y = std::numeric_limits<double>::infinity();
  std::size_t dropped = 0;
  const auto objs = toObjectSummaries(arr, dropped);
  ASSERT_EQ(objs.size(), 1u);
  EXPECT_EQ(dropped, 2u);
  EXPECT_EQ(objs[0].id, 4u);
  EXPECT_EQ(objs[0].bbox_max_W.x(), 1.0);
  EXPECT_DOUBLE_EQ(objs[0].observed_fraction, 0.5);
}

TEST(ToMapUpdate, PointsIntoTheMessageAndRefusesUnknownEncodings) {
  semantic_exploration::MapBlocks m;
  m.sequence = 7;
  m.resolution_m = 0.04f;
  m.block_size = 2;
  m.coords = {1, 2, 3};
  m.payload.assign(8, 0);
  semexp::MapReplica::Update u;
  EXPECT_EQ(toMapUpdate(m, u), "");
  EXPECT_EQ(u.sequence, 7u);
  EXPECT_EQ(u.coords, m.coords.data());
  EXPECT_EQ(u.coord_count, 3u);
  EXPECT_EQ(u.payload_size, 8u);
  m.uniform_coords = {4, 5, 6};
  m.uniform_values = {200};
  EXPECT_EQ(toMapUpdate(m, u), "");
  EXPECT_EQ(u.uniform_coords, m.uniform_coords.data());
  EXPECT_EQ(u.uniform_coord_count, 3u);
  EXPECT_EQ(u.uniform_value_count, 1u);
  EXPECT_EQ(u.uniform_values[0], 200);
  m.encoding = 9;
  EXPECT_NE(toMapUpdate(m, u).find("encoding 9"), std::string::npos);
}

TEST(ToHistoryMasks, ResizedMasksAreDroppedAndCounted) {
  std::vector<sensor_msgs::Image> masks(2);
  for (auto& m : masks) {
    m.width = 4;
    m.height = 1;
    m.step = 4;
    m.encoding = sensor_msgs::image_encodings::MONO8;
    m.data = {1, 0, 1, 1};
  }
  masks[1].width = 3;
  std::size_t bad = 0;
  const auto out = toHistoryMasks(masks, 4, 1, bad);
  EXPECT_EQ(bad, 1u);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0], (std::vector<std::uint8_t>{1, 0, 1, 1}));
  EXPECT_TRUE(out[1].empty());  // empty = all directions valid
}

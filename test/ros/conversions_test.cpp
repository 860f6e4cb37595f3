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

TEST(FromMapBlocksMsg, CopiesTheBlocksAndRefusesUnknownEncodings) {
  semantic_exploration::MapBlocks m;
  m.sequence = 7;
  m.resolution_m = 0.04f;
  m.block_size = 2;
  m.coords = {1, 2, 3};
  m.payload.assign(8, 0);
  semexp::MapBlocksData d;
  EXPECT_EQ(fromMapBlocksMsg(m, d), "");
  EXPECT_EQ(d.sequence, 7u);
  EXPECT_EQ(d.coords, m.coords);
  EXPECT_EQ(d.blockCount(), 1u);
  EXPECT_EQ(d.payload.size(), 8u);
  m.uniform_coords = {4, 5, 6};
  m.uniform_values = {200};
  EXPECT_EQ(fromMapBlocksMsg(m, d), "");
  EXPECT_EQ(d.uniform_coords, m.uniform_coords);
  ASSERT_EQ(d.uniform_values.size(), 1u);
  EXPECT_EQ(d.uniform_values[0], -56);  // the bits of 200 (0xc8) as int8
  m.encoding = 9;
  d.sequence = 0;
  EXPECT_NE(fromMapBlocksMsg(m, d).find("encoding 9"), std::string::npos);
  EXPECT_EQ(d.sequence, 0u);  // untouched
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

// ------------------------------------------------ what the map nodes send

TEST(MapNodeConversions, MapBlocksRoundTripThroughTheMessage) {
  semexp::MapBlocksData d;
  d.sequence = 7;
  d.full = true;
  d.resolution_m = 0.1;
  d.block_size = 2;
  d.origin_m = {-1.0, 2.0, 0.5};
  d.coords = {0, 0, 0, 1, -1, 3};
  d.payload = {-128, -20, 0, 1, 127, -1, 35, -35,   // block (0, 0, 0)
               10, 10, 10, 10, 10, 10, 10, 10};     // block (1, -1, 3)
  d.uniform_coords = {4, 5, 6};
  d.uniform_values = {-4};
  const auto m = toMapBlocksMsg(d, ros::Time(12.5), "world");
  EXPECT_EQ(m.header.stamp, ros::Time(12.5));
  EXPECT_EQ(m.header.frame_id, "world");
  EXPECT_EQ(m.encoding, semantic_exploration::MapBlocks::ENCODING_LOG_ODDS_I8);
  EXPECT_FLOAT_EQ(m.resolution_m, 0.1f);
  EXPECT_EQ(m.block_size, 2);
  EXPECT_DOUBLE_EQ(m.origin.x, -1.0);
  EXPECT_DOUBLE_EQ(m.origin.y, 2.0);
  EXPECT_DOUBLE_EQ(m.origin.z, 0.5);
  // int8 values keep their bits in the uint8 payload: -128 -> 0x80, -1 -> 0xff.
  ASSERT_EQ(m.payload.size(), 16u);
  EXPECT_EQ(m.payload[0], 0x80);
  EXPECT_EQ(m.payload[5], 0xff);
  EXPECT_EQ(m.payload[4], 127);
  ASSERT_EQ(m.uniform_values.size(), 1u);
  EXPECT_EQ(m.uniform_values[0], 0xfc);

  semexp::MapBlocksData u;
  ASSERT_EQ(fromMapBlocksMsg(m, u), "");
  EXPECT_EQ(u.sequence, 7u);
  EXPECT_TRUE(u.full);
  EXPECT_EQ(u.block_size, 2);
  EXPECT_TRUE(u.origin_m.isApprox(d.origin_m));
  EXPECT_FLOAT_EQ(static_cast<float>(u.resolution_m), 0.1f);
  EXPECT_EQ(u.encoding, d.encoding);
  ASSERT_EQ(u.coords.size(), 6u);
  EXPECT_EQ(u.coords, d.coords);
  EXPECT_EQ(u.coords[4], -1);
  ASSERT_EQ(u.payload.size(), 16u);
  EXPECT_EQ(u.payload, d.payload);  // every code back, byte for byte
  EXPECT_EQ(u.payload[0], -128);
  EXPECT_EQ(u.payload[7], -35);
  EXPECT_EQ(u.uniform_coords, d.uniform_coords);
  ASSERT_EQ(u.uniform_values.size(), 1u);
  EXPECT_EQ(u.uniform_values[0], -4);
}

TEST(MapNodeConversions, ObjectInfoCarriesTheSummaryThePlannerReads) {
  semexp::TsdfParams params;
  params.resolution_m = 0.04;
  semexp::MappedObject o(42, 3, "chair", params);
  o.detection_count = 5;
  o.undetected_count = 2;
  semexp::TsdfSummary s;
  s.bbox_min_W = {1.0, 2.0, 0.0};
  s.bbox_max_W = {1.5, 2.5, 0.9};
  s.centroid_W = {1.25, 2.25, 0.45};
  s.voxel_count = 900;
  s.observed_fraction = 0.75;
  s.weight_sum = 123.5;
  const auto info = toObjectInfo(o, s);
  EXPECT_EQ(info.id, 42u);
  EXPECT_EQ(info.class_id, 3);
  EXPECT_EQ(info.class_name, "chair");
  EXPECT_FLOAT_EQ(info.resolution_m, 0.04f);
  EXPECT_EQ(info.voxel_count, 900u);
  EXPECT_FLOAT_EQ(info.observed_fraction, 0.75f);
  EXPECT_EQ(info.detection_count, 5u);
  EXPECT_EQ(info.undetected_count, 2u);
  EXPECT_FLOAT_EQ(info.weight_sum, 123.5f);

  semantic_exploration::ObjectArray arr;
  arr.objects.push_back(info);
  std::size_t dropped = 99;
  const auto summaries = toObjectSummaries(arr, dropped);
  EXPECT_EQ(dropped, 0u);
  ASSERT_EQ(summaries.size(), 1u);
  EXPECT_EQ(summaries[0].id, 42u);
  EXPECT_TRUE(summaries[0].bbox_min_W.isApprox(s.bbox_min_W));
  EXPECT_TRUE(summaries[0].bbox_max_W.isApprox(s.bbox_max_W));
  EXPECT_TRUE(summaries[0].centroid_W.isApprox(s.centroid_W));
  EXPECT_DOUBLE_EQ(summaries[0].observed_fraction, 0.75);
}

TEST(MapNodeConversions, PosesRoundTripAndBadOnesAreRefused) {
  // 90 deg about z, then at (1, 2, 3): the camera's x axis points along world +y.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  const geometry_msgs::Pose m = toPose(T);
  EXPECT_NEAR(m.orientation.w, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(m.orientation.z, std::sqrt(0.5), 1e-12);
  EXPECT_DOUBLE_EQ(m.position.y, 2.0);
  Eigen::Isometry3d back;
  ASSERT_EQ(fromPose(m, back), "");
  EXPECT_TRUE(back.isApprox(T, 1e-12));
  EXPECT_TRUE((back * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d(1.0, 3.0, 3.0), 1e-12));

  // A quaternion of norm 2 is normalised; one of norm 0 or a NaN position is refused and T left alone.
  geometry_msgs::Pose scaled = m;
  scaled.orientation.w *= 2;
  scaled.orientation.z *= 2;
  ASSERT_EQ(fromPose(scaled, back), "");
  EXPECT_TRUE(back.isApprox(T, 1e-12));
  geometry_msgs::Pose zero = m;
  zero.orientation.w = zero.orientation.z = 0.0;
  EXPECT_NE(fromPose(zero, back), "");
  geometry_msgs::Pose nan = m;
  nan.position.x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(fromPose(nan, back), "");
  EXPECT_TRUE(back.isApprox(T, 1e-12));

  geometry_msgs::Transform t;
  t.translation.x = 1.0;
  t.translation.y = 2.0;
  t.translation.z = 3.0;
  t.rotation = m.orientation;
  EXPECT_TRUE(fromTransform(t).isApprox(T, 1e-12));

  const std::vector<geometry_msgs::Point> pts = {toPoint(Eigen::Vector3d(1, 2, 3)), toPoint(Eigen::Vector3d(-4, 5.5, 0))};
  const auto v = fromPoints(pts);
  ASSERT_EQ(v.size(), 2u);
  EXPECT_EQ(v[1], Eigen::Vector3d(-4, 5.5, 0));
}

// Message conversions of the flight-controller chain and the display cut:
// trajectory samples -> MultiDOFJointTrajectory -> SampledTrajectory, the
// refusals of malformed trajectories, and cutCloudAboveZ on a hand-made cloud.
#include <gtest/gtest.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include "semantic_exploration/ros/conversions.hpp"

using semexp_ros::cutCloudAboveZ;
using semexp_ros::fromTrajectoryMsg;
using semexp_ros::toTrajectoryMsg;

namespace {

trajectory_msgs::MultiDOFJointTrajectory straightLine() {
  semexp::TrajectoryConfig c;
  c.a_max_mps2 = 1.0;
  const semexp::Trajectory tr({{0, 0, 1}, {6, 0, 1}}, {3.0, -3.0}, 1.5, 0.75, c);
  return toTrajectoryMsg(tr.sample(0.1), "world", "body", ros::Time(5.0));
}

}  // namespace

TEST(TrajectoryConversions, RoundTripKeepsTimesPositionsAndYaws) {
  const auto msg = straightLine();  // 6 m: 5.5 s, points every 0.1 s plus the end
  ASSERT_EQ(msg.points.size(), 56u);
  EXPECT_EQ(msg.header.frame_id, "world");
  EXPECT_EQ(msg.header.stamp, ros::Time(5.0));
  ASSERT_EQ(msg.joint_names.size(), 1u);
  EXPECT_EQ(msg.joint_names[0], "body");
  EXPECT_NEAR(msg.points.back().time_from_start.toSec(), 5.5, 1e-9);
  EXPECT_NEAR(msg.points[15].velocities[0].linear.x, 1.5, 1e-9);  // cruising at 1.5 s
  EXPECT_NEAR(msg.points[5].accelerations[0].linear.x, 1.0, 1e-9);
  semexp::SampledTrajectory out;
  ASSERT_EQ(fromTrajectoryMsg(msg, "world", out), "");
  EXPECT_NEAR(out.duration_s(), 5.5, 1e-9);
  EXPECT_NEAR(out.at(2.75).position_W.x(), 3.0, 1e-6);
  EXPECT_NEAR(out.front().yaw_rad, 3.0, 1e-9);
  EXPECT_NEAR(out.back().yaw_rad, -3.0, 1e-9);   // the quaternion wraps it; the yaw went through pi
  EXPECT_NEAR(std::abs(out.at(2.75).yaw_rad), M_PI, 1e-6);
}

TEST(TrajectoryConversions, RefusesMalformedTrajectoriesSayingWhy) {
  semexp::SampledTrajectory out;
  auto msg = straightLine();
  msg.header.frame_id = "odom";
  EXPECT_NE(fromTrajectoryMsg(msg, "world", out).find("frame 'odom'"), std::string::npos);
  msg = straightLine();
  msg.header.frame_id = "/world";  // a leading slash is the same frame
  EXPECT_EQ(fromTrajectoryMsg(msg, "world", out), "");
  msg = straightLine();
  msg.points[3].time_from_start = msg.points[2].time_from_start;
  EXPECT_NE(fromTrajectoryMsg(msg, "world", out).find("point 3"), std::string::npos);
  msg = straightLine();
  msg.points[4].transforms.clear();
  EXPECT_NE(fromTrajectoryMsg(msg, "world", out).find("point 4 has 0 transforms"), std::string::npos);
  msg = straightLine();
  msg.points[1].transforms[0].rotation = geometry_msgs::Quaternion();  // all zero
  msg.points[1].transforms[0].rotation.w = 0;
  EXPECT_NE(fromTrajectoryMsg(msg, "world", out).find("quaternion"), std::string::npos);
  msg = straightLine();
  msg.points[2].transforms[0].translation.y = NAN;
  EXPECT_NE(fromTrajectoryMsg(msg, "world", out).find("point 2"), std::string::npos);
  // A refusal leaves `out` as it was.
  ASSERT_EQ(fromTrajectoryMsg(straightLine(), "world", out), "");
  msg.points.resize(3);
  EXPECT_NE(fromTrajectoryMsg(msg, "world", out), "");
  EXPECT_NEAR(out.duration_s(), 5.5, 1e-9);
  // No points: an empty trajectory (a cancel).
  msg.points.clear();
  EXPECT_EQ(fromTrajectoryMsg(msg, "world", out), "");
  EXPECT_TRUE(out.empty());
}

TEST(DisplayCut, KeepsThePointsAtOrBelowTheHeightWithAllTheirFields) {
  sensor_msgs::PointCloud2 in;
  in.header.frame_id = "world";
  sensor_msgs::PointCloud2Modifier mod(in);
  mod.setPointCloud2FieldsByString(2, "xyz", "rgb");
  const float zs[5] = {0.5f, 2.9f, 2.0f, NAN, -0.2f};
  mod.resize(5);
  sensor_msgs::PointCloud2Iterator<float> x(in, "x"), z(in, "z");
  sensor_msgs::PointCloud2Iterator<std::uint8_t> r(in, "r");
  for (int i = 0; i < 5; ++i, ++x, ++z, ++r) {
    *x = static_cast<float>(i);
    *z = zs[i];
    *r = static_cast<std::uint8_t>(10 * i);
  }
  sensor_msgs::PointCloud2 out;
  ASSERT_EQ(cutCloudAboveZ(in, 2.0, out), "");
  ASSERT_EQ(out.width, 3u);  // 0.5, 2.0 (at the limit) and -0.2; not 2.9 or NaN
  EXPECT_EQ(out.height, 1u);
  EXPECT_EQ(out.header.frame_id, "world");
  EXPECT_EQ(out.data.size(), 3u * in.point_step);
  sensor_msgs::PointCloud2ConstIterator<float> ox(out, "x");
  sensor_msgs::PointCloud2ConstIterator<std::uint8_t> orr(out, "r");
  const float want_x[3] = {0, 2, 4};
  for (int i = 0; i < 3; ++i, ++ox, ++orr) {
    EXPECT_EQ(*ox, want_x[i]);
    EXPECT_EQ(*orr, static_cast<std::uint8_t>(10 * want_x[i]));
  }
  sensor_msgs::PointCloud2 no_z;
  sensor_msgs::PointCloud2Modifier(no_z).setPointCloud2FieldsByString(1, "rgb");
  EXPECT_NE(cutCloudAboveZ(no_z, 2.0, out), "");
  in.data.resize(10);  // shorter than its points
  EXPECT_NE(cutCloudAboveZ(in, 2.0, out).find("shorter"), std::string::npos);
}

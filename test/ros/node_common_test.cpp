// Drop counting in the ROS shell: FrameGapCounter (frames missing from a
// constant-rate stream, from the stamps that arrive), DropCounter without a
// running node (counts only, nothing published), and TfGapGuard refusing a
// pose tf2 would interpolate across a gap in the pose stream. Also the 16UC1
// reader, the node name the frame reports carry, the per-frame CPU budget, and
// StampPeriod pacing work by message stamps.
#include <gtest/gtest.h>
#include <tf2_ros/buffer.h>

#include <chrono>
#include <cstring>
#include <thread>
#include <vector>

#include "semantic_exploration/ros/camera_node.hpp"
#include "semantic_exploration/ros/frame_timing.hpp"
#include "semantic_exploration/ros/node_common.hpp"

using semexp_ros::DropCounter;
using semexp_ros::FrameGapCounter;
using semexp_ros::TfGapGuard;

namespace {

ros::Time at(double t_s) { return ros::Time(t_s); }

}  // namespace

TEST(FrameGapCounter, CountsFramesMissingFromA10HzStream) {
  FrameGapCounter g;
  EXPECT_EQ(g.add(at(1.0)), 0u);  // first frame: nothing to compare with
  EXPECT_EQ(g.add(at(1.1)), 0u);
  EXPECT_NEAR(g.period_s(), 0.1, 1e-6);
  EXPECT_EQ(g.add(at(1.3)), 1u);  // 1.2 missing
  EXPECT_EQ(g.add(at(1.7)), 3u);  // 1.4, 1.5, 1.6 missing
  EXPECT_EQ(g.add(at(1.8)), 0u);
  EXPECT_NEAR(g.period_s(), 0.1, 1e-6);
}

TEST(FrameGapCounter, JitterRepeatsAndOlderStampsCountNothing) {
  FrameGapCounter g;
  for (int k = 0; k <= 5; ++k) g.add(at(2.0 + 0.1 * k));  // 2.0 .. 2.5
  EXPECT_EQ(g.add(at(2.6 + 0.04)), 0u);  // 0.14 s: a late frame, not a lost one
  EXPECT_EQ(g.add(at(2.7)), 0u);         // 0.06 s: the next one on time
  EXPECT_EQ(g.add(at(2.7)), 0u);         // the same frame again
  EXPECT_EQ(g.add(at(2.0)), 0u);         // an older frame (e.g. a bag replayed twice)
  EXPECT_EQ(g.add(at(2.8)), 0u);         // counting goes on from the newest stamp
  EXPECT_EQ(g.add(at(3.0)), 1u);
  EXPECT_NEAR(g.period_s(), 0.1, 1e-6);
}

TEST(FrameGapCounter, ThePeriodSurvivesManyDrops) {
  FrameGapCounter g;
  // 10 Hz with every third frame lost: two of three intervals are one period
  uint64_t missing = 0;
  for (int k = 0; k < 60; ++k)
    if (k % 3 != 2) missing += g.add(at(1.0 + 0.1 * k));
  EXPECT_EQ(missing, 19u);  // frames 2, 5, ..., 56 (59 lies after the last stamp)
  EXPECT_NEAR(g.period_s(), 0.1, 1e-6);
}

TEST(StampPeriod, IsDueOncePerPeriodOfStampsAndAgainAfterTimeWentBack) {
  semexp_ros::StampPeriod p(2.0);
  EXPECT_FALSE(p.started());  // nothing due yet: background_map publishes no surface share then
  std::vector<double> due;
  // A 10 Hz stream from 10.0 s to 15.0 s, a replay from 10.0 s, then three stamps of 10.5 s.
  std::vector<double> stamps;
  for (int k = 0; k <= 50; ++k) stamps.push_back(10.0 + 0.1 * k);
  for (double t : {10.0, 10.5, 12.0, 10.5, 10.5}) stamps.push_back(t);
  for (double t : stamps)
    if (p.due(at(t))) due.push_back(t);
  // 10.0, then the first stamp >= 12.0 and >= 14.0; 10.0 is older than 14.0 (time went back), 12.0 is 2 s
  // after it, 10.5 older than 12.0 again, and the repeated 10.5 is not due (0 s < 2 s).
  const std::vector<double> expected = {10.0, 12.0, 14.0, 10.0, 12.0, 10.5};
  EXPECT_TRUE(p.started());
  ASSERT_EQ(due.size(), expected.size());
  for (std::size_t i = 0; i < due.size(); ++i) EXPECT_NEAR(due[i], expected[i], 1e-9) << i;
}

TEST(StampPeriod, PeriodZeroIsDueForEveryStamp) {
  semexp_ros::StampPeriod p(0.0);
  for (double t : {1.0, 1.0, 1.1, 0.5}) EXPECT_TRUE(p.due(at(t))) << t;
}

TEST(DropCounter, CountsPerReasonWithoutANode) {
  DropCounter d(1000.0);
  d.drop("no_tf", "frame 1");
  d.drop("no_tf", "frame 2");
  d.drop("frame_gap", "3 frames missing", 3);
  d.drop("frame_gap", "nothing", 0);
  EXPECT_EQ(d.count("no_tf"), 2u);
  EXPECT_EQ(d.count("frame_gap"), 3u);
  EXPECT_EQ(d.count("size_mismatch"), 0u);
  EXPECT_EQ(d.total(), 5u);
  EXPECT_EQ(d.counts().size(), 2u);
}

namespace {

geometry_msgs::TransformStamped transform(const std::string& parent, const std::string& child, double t_s, double x) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time(t_s);
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.x = x;
  t.transform.rotation.w = 1.0;
  return t;
}

// world -> body at 50 Hz from 1.00 to 2.00 s (x = t), then nothing until 3.00 s, then 50 Hz again to 3.20 s
// (x = t + 10: the MAV moved 11 m while the pose source was silent); body -> camera static, 0.1 m ahead.
void fill(tf2_ros::Buffer& tf, TfGapGuard& guard) {
  tf.setTransform(transform("body", "camera", 0.0, 0.1), "test", true);
  for (int k = 0; k <= 60; ++k) {
    const double t = k <= 50 ? 1.0 + 0.02 * k : 3.0 + 0.02 * (k - 51);
    tf.setTransform(transform("world", "body", t, k <= 50 ? t : t + 10.0), "test");
    guard.add("body", ros::Time(t));
  }
}

}  // namespace

TEST(TfGapGuard, IntervalAroundAStamp) {
  TfGapGuard g(0.2, false);
  for (double t : {1.0, 1.02, 1.04, 3.0}) g.add("/body", ros::Time(t));  // a leading slash is dropped
  EXPECT_DOUBLE_EQ(g.intervalAround("body", ros::Time(1.02)), 0.0);      // a sample at the stamp
  EXPECT_NEAR(g.intervalAround("body", ros::Time(1.01)), 0.02, 1e-9);
  EXPECT_NEAR(g.intervalAround("body", ros::Time(2.0)), 1.96, 1e-9);
  EXPECT_DOUBLE_EQ(g.intervalAround("body", ros::Time(0.5)), 0.0);   // before the first: tf2 will not extrapolate
  EXPECT_DOUBLE_EQ(g.intervalAround("body", ros::Time(3.5)), -1.0);  // none after yet
  EXPECT_DOUBLE_EQ(g.intervalAround("camera", ros::Time(2.0)), 0.0);  // no samples: a static frame
}

TEST(TfGapGuard, TheLimitFollowsEachFramesOwnRate) {
  TfGapGuard g(0.2, false);
  for (int k = 0; k <= 20; ++k) g.add("body", ros::Time(1.0 + 0.02 * k));  // 50 Hz
  for (int k = 0; k <= 20; ++k) g.add("odom", ros::Time(1.0 + 1.0 * k));   // 1 Hz (a SLAM correction)
  EXPECT_DOUBLE_EQ(g.limit_s("body"), 0.2);                 // max_tf_gap_s beats 5 x 0.02 s
  EXPECT_NEAR(g.limit_s("odom"), 5.0, 1e-9);                // 5 sample periods beat 0.2 s
  EXPECT_DOUBLE_EQ(g.limit_s("camera"), 0.2);               // no samples
  g.add("body", ros::Time(3.0));                            // a 1.6 s gap: the lower quartile ignores it
  EXPECT_DOUBLE_EQ(g.limit_s("body"), 0.2);
  // Time jumping back (a bag replayed again) forgets the samples of the first pass.
  g.add("body", ros::Time(1.5));
  EXPECT_DOUBLE_EQ(g.intervalAround("body", ros::Time(2.0)), -1.0);  // nothing after 1.5 yet
  g.add("body", ros::Time(1.52));
  EXPECT_NEAR(g.intervalAround("body", ros::Time(1.51)), 0.02, 1e-9);
}

TEST(TfGapGuard, RefusesAPoseInterpolatedAcrossAGap) {
  tf2_ros::Buffer tf;
  TfGapGuard guard(0.2, false);
  fill(tf, guard);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  // Between two samples 20 ms apart: accepted, interpolated.
  ASSERT_EQ(semexp_ros::lookupPose(tf, "world", "camera", ros::Time(1.51), 0.0, T, &guard), "");
  EXPECT_NEAR(T.translation().x(), 1.51 + 0.1, 1e-9);
  // At the samples on either side of the gap: exact, accepted.
  ASSERT_EQ(semexp_ros::lookupPose(tf, "world", "camera", ros::Time(2.0), 0.0, T, &guard), "");
  EXPECT_NEAR(T.translation().x(), 2.1, 1e-9);
  ASSERT_EQ(semexp_ros::lookupPose(tf, "world", "camera", ros::Time(3.0), 0.0, T, &guard), "");
  EXPECT_NEAR(T.translation().x(), 13.1, 1e-9);
  // Inside the gap tf2 alone gives the straight line between 2.0 (x 2) and 3.0 (x 13) ...
  ASSERT_EQ(semexp_ros::lookupPose(tf, "world", "camera", ros::Time(2.5), 0.0, T), "");
  EXPECT_NEAR(T.translation().x(), 7.5 + 0.1, 1e-9);
  // ... which the guard refuses, naming the frame and the gap, and leaves T alone.
  T = Eigen::Isometry3d::Identity();
  const std::string why = semexp_ros::lookupPose(tf, "world", "camera", ros::Time(2.5), 0.0, T, &guard);
  EXPECT_NE(why.find("'body'"), std::string::npos) << why;
  EXPECT_NE(why.find("1.000 s gap"), std::string::npos) << why;
  EXPECT_TRUE(T.isApprox(Eigen::Isometry3d::Identity()));
  // A limit of 1 s accepts this 1 s gap.
  TfGapGuard loose(1.0, false);
  fill(tf, loose);
  EXPECT_EQ(semexp_ros::lookupPose(tf, "world", "camera", ros::Time(2.5), 0.0, T, &loose), "");
  TfGapGuard off(0.0, false);  // 0 = no check
  EXPECT_EQ(semexp_ros::lookupPose(tf, "world", "camera", ros::Time(2.5), 0.0, T, &off), "");
}

namespace {

sensor_msgs::CameraInfo cameraInfo(uint32_t w, uint32_t h) {
  sensor_msgs::CameraInfo ci;
  ci.width = w;
  ci.height = h;
  ci.K = {262.5, 0.0, (w - 1) / 2.0, 0.0, 262.5, (h - 1) / 2.0, 0.0, 0.0, 1.0};
  return ci;
}

}  // namespace

TEST(CameraInfoInput, RefusesOversizedCameraInfoNamingTheCap) {
  semexp_ros::CameraInfoInput in;
  semexp::PinholeCamera cam;  // 320 x 240 defaults
  // 100000 x 100000 px with a valid K: a per-pixel buffer would take 10^10 entries.
  std::string why = in.accept(cameraInfo(100000, 100000), 0.1, 10.0, cam);
  EXPECT_NE(why.find("camera_info/width"), std::string::npos) << why;
  EXPECT_NE(why.find("8192"), std::string::npos) << why;
  EXPECT_EQ(cam.width, 320);
  // Each side within the cap, the product over it (8192 x 4096 = 2 x 16.8 Mpx).
  why = in.accept(cameraInfo(8192, 4096), 0.1, 10.0, cam);
  EXPECT_NE(why.find("width x height must be <= 16777216"), std::string::npos) << why;
  // At the cap: accepted.
  EXPECT_EQ(in.accept(cameraInfo(4096, 4096), 0.1, 10.0, cam), "");
  EXPECT_EQ(cam.width, 4096);
  EXPECT_DOUBLE_EQ(cam.cx, 2047.5);
}

TEST(CameraInfoInput, RefusesASizeOtherThanTheDepthFrames) {
  semexp_ros::CameraInfoInput in;
  semexp::PinholeCamera cam;
  EXPECT_EQ(in.accept(cameraInfo(640, 480), 0.1, 10.0, cam), "");  // no depth frame yet: nothing to compare with
  in.depthFrame(320, 240);
  const std::string why = in.accept(cameraInfo(640, 480), 0.1, 10.0, cam);
  EXPECT_EQ(why, "camera_info is 640x480 px but the depth frames are 320x240 px");
  EXPECT_EQ(in.accept(cameraInfo(320, 240), 0.1, 10.0, cam), "");
  EXPECT_EQ(cam.width, 320);
  EXPECT_EQ(cam.height, 240);
}

TEST(CameraInfoInput, WarnsOnceAboutIgnoredDistortion) {
  sensor_msgs::CameraInfo ci = cameraInfo(320, 240);
  EXPECT_EQ(semexp_ros::ignoredDistortion(ci), "");  // no D
  ci.distortion_model = "plumb_bob";
  ci.D = {0.0, 0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(semexp_ros::ignoredDistortion(ci), "");  // all zero: rectified
  ci.D = {0.1, -0.25, 0.001, 0.0, 0.05};
  EXPECT_EQ(semexp_ros::ignoredDistortion(ci), "distortion_model 'plumb_bob' with D = [0.1, -0.25, 0.001, 0, 0.05]");
  semexp_ros::CameraInfoInput in;
  semexp::PinholeCamera cam;
  for (int k = 0; k < 3; ++k) EXPECT_EQ(in.accept(ci, 0.1, 10.0, cam), "");  // used: K only
  EXPECT_EQ(in.distortion_warnings(), 1);
}

TEST(CheckSaveDirectory, OnlyAbsolutePathsWithoutDotDot) {
  EXPECT_EQ(semexp_ros::checkSaveDirectory("/tmp/run1/map"), "");
  EXPECT_EQ(semexp_ros::checkSaveDirectory("/tmp/run1/./map/"), "");
  EXPECT_EQ(semexp_ros::checkSaveDirectory("map"), "directory 'map' must be an absolute path");
  EXPECT_EQ(semexp_ros::checkSaveDirectory(""), "directory '' must be an absolute path");
  EXPECT_EQ(semexp_ros::checkSaveDirectory("/tmp/run1/../../etc"), "directory '/tmp/run1/../../etc' must not contain '..'");
  EXPECT_EQ(semexp_ros::checkSaveDirectory("/tmp/a..b"), "");  // a name with dots is fine
}

// ------------------------------------------- 16UC1 images, node names, CPU budget

namespace {

sensor_msgs::Image mono16(uint32_t w, uint32_t h, uint32_t step, const std::string& encoding = "16UC1") {
  sensor_msgs::Image m;
  m.width = w;
  m.height = h;
  m.step = step;
  m.encoding = encoding;
  m.data.assign(static_cast<size_t>(step) * h, 0);
  return m;
}

}  // namespace

TEST(Uint16ToMat, CopiesRowsPastTheirPadding) {
  auto m = mono16(2, 2, 6);  // one 16-bit pad value per row
  const uint16_t rows[2][3] = {{7, 300, 0xffff}, {65535, 1, 0xffff}};
  std::memcpy(m.data.data(), rows, sizeof(rows));
  cv::Mat out;
  ASSERT_EQ(semexp_ros::uint16ToMat(m, out), "");
  ASSERT_EQ(out.type(), CV_16UC1);
  ASSERT_EQ(out.size(), cv::Size(2, 2));
  EXPECT_EQ(out.at<uint16_t>(0, 0), 7);
  EXPECT_EQ(out.at<uint16_t>(0, 1), 300);
  EXPECT_EQ(out.at<uint16_t>(1, 0), 65535);
  EXPECT_EQ(out.at<uint16_t>(1, 1), 1);
  auto mono = mono16(2, 2, 4, "mono16");
  EXPECT_EQ(semexp_ros::uint16ToMat(mono, out), "");
}

TEST(Uint16ToMat, RefusesWhatWouldBeReadOutOfBounds) {
  cv::Mat out;
  EXPECT_NE(semexp_ros::uint16ToMat(mono16(4, 2, 8, "32FC1"), out).find("expected 16UC1"), std::string::npos);
  EXPECT_NE(semexp_ros::uint16ToMat(mono16(0, 0, 0), out), "");
  EXPECT_NE(semexp_ros::uint16ToMat(mono16(4, 2, 6), out).find("step 6"), std::string::npos);  // a row is 8 bytes
  auto short_data = mono16(4, 2, 8);
  short_data.data.resize(15);
  EXPECT_NE(semexp_ros::uint16ToMat(short_data, out).find("15 bytes"), std::string::npos);
  auto big = mono16(4, 2, 8);
  big.is_bigendian = 1;
  EXPECT_NE(semexp_ros::uint16ToMat(big, out), "");
}

TEST(ShortNodeName, IsWhatLockstepNodesLists) {
  EXPECT_EQ(semexp_ros::shortNodeName("/background_map"), "background_map");
  EXPECT_EQ(semexp_ros::shortNodeName("/robot1/object_map"), "object_map");
  EXPECT_EQ(semexp_ros::shortNodeName("depth_history/"), "depth_history");
  EXPECT_EQ(semexp_ros::shortNodeName("planner"), "planner");
}

TEST(CpuBudget, NearestRankMedianAndP95) {
  semexp_ros::CpuBudget b(100);
  EXPECT_EQ(b.median_ms(), 0.0);
  EXPECT_EQ(b.p95_ms(), 0.0);
  // 1..20 ms in shuffled order: median = rank ceil(10) = 10, p95 = rank ceil(19) = 19.
  for (int v : {20, 3, 17, 1, 9, 12, 5, 14, 7, 19, 2, 11, 16, 4, 10, 18, 6, 13, 8, 15}) b.add(v);
  EXPECT_EQ(b.frames(), 20u);
  EXPECT_EQ(b.median_ms(), 10.0);
  EXPECT_EQ(b.p95_ms(), 19.0);
  EXPECT_EQ(b.percentile_ms(100.0), 20.0);
  semexp_ros::CpuBudget one;
  one.add(4.5);
  EXPECT_EQ(one.median_ms(), 4.5);
  EXPECT_EQ(one.p95_ms(), 4.5);
}

TEST(CpuBudget, KeepsOnlyTheLastWindow) {
  semexp_ros::CpuBudget b(4);
  for (int v : {100, 100, 100, 100, 1, 2, 3, 4}) b.add(v);  // the four 100s drop out of the window
  EXPECT_EQ(b.frames(), 8u);
  EXPECT_EQ(b.median_ms(), 2.0);  // rank ceil(2) of {1, 2, 3, 4}
  EXPECT_EQ(b.p95_ms(), 4.0);
}

TEST(FrameTimer, ThreadCpuTimeCountsWorkNotSleep) {
  const semexp_ros::FrameTimer idle;
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_GE(idle.wall_ms(), 50.0);
  EXPECT_LT(idle.cpu_ms(), 25.0);  // sleeping costs (almost) no CPU
  const semexp_ros::FrameTimer busy;
  volatile double x = 0;
  while (busy.cpu_ms() < 30.0) x = x + 1.0;  // spins until 30 ms of CPU time are used
  EXPECT_GE(busy.wall_ms(), busy.cpu_ms() - 1.0);
}

// background_map's frame runs partly on its integration pool's threads: their CPU clock's change counts.
TEST(FrameTimer, CountsTheHelperThreadsCpu) {
  double helper_s = 2.0;
  const semexp_ros::FrameTimer t([&] { return helper_s; });
  helper_s = 2.25;  // the helpers used 250 ms since the frame began
  EXPECT_GE(t.cpu_ms(), 250.0);
  EXPECT_LT(t.cpu_ms(), 275.0);  // plus (almost) nothing of this thread
  helper_s = 1.0;                // a clock that went back (a new pool) adds nothing
  EXPECT_LT(t.cpu_ms(), 25.0);
}

// Found by the soak (issue 15): a padded row step that is no multiple of the
// pixel size is valid in sensor_msgs/Image, but made cv::Mat throw out of the
// depth callback; and width x bytes per pixel wrapped around in uint32.
TEST(DepthToMeters, TakesAnyRowPadding) {
  sensor_msgs::Image m;
  m.encoding = "32FC1";
  m.width = 3;
  m.height = 2;
  m.step = 13;  // 12 bytes of pixels + 1 byte of padding per row
  m.data.assign(26, 0);
  const float rows[2][3] = {{1.0f, 2.0f, 3.5f}, {4.0f, 5.0f, 6.25f}};
  std::memcpy(&m.data[0], rows[0], 12);
  std::memcpy(&m.data[13], rows[1], 12);
  cv::Mat d;
  ASSERT_EQ(semexp_ros::depthToMeters(m, d), "");
  ASSERT_EQ(d.type(), CV_32FC1);
  ASSERT_EQ(d.cols, 3);
  ASSERT_EQ(d.rows, 2);
  for (int v = 0; v < 2; ++v)
    for (int u = 0; u < 3; ++u) EXPECT_EQ(d.at<float>(v, u), rows[v][u]) << v << "," << u;

  m.encoding = "16UC1";  // 2-byte pixels, step 7: 3 px + 1 byte of padding
  m.step = 7;
  m.data.assign(14, 0);
  const uint16_t mm[2][3] = {{1000, 2000, 0}, {1, 65535, 500}};
  std::memcpy(&m.data[0], mm[0], 6);
  std::memcpy(&m.data[7], mm[1], 6);
  ASSERT_EQ(semexp_ros::depthToMeters(m, d), "");
  EXPECT_FLOAT_EQ(d.at<float>(0, 1), 2.0f);
  EXPECT_FLOAT_EQ(d.at<float>(1, 1), 65.535f);
  EXPECT_FLOAT_EQ(d.at<float>(0, 2), 0.0f);
}

TEST(DepthToMeters, RefusesARowLengthThatWrapsAround) {
  sensor_msgs::Image m;
  m.encoding = "32FC1";
  m.width = 1u << 30;  // x 4 bytes = 2^32, 0 in uint32
  m.height = 1;
  m.step = 4;
  m.data.assign(4, 0);
  cv::Mat d;
  EXPECT_EQ(semexp_ros::depthToMeters(m, d), "step 4 shorter than a row of 1073741824 px");
  cv::Mat rgb;
  m.encoding = "rgba8";
  EXPECT_EQ(semexp_ros::colourToRgb(m, rgb), "step 4 shorter than a row of 1073741824 px");
}

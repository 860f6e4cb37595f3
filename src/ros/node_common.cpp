#include "semantic_exploration/ros/node_common.hpp"

#include <sensor_msgs/image_encodings.h>
#include <tf2_msgs/TFMessage.h>

#include "semantic_exploration/DropCounts.h"
#include "semantic_exploration/ros/conversions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <opencv2/imgproc.hpp>

namespace semexp_ros {

namespace enc = sensor_msgs::image_encodings;

std::string imageToMat(const sensor_msgs::Image& msg, int cv_type, int bytes_per_pixel, cv::Mat& out) {
  // 64-bit sizes: width x bytes per pixel must not wrap around in uint32.
  const uint64_t row = static_cast<uint64_t>(msg.width) * static_cast<uint64_t>(bytes_per_pixel);
  if (msg.width == 0 || msg.height == 0) return "empty image";
  if (msg.width > static_cast<uint32_t>(std::numeric_limits<int>::max()) ||
      msg.height > static_cast<uint32_t>(std::numeric_limits<int>::max()))
    return "image of " + std::to_string(msg.width) + "x" + std::to_string(msg.height) + " px is too large";
  if (msg.step < row)
    return "step " + std::to_string(msg.step) + " shorter than a row of " + std::to_string(msg.width) + " px";
  if (msg.data.size() < static_cast<uint64_t>(msg.step) * msg.height)
    return "data holds " + std::to_string(msg.data.size()) + " bytes, expected " +
           std::to_string(static_cast<uint64_t>(msg.step) * msg.height);
  if (msg.is_bigendian) return "big-endian images are not supported";
  // Row by row: a step that is no multiple of the pixel size (padding of any
  // length) is valid in sensor_msgs/Image but not in a cv::Mat header.
  out.create(static_cast<int>(msg.height), static_cast<int>(msg.width), cv_type);
  for (uint32_t v = 0; v < msg.height; ++v)
    std::memcpy(out.ptr(static_cast<int>(v)), &msg.data[static_cast<size_t>(v) * msg.step], row);
  return "";
}

std::string depthToMeters(const sensor_msgs::Image& msg, cv::Mat& depth_m) {
  if (msg.encoding == enc::TYPE_32FC1) return imageToMat(msg, CV_32FC1, 4, depth_m);
  if (msg.encoding == enc::TYPE_16UC1 || msg.encoding == enc::MONO16) {
    cv::Mat mm;
    if (auto err = imageToMat(msg, CV_16UC1, 2, mm); !err.empty()) return err;
    mm.convertTo(depth_m, CV_32FC1, 1e-3);  // millimetres -> metres; 0 stays 0 (invalid)
    return "";
  }
  return "unsupported depth encoding '" + msg.encoding + "' (expected 32FC1 in m or 16UC1 in mm)";
}

std::string uint16ToMat(const sensor_msgs::Image& msg, cv::Mat& out) {
  if (msg.encoding != enc::TYPE_16UC1 && msg.encoding != enc::MONO16)
    return "encoding '" + msg.encoding + "' (expected 16UC1)";
  return imageToMat(msg, CV_16UC1, 2, out);  // row by row: any padding, 64-bit size checks
}

std::string colourToRgb(const sensor_msgs::Image& msg, cv::Mat& rgb) {
  struct Fmt { const char* name; int type; int bpp; int code; };
  static const Fmt fmts[] = {
      {"rgb8", CV_8UC3, 3, -1},
      {"bgr8", CV_8UC3, 3, cv::COLOR_BGR2RGB},
      {"rgba8", CV_8UC4, 4, cv::COLOR_RGBA2RGB},
      {"bgra8", CV_8UC4, 4, cv::COLOR_BGRA2RGB},
      {"mono8", CV_8UC1, 1, cv::COLOR_GRAY2RGB},
  };
  for (const auto& f : fmts) {
    if (msg.encoding != f.name) continue;
    cv::Mat view;
    if (auto err = imageToMat(msg, f.type, f.bpp, view); !err.empty()) return err;
    if (f.code < 0)
      rgb = view;
    else
      cv::cvtColor(view, rgb, f.code);
    return "";
  }
  return "unsupported colour encoding '" + msg.encoding + "' (expected rgb8, bgr8, rgba8, bgra8 or mono8)";
}

sensor_msgs::Image toImageMsg(const std_msgs::Header& header, const cv::Mat& m) {
  sensor_msgs::Image img;
  img.header = header;
  switch (m.type()) {
    case CV_32FC1: img.encoding = enc::TYPE_32FC1; break;
    case CV_16UC1: img.encoding = enc::TYPE_16UC1; break;
    case CV_8UC1: img.encoding = enc::MONO8; break;
    default: throw std::invalid_argument("toImageMsg: unsupported cv::Mat type " + std::to_string(m.type()));
  }
  img.height = static_cast<uint32_t>(m.rows);
  img.width = static_cast<uint32_t>(m.cols);
  img.is_bigendian = 0;
  img.step = static_cast<uint32_t>(m.cols * m.elemSize());
  img.data.resize(static_cast<size_t>(img.step) * m.rows);
  for (int v = 0; v < m.rows; ++v) std::memcpy(&img.data[static_cast<size_t>(v) * img.step], m.ptr(v), img.step);
  return img;
}

sensor_msgs::Image floatImageMsg(const std_msgs::Header& header, const std::vector<float>& values, int w, int h) {
  cv::Mat m = cv::Mat::zeros(h, w, CV_32FC1);
  if (values.size() == static_cast<size_t>(w) * static_cast<size_t>(h))
    cv::Mat(h, w, CV_32FC1, const_cast<float*>(values.data())).copyTo(m);
  return toImageMsg(header, m);
}

std::string cameraFromInfo(const sensor_msgs::CameraInfo& info, double d_min_m, double d_max_m,
                           semexp::PinholeCamera& camera) {
  semexp::PinholeCamera c;
  c.width = static_cast<int>(info.width);
  c.height = static_cast<int>(info.height);
  c.fx = info.K[0];
  c.fy = info.K[4];
  c.cx = info.K[2];
  c.cy = info.K[5];
  c.d_min_m = d_min_m;
  c.d_max_m = d_max_m;
  try {
    c.validate("camera_info/");
  } catch (const semexp::ConfigError& e) {
    return e.what();
  }
  camera = c;
  return "";
}

std::string outOfBounds(const std::string& what, const Eigen::Vector3d& p_W) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), " at (%.3f, %.3f, %.3f) lies outside the map bounds", p_W.x(), p_W.y(), p_W.z());
  return what + buf;
}

std::string checkSaveDirectory(const std::string& directory) {
  namespace fs = std::filesystem;
  const fs::path dir(directory);
  if (directory.empty() || !dir.is_absolute())
    return "directory '" + directory + "' must be an absolute path";
  for (const auto& part : dir)
    if (part == "..") return "directory '" + directory + "' must not contain '..'";
  return "";
}

std::string ignoredDistortion(const sensor_msgs::CameraInfo& info) {
  if (std::all_of(info.D.begin(), info.D.end(), [](double d) { return d == 0.0; })) return "";
  std::string d;
  char buf[32];
  for (const double v : info.D) {
    std::snprintf(buf, sizeof(buf), "%s%g", d.empty() ? "" : ", ", v);
    d += buf;
  }
  return "distortion_model '" + info.distortion_model + "' with D = [" + d + "]";
}

std::string CameraInfoInput::accept(const sensor_msgs::CameraInfo& info, double d_min_m, double d_max_m,
                                    semexp::PinholeCamera& camera) {
  semexp::PinholeCamera c;
  std::string err = cameraFromInfo(info, d_min_m, d_max_m, c);
  if (!err.empty()) return err;
  if (depth_width_px_ > 0 && (c.width != depth_width_px_ || c.height != depth_height_px_))
    return "camera_info is " + std::to_string(c.width) + "x" + std::to_string(c.height) + " px but the depth frames are " +
           std::to_string(depth_width_px_) + "x" + std::to_string(depth_height_px_) + " px";
  if (distortion_warnings_ == 0) {
    const std::string d = ignoredDistortion(info);
    if (!d.empty()) {
      ROS_WARN("camera_info has %s: ignored, images are taken as rectified (only K is used)", d.c_str());
      ++distortion_warnings_;
    }
  }
  camera = c;
  return "";
}

TfGapGuard::TfGapGuard(double max_gap_s, bool subscribe) : max_gap_s_(max_gap_s) {
  if (!(max_gap_s_ > 0.0) || !subscribe || !ros::isInitialized()) return;
  ros::NodeHandle nh;
  nh.setCallbackQueue(&queue_);
  sub_ = nh.subscribe<tf2_msgs::TFMessage>("/tf", 100, [this](const tf2_msgs::TFMessageConstPtr& msg) {
    for (const auto& t : msg->transforms) add(t.child_frame_id, t.header.stamp);
  });
  spinner_ = std::make_unique<ros::AsyncSpinner>(1, &queue_);
  spinner_->start();
}

TfGapGuard::~TfGapGuard() {
  if (spinner_) spinner_->stop();
  sub_.shutdown();
}

void TfGapGuard::add(const std::string& child_frame, const ros::Time& stamp) {
  std::string frame = child_frame;
  if (!frame.empty() && frame[0] == '/') frame.erase(0, 1);  // tf2 ignores a leading slash too
  std::lock_guard<std::mutex> lock(mutex_);
  auto& s = stamps_[frame];
  if (!s.empty() && stamp + ros::Duration(1.0) < *s.rbegin()) s.clear();  // time went back
  s.insert(stamp);
  const ros::Time newest = *s.rbegin();
  const ros::Time keep_from = newest.toSec() > 30.0 ? newest - ros::Duration(30.0) : ros::Time(0);
  s.erase(s.begin(), s.lower_bound(keep_from));
}

double TfGapGuard::intervalAround(const std::string& child_frame, const ros::Time& stamp) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = stamps_.find(child_frame);
  if (it == stamps_.end()) return 0.0;  // not a dynamic frame (or never seen): nothing to interpolate
  const auto& s = it->second;
  const auto after = s.lower_bound(stamp);
  if (after != s.end() && *after == stamp) return 0.0;
  if (after == s.begin()) return 0.0;
  if (after == s.end()) return -1.0;
  return (*after - *std::prev(after)).toSec();
}

double TfGapGuard::limit_s(const std::string& child_frame) const {
  std::vector<double> dt;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = stamps_.find(child_frame);
    if (it != stamps_.end())
      for (auto b = it->second.rbegin(), a = std::next(b); a != it->second.rend() && dt.size() < 15; ++a, ++b)
        dt.push_back((*b - *a).toSec());
  }
  if (dt.empty()) return max_gap_s_;
  const size_t q = (dt.size() - 1) / 4;  // lower quartile: robust to the gaps themselves
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(q), dt.end());
  return std::max(max_gap_s_, kGapPeriods * dt[q]);
}

std::string TfGapGuard::check(const tf2_ros::Buffer& tf, const std::string& target, const std::string& source,
                              const ros::Time& stamp, double timeout_s) const {
  if (!(max_gap_s_ > 0.0)) return "";
  std::vector<std::string> chain;
  try {
    tf._chainAsVector(target, stamp, source, stamp, target, chain);
  } catch (const std::exception&) {
    return "";  // the lookup itself reports what is wrong with the chain
  }
  const auto deadline = ros::WallTime::now() + ros::WallDuration(std::max(0.0, timeout_s));
  for (const std::string& frame : chain) {
    double gap = intervalAround(frame, stamp);
    while (gap < 0.0 && ros::WallTime::now() < deadline && ros::ok()) {
      ros::WallDuration(0.002).sleep();
      gap = intervalAround(frame, stamp);
    }
    const double limit = gap > max_gap_s_ ? limit_s(frame) : max_gap_s_;
    if (gap > limit) {
      char buf[240];
      std::snprintf(buf, sizeof(buf), "the pose of '%s' at %.3f s lies in a %.3f s gap between its tf samples "
                    "(limit %.3f s: max_tf_gap_s or %.0f sample periods): tf2 would interpolate across it",
                    frame.c_str(), stamp.toSec(), gap, limit, kGapPeriods);
      return buf;
    }
  }
  return "";
}

PoseSource::PoseSource(const TfSettings& settings, bool guard_gaps) : settings_(settings), listener_(buffer_) {
  if (guard_gaps) guard_ = std::make_unique<TfGapGuard>(settings_.max_gap_s);
}

std::string PoseSource::lookup(const std::string& target, const std::string& source, const ros::Time& stamp,
                               Eigen::Isometry3d& T) const {
  return lookupPose(buffer_, target, source, stamp, settings_.timeout_s, T, guard_.get());
}

std::string PoseSource::cameraPose(const FrameNames& frames, const std_msgs::Header& header,
                                   Eigen::Isometry3d& T_WC) const {
  return lookup(frames.world, header.frame_id.empty() ? frames.camera : header.frame_id, header.stamp, T_WC);
}

std::string lookupPose(const tf2_ros::Buffer& tf, const std::string& target, const std::string& source,
                       const ros::Time& stamp, double timeout_s, Eigen::Isometry3d& T, const TfGapGuard* guard) {
  // Waits in wall time: under /use_sim_time a lockstep simulator holds the
  // clock until this frame is reported, so a wait in sim time (tf2's timeout)
  // would never end while the pose is missing.
  std::string err;
  const auto deadline = ros::WallTime::now() + ros::WallDuration(std::max(0.0, timeout_s));
  while (!tf.canTransform(target, source, stamp, &err)) {
    if (ros::WallTime::now() >= deadline || !ros::ok())
      return err.empty() ? "no transform " + target + " <- " + source : err;
    err.clear();
    ros::WallDuration(0.002).sleep();
  }
  if (guard) {
    // At least a moment for a sample tf2's listener thread already has to reach the guard's thread.
    const double left_s = std::max(0.02, (deadline - ros::WallTime::now()).toSec());
    const std::string gap = guard->check(tf, target, source, stamp, left_s);
    if (!gap.empty()) return gap;
  }
  try {
    T = fromTransform(tf.lookupTransform(target, source, stamp).transform);
    if (!T.matrix().allFinite()) return "transform " + target + " <- " + source + " is not finite";
    return "";
  } catch (const std::exception& e) {
    return e.what();
  }
}

DropCounter::DropCounter(double period_s) : period_s_(period_s) {
  if (!ros::isInitialized()) return;  // e.g. a unit test without a node: count only
  ros::NodeHandle nh;
  pub_ = nh.advertise<semantic_exploration::DropCounts>("/dropped_input", 1, true);
  publish();
}

void DropCounter::publish() const {
  if (!pub_) return;
  semantic_exploration::DropCounts m;
  m.header.stamp = ros::Time::isValid() ? ros::Time::now() : ros::Time();
  m.node = ros::this_node::getName();
  for (const auto& kv : counts_) {
    m.reasons.push_back(kv.first);
    m.counts.push_back(kv.second);
  }
  pub_.publish(m);
}

void DropCounter::drop(const std::string& reason, const std::string& detail, uint64_t n) {
  if (n == 0) return;
  counts_[reason] += n;
  publish();
  const auto now = ros::WallTime::now();
  auto it = last_log_.find(reason);
  if (it == last_log_.end() || (now - it->second).toSec() >= period_s_) {
    ROS_WARN("dropped input (%s, %lu so far): %s", reason.c_str(), static_cast<unsigned long>(counts_[reason]),
             detail.c_str());
    last_log_[reason] = now;
  }
}

uint64_t FrameGapCounter::add(const ros::Time& stamp) {
  if (last_.isZero()) {
    last_ = stamp;
    return 0;
  }
  const double dt_s = (stamp - last_).toSec();
  if (dt_s <= 0.0) return 0;
  last_ = stamp;
  intervals_s_.push_back(dt_s);
  if (intervals_s_.size() > kWindow) intervals_s_.pop_front();
  std::vector<double> v(intervals_s_.begin(), intervals_s_.end());
  const size_t q = (v.size() - 1) / 4;  // lower quartile
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(q), v.end());
  period_s_ = v[q];
  const long k = std::lround(dt_s / period_s_);
  return k > 1 ? static_cast<uint64_t>(k - 1) : 0;
}

bool StampPeriod::due(const ros::Time& stamp) {
  if (started_ && stamp >= last_ && (stamp - last_).toSec() < period_s_) return false;
  started_ = true;
  last_ = stamp;
  return true;
}

void countFrameGaps(FrameGapCounter& gaps, DropCounter& drops, const ros::Time& stamp, const std::string& stream) {
  if (const uint64_t missing = gaps.add(stamp))
    drops.drop("frame_gap", std::to_string(missing) + " " + stream + " frame(s) missing before " +
                                std::to_string(stamp.toSec()) + " s (period " + std::to_string(gaps.period_s()) +
                                " s)", missing);
}

uint64_t DropCounter::count(const std::string& reason) const {
  const auto it = counts_.find(reason);
  return it == counts_.end() ? 0 : it->second;
}

uint64_t DropCounter::total() const {
  uint64_t n = 0;
  for (const auto& kv : counts_) n += kv.second;
  return n;
}

}  // namespace semexp_ros

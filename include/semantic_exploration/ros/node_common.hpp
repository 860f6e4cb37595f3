#pragma once
/// @file node_common.hpp
/// What every node needs between messages and the core: image conversion with
/// validation, camera_info to PinholeCamera, tf2 pose lookup, counted and
/// throttled reporting of dropped input, and a guarded main.

#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <Eigen/Geometry>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/config_error.hpp"
#include "semantic_exploration/ros/params.hpp"

namespace semexp_ros {

/// Copies the pixels of `msg` (rows `step` bytes apart, padding of any length)
/// into `out`, a new contiguous cv::Mat of `cv_type` with `bytes_per_pixel`
/// bytes per pixel. Returns "" on success, else why the layout is unusable:
/// empty, a side over INT_MAX px, a step shorter than a row, data shorter
/// than step x height, or big-endian.
std::string imageToMat(const sensor_msgs::Image& msg, int cv_type, int bytes_per_pixel, cv::Mat& out);

/// Converts depth (32FC1 metres or 16UC1 millimetres) to a CV_32FC1 image in
/// metres (a deep copy). Returns "" on success, else why it was rejected.
std::string depthToMeters(const sensor_msgs::Image& msg, cv::Mat& depth_m);

/// Converts colour (rgb8, bgr8, rgba8, bgra8, mono8) to a CV_8UC3 RGB image.
/// Returns "" on success, else why it was rejected.
std::string colourToRgb(const sensor_msgs::Image& msg, cv::Mat& rgb);

/// Copies a 16UC1 (or mono16) image, e.g. an instance or object id image, to
/// a CV_16UC1 image. Returns "" on success, else why it was rejected.
std::string uint16ToMat(const sensor_msgs::Image& msg, cv::Mat& out);

/// Image message holding a copy of `m`: CV_32FC1 -> 32FC1, CV_16UC1 -> 16UC1,
/// CV_8UC1 -> mono8 (other types throw std::invalid_argument).
sensor_msgs::Image toImageMsg(const std_msgs::Header& header, const cv::Mat& m);

/// 32FC1 image message of a row-major w x h float buffer; all zeros if
/// `values` does not hold w * h values (e.g. a gain the planner skipped).
sensor_msgs::Image floatImageMsg(const std_msgs::Header& header, const std::vector<float>& values, int w, int h);

/// Builds the core camera model from camera_info (K) and a depth range.
/// Returns "" on success, else why the camera_info is unusable.
std::string cameraFromInfo(const sensor_msgs::CameraInfo& info, double d_min_m, double d_max_m,
                           semexp::PinholeCamera& camera);

/// "<what> at (x, y, z) lies outside the map bounds", for out_of_bounds drops.
std::string outOfBounds(const std::string& what, const Eigen::Vector3d& p_W);

/// "" if `directory` may be saved into (SaveMap), else why not: it must be an
/// absolute path without ".." components, so that a save never lands
/// relative to a node's working directory (~/.ros under roslaunch) or
/// outside the directory it names.
std::string checkSaveDirectory(const std::string& directory);

/// Describes the lens distortion in `info` that the nodes ignore (they take
/// images as rectified and use K only): "" when D is empty or all zero, else
/// e.g. "distortion_model 'plumb_bob' with D = [0.1, -0.2, 0, 0, 0]".
std::string ignoredDistortion(const sensor_msgs::CameraInfo& info);

/// camera_info -> camera model for one node: K and the size are validated
/// (the size capped by PinholeCamera::kMaxSidePx / kMaxPixels), the size is
/// checked against the depth frames seen so far, and distortion is warned
/// about once per node, naming what is ignored.
class CameraInfoInput {
 public:
  /// "" and `camera` set if `info` is usable, else why (the caller counts a
  /// "bad_camera_info" drop and keeps its previous camera).
  std::string accept(const sensor_msgs::CameraInfo& info, double d_min_m, double d_max_m,
                     semexp::PinholeCamera& camera);
  /// Records the size of a depth frame; a camera_info of another size is refused from then on.
  void depthFrame(int width_px, int height_px) {
    depth_width_px_ = width_px;
    depth_height_px_ = height_px;
  }
  /// Distortion warnings logged so far (at most 1).
  int distortion_warnings() const { return distortion_warnings_; }

 private:
  int depth_width_px_ = 0, depth_height_px_ = 0;  ///< 0 until a depth frame arrived
  int distortion_warnings_ = 0;
};

/// Stamps of the transforms on /tf (the dynamic ones), to refuse a pose that
/// tf2 would interpolate across a gap in the pose stream: tf2 interpolates
/// linearly between the two samples around a stamp however far apart they
/// are, so a frame taken while the pose source stalled would get a pose the
/// MAV never had. A gap is wider than both max_gap_s and kGapPeriods of the
/// frame's own sample period, so that a slow transform (a SLAM map -> odom at
/// 1 Hz) is not taken for a stalled one. Listens on a thread of its own, as
/// tf2's listener does, so that it keeps up while a node's callback waits for
/// a pose.
class TfGapGuard {
 public:
  /// max_gap_s: widest accepted interval between the samples around a stamp, s;
  /// <= 0 disables the check. With `subscribe` false it only learns from add().
  explicit TfGapGuard(double max_gap_s, bool subscribe = true);
  ~TfGapGuard();
  TfGapGuard(const TfGapGuard&) = delete;
  TfGapGuard& operator=(const TfGapGuard&) = delete;

  static constexpr double kGapPeriods = 5.0;  ///< a gap is at least this many sample periods

  double max_gap_s() const { return max_gap_s_; }
  /// Records a sample of child_frame's transform. Samples older than 30 s
  /// before the newest are forgotten; a sample more than 1 s older than the
  /// newest (time jumped back: a bag replayed again) forgets all before it.
  void add(const std::string& child_frame, const ros::Time& stamp);
  /// Widest accepted interval between child_frame's samples around a stamp:
  /// max(max_gap_s, kGapPeriods x its sample period), the period being the
  /// lower quartile of its last 15 sample intervals, s.
  double limit_s(const std::string& child_frame) const;
  /// Interval between child_frame's samples around `stamp`, s: 0 if a sample
  /// is at `stamp` or there is none before it (tf2 cannot interpolate then),
  /// -1 if there is none after it yet.
  double intervalAround(const std::string& child_frame, const ros::Time& stamp) const;
  /// "" if no frame on the chain target <- source is interpolated at `stamp`
  /// across more than its limit_s(); else why. A sample tf2 already has may not
  /// have reached this guard yet: it waits for it up to timeout_s (wall).
  std::string check(const tf2_ros::Buffer& tf, const std::string& target, const std::string& source,
                    const ros::Time& stamp, double timeout_s) const;

 private:
  double max_gap_s_;
  mutable std::mutex mutex_;
  std::unordered_map<std::string, std::set<ros::Time>> stamps_;
  ros::CallbackQueue queue_;
  ros::Subscriber sub_;
  std::unique_ptr<ros::AsyncSpinner> spinner_;
};

/// T_target_source at `stamp` through tf2, waiting up to `timeout_s` wall
/// seconds (not sim time, which a lockstep simulator holds meanwhile). With a
/// `guard`, a pose interpolated across a gap in the pose stream is refused.
/// Returns "" on success, else the reason.
std::string lookupPose(const tf2_ros::Buffer& tf, const std::string& target, const std::string& source,
                       const ros::Time& stamp, double timeout_s, Eigen::Isometry3d& T_target_source,
                       const TfGapGuard* guard = nullptr);

/// Where a node gets its poses: a tf2 buffer and listener, the node's tf
/// settings and, for poses at image stamps, a TfGapGuard. One per node.
class PoseSource {
 public:
  /// guard_gaps: refuse poses interpolated across a gap (settings.max_gap_s);
  /// off for a node that only takes the latest pose (the planner).
  explicit PoseSource(const TfSettings& settings, bool guard_gaps = true);
  PoseSource(const PoseSource&) = delete;
  PoseSource& operator=(const PoseSource&) = delete;

  /// T_target_source at `stamp` (ros::Time(0) = latest), waiting up to the
  /// settings' timeout_s wall seconds; see lookupPose(). "" on success, else why.
  std::string lookup(const std::string& target, const std::string& source, const ros::Time& stamp,
                     Eigen::Isometry3d& T_target_source) const;
  /// T_WC of an image: the pose of its header.frame_id (frames.camera when
  /// empty) in frames.world at its stamp, as lookup().
  std::string cameraPose(const FrameNames& frames, const std_msgs::Header& header, Eigen::Isometry3d& T_WC) const;

 private:
  TfSettings settings_;
  tf2_ros::Buffer buffer_;
  tf2_ros::TransformListener listener_;
  std::unique_ptr<TfGapGuard> guard_;  ///< null when gaps are not guarded
};

/// Counts dropped input per reason and logs each reason at most every
/// `period_s` seconds, so a bad stream never floods the log. Constructed in a
/// node (after ros::init), it also publishes its counts latched on
/// /dropped_input (semantic_exploration/DropCounts) at start and after each
/// drop, so that a run's report can collect them.
class DropCounter {
 public:
  explicit DropCounter(double period_s = 5.0);
  /// Counts one drop for `reason` and logs `detail` (throttled per reason).
  void drop(const std::string& reason, const std::string& detail) { drop(reason, detail, 1); }
  /// Counts `n` drops for `reason` at once (e.g. frames missing from a stream).
  void drop(const std::string& reason, const std::string& detail, uint64_t n);
  /// Number of drops counted for `reason`.
  uint64_t count(const std::string& reason) const;
  uint64_t total() const;
  const std::map<std::string, uint64_t>& counts() const { return counts_; }

 private:
  void publish() const;
  double period_s_;
  std::map<std::string, uint64_t> counts_;
  std::map<std::string, ros::WallTime> last_log_;
  ros::Publisher pub_;
};

/// Counts frames missing from a constant-rate camera stream from the stamps
/// that do arrive: the frame period is the lower quartile of the last stamp
/// intervals (robust to jitter, and to gaps in up to three quarters of the
/// intervals), and an interval of k periods means k - 1 frames were lost. Repeated or
/// older stamps count nothing.
class FrameGapCounter {
 public:
  /// Frames missing between the newest earlier stamp and `stamp` (0 for the first).
  uint64_t add(const ros::Time& stamp);
  /// Estimated frame period, s (0 until two frames arrived).
  double period_s() const { return period_s_; }

 private:
  static constexpr size_t kWindow = 15;  ///< intervals in the quartile
  ros::Time last_;
  std::deque<double> intervals_s_;
  double period_s_ = 0.0;
};

/// Says when work paced by message stamps (sim or sensor time, not wall
/// time) falls due: the first stamp, then once `period_s` has passed since the
/// last due stamp. A stamp older than that one (a bag replayed from its start,
/// a restarted simulator) is due at once. Period 0: every stamp is due.
class StampPeriod {
 public:
  explicit StampPeriod(double period_s) : period_s_(period_s) {}
  /// Whether `stamp` is due; a due stamp becomes the new reference.
  bool due(const ros::Time& stamp);
  /// Whether any stamp was due yet (the paced work was done at least once).
  bool started() const { return started_; }

 private:
  double period_s_;
  ros::Time last_;
  bool started_ = false;
};

/// Feeds `stamp` to `gaps` and counts the frames found missing before it as
/// "frame_gap" drops of `stream` (e.g. "depth"), with one throttled log line.
void countFrameGaps(FrameGapCounter& gaps, DropCounter& drops, const ros::Time& stamp, const std::string& stream);

/// Runs a node class: constructs it (it loads and validates parameters) and
/// spins. Invalid configuration logs FATAL naming the parameter and returns 2.
template <typename NodeT>
int runNode(const char* name) {
  // The handles outlive the try block: destroying the last one shuts roscpp
  // down, and rosconsole would then swallow the FATAL line below.
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  try {
    NodeT node(nh, pnh);
    ROS_INFO("%s: started", name);
    ros::spin();
    ROS_INFO("%s: shutting down", name);
    return 0;
  } catch (const semexp::ConfigError& e) {
    ROS_FATAL("%s: %s", name, e.what());
    return 2;
  } catch (const std::exception& e) {
    ROS_FATAL("%s: %s", name, e.what());
    return 1;
  }
}

}  // namespace semexp_ros

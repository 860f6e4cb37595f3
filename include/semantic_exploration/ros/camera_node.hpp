#pragma once
/// @file camera_node.hpp
/// The base of the nodes fed by the depth camera (background_map, object_map,
/// instance_matching, depth_history). It owns what they share:
/// - `camera/camera_info`: validated (CameraInfoInput: K, size cap, size of
///   the depth frames seen so far) and counted as "bad_camera_info" if not;
/// - the camera, bounds, frame names and tf settings parameters, and the
///   PoseSource giving T_WC at image stamps (gap-guarded);
/// - the DropCounter and the common refusals of a frame ("bad_depth",
///   "no_camera_info", "size_mismatch", "no_tf", "out_of_bounds");
/// - the `frame_integrated` report (FrameIntegrated) the simulator's lockstep
///   waits for. Its `node` is the node's own ROS name without namespace, the
///   name `lockstep_nodes` lists: one source for both.

#include <message_filters/synchronizer.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <Eigen/Geometry>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "semantic_exploration/SaveMap.h"
#include "semantic_exploration/ros/frame_timing.hpp"
#include "semantic_exploration/ros/node_common.hpp"
#include "semantic_exploration/ros/params.hpp"

namespace semexp_ros {

/// Why a frame was refused: a DropCounter reason and its detail; an empty
/// reason means the step succeeded.
struct Refusal {
  std::string reason;
  std::string detail;
  explicit operator bool() const { return !reason.empty(); }
};

/// A node's ROS name without namespace ("/robot/object_map" -> "object_map"),
/// by default this node's.
std::string shortNodeName(const std::string& full_name = ros::this_node::getName());

class CameraNode {
 public:
  CameraNode(const CameraNode&) = delete;
  CameraNode& operator=(const CameraNode&) = delete;
  virtual ~CameraNode() = default;

 protected:
  /// What a depth frame before any camera_info meets.
  enum class BeforeCameraInfo {
    kUseParameters,  ///< the `camera/*` parameters serve; a frame of another size is "no_camera_info"
    kRefuse,         ///< every frame is "no_camera_info" until a camera_info came
  };

  /// Loads the shared parameters from `pnh` (throws semexp::ConfigError),
  /// subscribes camera/camera_info and, with `reports_frames`, advertises
  /// frame_integrated.
  CameraNode(ros::NodeHandle& nh, ros::NodeHandle& pnh, BeforeCameraInfo before_info, bool reports_frames);

  const ParamReader& params() const { return params_; }
  /// The node's name (shortNodeName()) as reported in FrameIntegrated.node.
  const std::string& name() const { return name_; }

  /// False once a node's layout depends on the camera (depth_history after
  /// its first frame): a valid camera_info is then checked but not taken.
  virtual bool cameraChangeable() const { return true; }

  /// Depth (32FC1 m, 16UC1 mm) to CV_32FC1 metres; records its size for the
  /// camera_info checks and compares it with the camera's. Refusals:
  /// "bad_depth", "no_camera_info", "size_mismatch".
  Refusal readDepth(const sensor_msgs::Image& msg, cv::Mat& depth_m);
  /// T_WC of an image through PoseSource ("no_tf"); with `check_bounds`, a
  /// camera outside the map bounds is "out_of_bounds".
  Refusal cameraPose(const std_msgs::Header& header, Eigen::Isometry3d& T_WC, bool check_bounds = true) const;
  /// Counts the refusal and, for a node that reports frames, reports the frame as not integrated.
  void refuse(const std_msgs::Header& header, const Refusal& why, const FrameTimer& timer);
  /// Publishes frame_integrated for the frame of `header` with its wall and
  /// CPU time (the timer's plus what chargeCpu() added since the last report).
  void reportFrame(const std_msgs::Header& header, bool integrated, const FrameTimer& timer);
  /// CPU time (ms) of work for a frame done outside its frame callback
  /// (object_map's render for instance_matching, which object_map integrates
  /// next): it counts in the next reported frame.
  void chargeCpu(double cpu_ms) { charged_cpu_ms_ += cpu_ms; }
  /// True, with `res` filled as refused and an error logged, if a SaveMap
  /// request's directory may not be saved into (checkSaveDirectory()).
  bool saveRefused(const std::string& directory, semantic_exploration::SaveMap::Response& res) const;
  /// CPU time per frame so far (frames reported, integrated or not).
  const CpuBudget& cpuBudget() const { return cpu_budget_; }

  /// ApproximateTime synchroniser over `subs` that pairs only messages at
  /// most `max_interval_s` apart (a detection paired with the next depth
  /// frame would paint its mask onto whatever moved into it).
  template <typename Policy, typename... Subs>
  static std::unique_ptr<message_filters::Synchronizer<Policy>> makeSync(double max_interval_s, Subs&... subs) {
    Policy policy(10);
    policy.setMaxIntervalDuration(ros::Duration(max_interval_s));
    return std::make_unique<message_filters::Synchronizer<Policy>>(static_cast<const Policy&>(policy), subs...);
  }

  const std::string name_;
  const ParamReader params_;
  DropCounter drops_;
  semexp::PinholeCamera camera_;         ///< `camera/*` until a camera_info is accepted
  sensor_msgs::CameraInfo camera_info_;  ///< the last accepted camera_info (if have_info_)
  bool have_info_ = false;               ///< camera_ came from a camera_info
  const semexp::Bounds bounds_;
  const FrameNames frames_;
  PoseSource poses_;  ///< T_WC at image stamps (tf2, gap-guarded)

 private:
  void infoCallback(const sensor_msgs::CameraInfoConstPtr& msg);

  BeforeCameraInfo before_info_;
  bool reports_frames_;
  CameraInfoInput camera_input_;
  CpuBudget cpu_budget_;
  double charged_cpu_ms_ = 0.0;  ///< chargeCpu() since the last report
  ros::Subscriber info_sub_;
  ros::Publisher integrated_pub_;
};

}  // namespace semexp_ros

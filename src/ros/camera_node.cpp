#include "semantic_exploration/ros/camera_node.hpp"

#include "semantic_exploration/FrameIntegrated.h"

namespace semexp_ros {

namespace {

std::string sizeText(int width_px, int height_px) {
  return std::to_string(width_px) + "x" + std::to_string(height_px);
}

}  // namespace

std::string shortNodeName(const std::string& full_name) {
  std::string n = full_name;
  while (!n.empty() && n.back() == '/') n.pop_back();
  const auto slash = n.rfind('/');
  return slash == std::string::npos ? n : n.substr(slash + 1);
}

CameraNode::CameraNode(ros::NodeHandle& nh, ros::NodeHandle& pnh, BeforeCameraInfo before_info, bool reports_frames)
    : name_(shortNodeName()),
      params_(ParamReader::fromNodeHandle(pnh)),
      camera_(loadCamera(params_)),
      bounds_(loadBounds(params_)),
      frames_(loadFrames(params_)),
      poses_(loadTf(params_)),
      before_info_(before_info),
      reports_frames_(reports_frames) {
  info_sub_ = nh.subscribe("camera/camera_info", 1, &CameraNode::infoCallback, this);
  if (reports_frames_) integrated_pub_ = nh.advertise<semantic_exploration::FrameIntegrated>("frame_integrated", 10);
}

void CameraNode::infoCallback(const sensor_msgs::CameraInfoConstPtr& msg) {
  semexp::PinholeCamera c;
  const auto err = camera_input_.accept(*msg, camera_.d_min_m, camera_.d_max_m, c);
  if (!err.empty()) {
    drops_.drop("bad_camera_info", err);
    return;
  }
  if (!cameraChangeable()) return;
  camera_ = c;
  camera_info_ = *msg;
  have_info_ = true;
}

Refusal CameraNode::readDepth(const sensor_msgs::Image& msg, cv::Mat& depth_m) {
  if (auto err = depthToMeters(msg, depth_m); !err.empty()) return {"bad_depth", err};
  camera_input_.depthFrame(depth_m.cols, depth_m.rows);
  if (!have_info_ && before_info_ == BeforeCameraInfo::kRefuse)
    return {"no_camera_info", "depth received before any camera_info"};
  if (depth_m.cols == camera_.width && depth_m.rows == camera_.height) return {};
  if (!have_info_)
    return {"no_camera_info", "depth " + sizeText(depth_m.cols, depth_m.rows) +
                                  " before any camera_info and not of the configured camera size " +
                                  sizeText(camera_.width, camera_.height)};
  return {"size_mismatch", "depth " + sizeText(depth_m.cols, depth_m.rows) + " but camera_info " +
                               sizeText(camera_.width, camera_.height)};
}

Refusal CameraNode::cameraPose(const std_msgs::Header& header, Eigen::Isometry3d& T_WC, bool check_bounds) const {
  if (auto err = poses_.cameraPose(frames_, header, T_WC); !err.empty()) return {"no_tf", err};
  if (check_bounds && !bounds_.contains(T_WC.translation()))
    return {"out_of_bounds", outOfBounds("camera", T_WC.translation())};
  return {};
}

bool CameraNode::saveRefused(const std::string& directory, semantic_exploration::SaveMap::Response& res) const {
  const std::string why = checkSaveDirectory(directory);
  if (why.empty()) return false;
  res.success = false;
  res.message = name_ + ": save refused: " + why;
  ROS_ERROR("%s", res.message.c_str());
  return true;
}

void CameraNode::refuse(const std_msgs::Header& header, const Refusal& why, const FrameTimer& timer) {
  drops_.drop(why.reason, why.detail);
  reportFrame(header, false, timer);
}

void CameraNode::reportFrame(const std_msgs::Header& header, bool integrated, const FrameTimer& timer) {
  if (!reports_frames_) return;
  semantic_exploration::FrameIntegrated done;
  done.header = header;
  done.node = name_;
  done.integrated = integrated;
  done.time_ms = static_cast<float>(timer.wall_ms());
  done.cpu_ms = static_cast<float>(timer.cpu_ms() + charged_cpu_ms_);
  charged_cpu_ms_ = 0.0;
  cpu_budget_.add(done.cpu_ms);
  integrated_pub_.publish(done);
}

}  // namespace semexp_ros

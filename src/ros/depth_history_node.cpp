#include "semantic_exploration/ros/depth_history_node.hpp"

#include <sensor_msgs/image_encodings.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>

#include "semantic_exploration/FrameIntegrated.h"

namespace semexp_ros {

namespace {

// The planner asks get_masks for its raycast images, and get_masks answers only its own size: a mismatch would
// fail every planning iteration, so it fails here (every node loads the whole YAML, planner section included).
void checkPlannerImageSize(const ParamReader& p, const semexp::DepthHistoryConfig& config) {
  if (!p.has("planner")) return;  // no planner configured alongside
  semexp::PlannerConfig planner;
  p.get("planner/raycast_width", planner.raycast_width);
  p.get("planner/raycast_height", planner.raycast_height);
  if (config.width != planner.raycast_width)
    throw semexp::ConfigError("depth_history/width", "is " + std::to_string(config.width) +
                                                         " but planner/raycast_width is " +
                                                         std::to_string(planner.raycast_width) + "; they must be equal");
  if (config.height != planner.raycast_height)
    throw semexp::ConfigError("depth_history/height", "is " + std::to_string(config.height) +
                                                          " but planner/raycast_height is " +
                                                          std::to_string(planner.raycast_height) +
                                                          "; they must be equal");
}

}  // namespace

DepthHistoryNode::DepthHistoryNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  const auto p = ParamReader::fromNodeHandle(pnh);
  config_ = loadDepthHistory(p);
  checkPlannerImageSize(p, config_);
  camera_ = loadCamera(p);
  bounds_ = loadBounds(p);
  frames_ = loadFrames(p);
  poses_ = std::make_unique<PoseSource>(loadTf(p));
  p.getAtLeast("depth_history/marker_period_s", marker_period_s_, 0.0, "s");
  markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("markers", 1, true);
  integrated_pub_ = nh.advertise<semantic_exploration::FrameIntegrated>("frame_integrated", 10);
  masks_srv_ = pnh.advertiseService("get_masks", &DepthHistoryNode::getMasks, this);
  info_sub_ = nh.subscribe("camera/camera_info", 1, &DepthHistoryNode::infoCallback, this);
  depth_sub_ = nh.subscribe("camera/depth/image_raw", 2, &DepthHistoryNode::depthCallback, this);
  ROS_INFO("depth_history: %.2f m cells, %dx%d images", config_.cell_size_m, config_.width, config_.height);
}

void DepthHistoryNode::infoCallback(const sensor_msgs::CameraInfoConstPtr& msg) {
  semexp::PinholeCamera c;
  const auto err = camera_input_.accept(*msg, camera_.d_min_m, camera_.d_max_m, c);
  if (!err.empty()) {
    drops_.drop("bad_camera_info", err);
    return;
  }
  if (history_) return;  // the layout is fixed for the run
  camera_ = c;  // the history is built at the first depth frame of this size
  have_info_ = true;
}

void DepthHistoryNode::reportFrame(const std_msgs::Header& header, bool integrated, double time_ms) {
  semantic_exploration::FrameIntegrated done;
  done.header = header;
  done.node = "depth_history";
  done.integrated = integrated;
  done.time_ms = static_cast<float>(time_ms);
  integrated_pub_.publish(done);
}

void DepthHistoryNode::depthCallback(const sensor_msgs::ImageConstPtr& msg) {
  const auto t0 = ros::WallTime::now();
  cv::Mat depth_m;
  auto err = depthToMeters(*msg, depth_m);
  if (!err.empty()) {
    drops_.drop("bad_depth", err);
    reportFrame(msg->header, false, 0.0);
    return;
  }
  camera_input_.depthFrame(depth_m.cols, depth_m.rows);
  if (!history_) {
    // Built from the camera whose size the depth stream confirms (its per-pixel rays are sized from it).
    if (depth_m.cols != camera_.width || depth_m.rows != camera_.height) {
      if (have_info_)
        drops_.drop("size_mismatch", "depth " + std::to_string(depth_m.cols) + "x" + std::to_string(depth_m.rows) +
                                         " but camera_info " + std::to_string(camera_.width) + "x" +
                                         std::to_string(camera_.height));
      else
        drops_.drop("no_camera_info", "depth before any camera_info and not of the configured camera size");
      reportFrame(msg->header, false, 0.0);
      return;
    }
    history_ = std::make_unique<semexp::DepthHistory>(config_, bounds_, camera_);
  }
  if (depth_m.cols != camera_.width || depth_m.rows != camera_.height) {
    drops_.drop("size_mismatch", "depth " + std::to_string(depth_m.cols) + "x" + std::to_string(depth_m.rows) +
                                     " but camera " + std::to_string(camera_.width) + "x" +
                                     std::to_string(camera_.height));
    reportFrame(msg->header, false, 0.0);
    return;
  }
  Eigen::Isometry3d T_WC;
  err = poses_->cameraPose(frames_, msg->header, T_WC);
  if (!err.empty()) {
    drops_.drop("no_tf", err);
    reportFrame(msg->header, false, 0.0);
    return;
  }
  const std::size_t invalid = history_->integrate(depth_m, T_WC);
  ++frames_integrated_;
  markers_dirty_ = markers_dirty_ || invalid > 0;
  reportFrame(msg->header, true, (ros::WallTime::now() - t0).toSec() * 1e3);
  if (markers_dirty_ && (ros::WallTime::now() - last_markers_).toSec() >= marker_period_s_) publishMarkers(msg->header.stamp);
}

void DepthHistoryNode::publishMarkers(const ros::Time& stamp) {
  markers_dirty_ = false;
  last_markers_ = ros::WallTime::now();
  visualization_msgs::Marker m;
  m.header.frame_id = frames_.world;
  m.header.stamp = stamp;
  m.ns = "invalid_depth_cells";
  m.id = 0;
  m.type = visualization_msgs::Marker::CUBE_LIST;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.scale.x = m.scale.y = m.scale.z = 0.6 * config_.cell_size_m;
  const double pixels = static_cast<double>(config_.width) * config_.height;
  for (const auto& c : history_->invalid_cells()) {
    geometry_msgs::Point p;
    p.x = c.center_W.x();
    p.y = c.center_W.y();
    p.z = c.center_W.z();
    m.points.push_back(p);
    // Yellow (few invalid directions) to red (many).
    const double f = std::min(1.0, 4.0 * c.invalid_pixels / pixels);
    std_msgs::ColorRGBA col;
    col.r = 1.0f;
    col.g = static_cast<float>(1.0 - f);
    col.b = 0.0f;
    col.a = 0.6f;
    m.colors.push_back(col);
  }
  visualization_msgs::MarkerArray arr;
  if (m.points.empty()) m.action = visualization_msgs::Marker::DELETE;
  arr.markers.push_back(m);
  markers_pub_.publish(arr);
}

bool DepthHistoryNode::getMasks(semantic_exploration::GetHistoryMasks::Request& req,
                                semantic_exploration::GetHistoryMasks::Response& res) {
  if (req.width != config_.width || req.height != config_.height) {
    // Counted like every refused request (found by the soak: it was only logged).
    drops_.drop("bad_mask_request", "get_masks asked for " + std::to_string(req.width) + "x" +
                                        std::to_string(req.height) + ", the history is " +
                                        std::to_string(config_.width) + "x" + std::to_string(config_.height));
    return false;
  }
  if (const std::string why = semexp::SphericalGrid::checkRequest(static_cast<long>(req.positions.size()),
                                                                  config_.width, config_.height); !why.empty()) {
    drops_.drop("request_too_large", "get_masks: " + why);
    return false;
  }
  std::vector<Eigen::Vector3d> ps;
  ps.reserve(req.positions.size());
  for (const auto& p : req.positions) ps.emplace_back(p.x, p.y, p.z);
  std::vector<std::vector<std::uint8_t>> masks;
  if (history_)
    masks = history_->masks(ps);
  else
    masks.assign(ps.size(), std::vector<std::uint8_t>(static_cast<std::size_t>(config_.width) * config_.height, 1));
  res.masks.resize(masks.size());
  for (std::size_t i = 0; i < masks.size(); ++i) {
    auto& img = res.masks[i];
    img.header.stamp = ros::Time::now();
    img.header.frame_id = frames_.world;
    img.width = static_cast<uint32_t>(config_.width);
    img.height = static_cast<uint32_t>(config_.height);
    img.encoding = sensor_msgs::image_encodings::MONO8;
    img.step = img.width;
    img.data = std::move(masks[i]);
  }
  return true;
}

}  // namespace semexp_ros

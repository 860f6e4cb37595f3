#include "semantic_exploration/ros/depth_history_node.hpp"

#include <sensor_msgs/image_encodings.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>

#include "semantic_exploration/ros/conversions.hpp"


namespace semexp_ros {

DepthHistoryNode::DepthHistoryNode(ros::NodeHandle& nh, ros::NodeHandle& pnh)
    : CameraNode(nh, pnh, BeforeCameraInfo::kUseParameters, true) {
  const auto& p = params();
  config_ = loadDepthHistory(p);
  node_config_ = loadDepthHistoryNode(p, config_);
  markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("markers", 1, true);
  masks_srv_ = pnh.advertiseService("get_masks", &DepthHistoryNode::getMasks, this);
  depth_sub_ = nh.subscribe("camera/depth/image_raw", 2, &DepthHistoryNode::depthCallback, this);
  ROS_INFO("depth_history: %.2f m cells, %dx%d images", config_.cell_size_m, config_.width, config_.height);
}

void DepthHistoryNode::depthCallback(const sensor_msgs::ImageConstPtr& msg) {
  const FrameTimer timer;
  cv::Mat depth_m;
  if (const Refusal why = readDepth(*msg, depth_m)) return refuse(msg->header, why, timer);
  // Built from the camera whose size the depth stream confirms (its per-pixel rays are sized from it).
  if (!history_) history_ = std::make_unique<semexp::DepthHistory>(config_, bounds_, camera_);
  Eigen::Isometry3d T_WC;
  if (const Refusal why = cameraPose(msg->header, T_WC, false)) return refuse(msg->header, why, timer);
  const std::size_t invalid = history_->integrate(depth_m, T_WC);
  ++frames_integrated_;
  markers_dirty_ = markers_dirty_ || invalid > 0;
  reportFrame(msg->header, true, timer);
  if (markers_dirty_ && (ros::WallTime::now() - last_markers_).toSec() >= node_config_.marker_period_s) publishMarkers(msg->header.stamp);
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
  const std::vector<Eigen::Vector3d> ps = fromPoints(req.positions);
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

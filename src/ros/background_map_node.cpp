#include "semantic_exploration/ros/background_map_node.hpp"

#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "semantic_exploration/FrameIntegrated.h"
#include "semantic_exploration/MapBlocks.h"
#include "semantic_exploration/MapStats.h"
#include "semantic_exploration/ros/conversions.hpp"

namespace semexp_ros {

namespace {

constexpr double kColourSyncTolerance_s = 0.005;  // colour and depth of one frame share (almost) one stamp

semantic_exploration::MapBlocks toMsg(const semexp::MapBlocksData& d, const ros::Time& stamp, const std::string& frame) {
  semantic_exploration::MapBlocks m;
  m.header.stamp = stamp;
  m.header.frame_id = frame;
  m.sequence = d.sequence;
  m.full = d.full;
  m.resolution_m = static_cast<float>(d.resolution_m);
  m.block_size = static_cast<std::uint8_t>(d.block_size);
  m.origin.x = d.origin_m.x();
  m.origin.y = d.origin_m.y();
  m.origin.z = d.origin_m.z();
  m.encoding = semantic_exploration::MapBlocks::ENCODING_LOG_ODDS_I8;
  m.coords = d.coords;
  m.payload.resize(d.payload.size());
  if (!d.payload.empty()) std::memcpy(m.payload.data(), d.payload.data(), d.payload.size());
  m.uniform_coords = d.uniform_coords;
  m.uniform_values.resize(d.uniform_values.size());
  if (!d.uniform_values.empty()) std::memcpy(m.uniform_values.data(), d.uniform_values.data(), d.uniform_values.size());
  return m;
}

}  // namespace

BackgroundMapNode::BackgroundMapNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  const auto p = ParamReader::fromNodeHandle(pnh);
  camera_ = loadCamera(p);
  bounds_ = loadBounds(p);
  config_ = loadBackgroundMap(p);
  exploration_ = loadExploration(p);
  frames_ = loadFrames(p);
  poses_ = std::make_unique<PoseSource>(loadTf(p));
  p.getAtLeast("background_map/frontier_period_s", frontier_period_s_, 0.0, "s");
  p.getAtLeast("background_map/colour_wait_s", colour_wait_s_, 0.0, "s");
  p.getAtLeast("background_map/start_free_radius_m", start_free_radius_m_, 0.0, "m");
  map_ = std::make_unique<semexp::OccupancyMap>(config_, bounds_);
  evidence_ = std::make_unique<semexp::FrontierEvidence>(loadFrontierEvidence(p));

  occupied_pub_ = pnh.advertise<sensor_msgs::PointCloud2>(
      "occupied", 1, [this](const ros::SingleSubscriberPublisher& sub) { occupiedConnected(sub); },
      ros::SubscriberStatusCallback(), ros::VoidConstPtr(), true);
  frontiers_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("frontiers", 1, true);
  retired_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("retired_frontiers", 1, true);
  update_pub_ = pnh.advertise<semantic_exploration::MapBlocks>("map_update", 50);
  stats_pub_ = pnh.advertise<semantic_exploration::MapStats>("stats", 10);
  integrated_pub_ = nh.advertise<semantic_exploration::FrameIntegrated>("frame_integrated", 10);
  gains_srv_ = pnh.advertiseService("compute_gains", &BackgroundMapNode::computeGains, this);
  get_map_srv_ = pnh.advertiseService("get_map", &BackgroundMapNode::getMap, this);
  save_srv_ = pnh.advertiseService("save", &BackgroundMapNode::save, this);
  info_sub_ = nh.subscribe("camera/camera_info", 1, &BackgroundMapNode::infoCallback, this);
  depth_sub_ = nh.subscribe("camera/depth/image_raw", 2, &BackgroundMapNode::depthCallback, this);
  if (config_.integrate_colour) rgb_sub_ = nh.subscribe("camera/rgb/image_raw", 5, &BackgroundMapNode::rgbCallback, this);
  flush_timer_ = nh.createWallTimer(ros::WallDuration(std::max(0.005, 0.5 * colour_wait_s_)), &BackgroundMapNode::flushTimer, this);
  last_header_.frame_id = frames_.world;
  ROS_INFO("background_map: resolution %.3f m, bounds [%.1f %.1f %.1f] - [%.1f %.1f %.1f] m, colour %s",
           config_.resolution_m, bounds_.min_m.x(), bounds_.min_m.y(), bounds_.min_m.z(), bounds_.max_m.x(),
           bounds_.max_m.y(), bounds_.max_m.z(), config_.integrate_colour ? "on" : "off");
}

void BackgroundMapNode::infoCallback(const sensor_msgs::CameraInfoConstPtr& msg) {
  semexp::PinholeCamera c;
  const auto err = camera_input_.accept(*msg, camera_.d_min_m, camera_.d_max_m, c);
  if (!err.empty()) {
    drops_.drop("bad_camera_info", err);
    return;
  }
  camera_ = c;
  have_info_ = true;
}

// ------------------------------------------------------------ frame pairing

sensor_msgs::ImageConstPtr BackgroundMapNode::matchingRgb(const ros::Time& stamp) const {
  for (auto it = rgb_buffer_.rbegin(); it != rgb_buffer_.rend(); ++it)
    if (std::abs(((*it)->header.stamp - stamp).toSec()) <= kColourSyncTolerance_s) return *it;
  return nullptr;
}

void BackgroundMapNode::depthCallback(const sensor_msgs::ImageConstPtr& msg) {
  countFrameGaps(depth_gaps_, drops_, msg->header.stamp, "depth");
  if (pending_depth_) {  // an older frame whose colour never came
    processFrame(pending_depth_, nullptr);
    pending_depth_.reset();
  }
  if (!config_.integrate_colour) return processFrame(msg, nullptr);
  if (auto rgb = matchingRgb(msg->header.stamp)) return processFrame(msg, rgb);
  // Wait briefly for the colour image while someone publishes colour.
  if (rgb_sub_.getNumPublishers() > 0 ||
      (!last_rgb_wall_.isZero() && (ros::WallTime::now() - last_rgb_wall_).toSec() < 1.0)) {
    pending_depth_ = msg;
    pending_since_ = ros::WallTime::now();
    return;
  }
  processFrame(msg, nullptr);
}

void BackgroundMapNode::rgbCallback(const sensor_msgs::ImageConstPtr& msg) {
  rgb_buffer_.push_back(msg);
  while (rgb_buffer_.size() > 10) rgb_buffer_.pop_front();
  last_rgb_wall_ = ros::WallTime::now();
  if (pending_depth_ &&
      std::abs((msg->header.stamp - pending_depth_->header.stamp).toSec()) <= kColourSyncTolerance_s) {
    const auto d = pending_depth_;
    pending_depth_.reset();
    processFrame(d, msg);
  }
}

void BackgroundMapNode::flushTimer(const ros::WallTimerEvent&) {
  if (pending_depth_ && (ros::WallTime::now() - pending_since_).toSec() >= colour_wait_s_) {
    const auto d = pending_depth_;
    pending_depth_.reset();
    processFrame(d, nullptr);
  }
  // Frames may stop (the MAV hovers, a bag ends): the last change still goes out once its period is over.
  if (map_ && (frontiers_dirty_ || occupied_dirty_)) publishClouds(last_header_.stamp);
}

// -------------------------------------------------------------- integration

void BackgroundMapNode::reportFrame(const std_msgs::Header& header, bool integrated, double time_ms) {
  semantic_exploration::FrameIntegrated done;
  done.header = header;
  done.node = "background_map";
  done.integrated = integrated;
  done.time_ms = static_cast<float>(time_ms);
  integrated_pub_.publish(done);
}

void BackgroundMapNode::processFrame(const sensor_msgs::ImageConstPtr& msg, const sensor_msgs::ImageConstPtr& rgb_msg) {
  const auto t0 = ros::WallTime::now();
  auto fail = [&](const std::string& reason, const std::string& detail) {
    drops_.drop(reason, detail);
    publishStats(msg->header);
    reportFrame(msg->header, false, (ros::WallTime::now() - t0).toSec() * 1e3);
  };
  cv::Mat depth_m;
  auto err = depthToMeters(*msg, depth_m);
  if (!err.empty()) return fail("bad_encoding", err);
  camera_input_.depthFrame(depth_m.cols, depth_m.rows);
  if (!have_info_) return fail("no_camera_info", "depth received before any camera_info");
  if (depth_m.cols != camera_.width || depth_m.rows != camera_.height)
    return fail("size_mismatch", "depth " + std::to_string(depth_m.cols) + "x" + std::to_string(depth_m.rows) +
                                     " but camera_info " + std::to_string(camera_.width) + "x" +
                                     std::to_string(camera_.height));
  cv::Mat rgb;
  if (rgb_msg) {
    err = colourToRgb(*rgb_msg, rgb);
    if (err.empty() && rgb.size() != depth_m.size()) err = "colour and depth differ in size";
    if (!err.empty()) {
      drops_.drop("bad_rgb", err + " (integrating depth without colour)");
      rgb.release();
    }
  }
  Eigen::Isometry3d T_WC;
  err = poses_->cameraPose(frames_, msg->header, T_WC);
  if (!err.empty()) return fail("no_tf", err);
  if (!bounds_.contains(T_WC.translation()))
    return fail("out_of_bounds", "camera at (" + std::to_string(T_WC.translation().x()) + ", " +
                                     std::to_string(T_WC.translation().y()) + ", " +
                                     std::to_string(T_WC.translation().z()) + ") lies outside the map bounds");
  const auto t_int = ros::WallTime::now();
  semexp::IntegrationStats st;
  try {
    st = map_->integrate(depth_m, rgb, camera_, T_WC);
  } catch (const std::exception& e) {
    return fail("bad_input", e.what());
  }
  if (frames_integrated_ == 0 && start_free_radius_m_ > 0) {
    // The paper assumes free space around the start: the camera cannot see the MAV's own position.
    map_->markFreeSphere(T_WC.translation(), start_free_radius_m_);
    ROS_INFO("background_map: unknown space within %.2f m of the first camera pose marked free", start_free_radius_m_);
  }
  last_integration_ms_ = static_cast<float>((ros::WallTime::now() - t_int).toSec() * 1e3);
  const auto t_fr = ros::WallTime::now();
  map_->updateFrontiers();
  // depthToMeters returns a fresh (continuous) CV_32F image.
  if (depth_m.isContinuous()) evidence_->look(*map_, depth_m.ptr<float>(), camera_, T_WC);
  last_frontier_ms_ = static_cast<float>((ros::WallTime::now() - t_fr).toSec() * 1e3);
  invalid_depth_pixels_ += st.invalid_pixels;
  if (st.invalid_pixels > 0)
    ROS_DEBUG_THROTTLE(5.0, "background_map: %zu invalid depth pixels in the last frame (they carve nothing)",
                       st.invalid_pixels);
  ++frames_integrated_;
  last_header_ = msg->header;
  last_header_.frame_id = frames_.world;
  if (map_->pendingUpdateCount() > 0) update_pub_.publish(toMsg(map_->takeUpdate(), msg->header.stamp, frames_.world));
  publishStats(msg->header);
  frontiers_dirty_ = occupied_dirty_ = true;
  publishClouds(msg->header.stamp);
  reportFrame(msg->header, true, (ros::WallTime::now() - t0).toSec() * 1e3);
}

void BackgroundMapNode::publishStats(const std_msgs::Header& header) {
  semantic_exploration::MapStats s;
  s.header.stamp = header.stamp;
  s.header.frame_id = frames_.world;
  s.free_volume_m3 = map_->freeVolume();
  s.occupied_volume_m3 = map_->occupiedVolume();
  s.explored_volume_m3 = s.free_volume_m3 + s.occupied_volume_m3;
  s.frontier_count = static_cast<std::uint32_t>(map_->frontierCount());
  s.retired_frontier_count = static_cast<std::uint32_t>(evidence_->retiredCount());
  s.surface_voxels = surface_.occupied_voxels;
  s.surface_observed_share = surface_measured_ ? surface_.share() : -1.0;
  s.block_count = static_cast<std::uint32_t>(map_->blockCount());
  s.memory_bytes = map_->memoryBytes();
  s.integration_time_ms = last_integration_ms_;
  s.frontier_time_ms = last_frontier_ms_;
  s.frames_integrated = frames_integrated_;
  s.dropped_bad_encoding = drops_.count("bad_encoding");
  s.dropped_size_mismatch = drops_.count("size_mismatch");
  s.dropped_no_tf = drops_.count("no_tf");
  s.dropped_out_of_bounds = drops_.count("out_of_bounds");
  s.dropped_no_camera_info = drops_.count("no_camera_info");
  s.invalid_depth_pixels = invalid_depth_pixels_;
  stats_pub_.publish(s);
}

void BackgroundMapNode::publishClouds(const ros::Time& stamp) {
  // Each cloud keeps its own dirty flag: the frontier cloud falls due more often than the occupied one, and
  // the map change that made both dirty must still reach the occupied cloud.
  const ros::WallTime now = ros::WallTime::now();
  const auto due = [&](const ros::WallTime& last, double period_s) {
    return last.isZero() || (now - last).toSec() >= period_s;
  };
  if (frontiers_dirty_ && due(last_frontier_pub_, frontier_period_s_)) {
    std::vector<Eigen::Vector3d> active, retired;
    active.reserve(map_->frontierCount());
    map_->forEachFrontier([&](const Eigen::Vector3d& c, double) {
      (evidence_->retired(c) ? retired : active).push_back(c);
    });
    frontiers_pub_.publish(toPointCloud(active, stamp, frames_.world));
    retired_pub_.publish(toPointCloud(retired, stamp, frames_.world));
    last_frontier_pub_ = now;
    // The termination's background share, at the frontier cloud's pace (one pass over the occupied blocks).
    surface_ = map_->surfaceObservedWithin(exploration_.d_bg_m);
    surface_measured_ = true;
    frontiers_dirty_ = false;
  }
  if (occupied_dirty_ && due(last_occupied_pub_, config_.publish_period_s)) {
    // Built only for a listener; a skipped cloud is sent when one connects (the topic is latched, and rviz
    // started after the map stopped changing must still get it).
    occupied_skipped_ = occupied_pub_.getNumSubscribers() == 0;
    if (!occupied_skipped_) publishOccupied(stamp);
    last_occupied_pub_ = now;
    occupied_dirty_ = false;
  }
}

void BackgroundMapNode::publishOccupied(const ros::Time& stamp) {
  std::vector<Eigen::Vector3f> pts;
  std::vector<std::array<std::uint8_t, 3>> cols;
  map_->forEachOccupied([&](const Eigen::Vector3d& c, double, const std::uint8_t* rgb) {
    pts.push_back(c.cast<float>());
    cols.push_back({rgb[0], rgb[1], rgb[2]});
  });
  sensor_msgs::PointCloud2 cloud;
  cloud.header.stamp = stamp;
  cloud.header.frame_id = frames_.world;
  sensor_msgs::PointCloud2Modifier mod(cloud);
  mod.setPointCloud2FieldsByString(2, "xyz", "rgb");
  mod.resize(pts.size());
  sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  sensor_msgs::PointCloud2Iterator<std::uint8_t> r(cloud, "r"), g(cloud, "g"), b(cloud, "b");
  for (std::size_t i = 0; i < pts.size(); ++i, ++x, ++y, ++z, ++r, ++g, ++b) {
    *x = pts[i].x();
    *y = pts[i].y();
    *z = pts[i].z();
    *r = cols[i][0];
    *g = cols[i][1];
    *b = cols[i][2];
  }
  occupied_pub_.publish(cloud);
}

void BackgroundMapNode::occupiedConnected(const ros::SingleSubscriberPublisher&) {
  if (occupied_skipped_ && map_) {
    occupied_skipped_ = false;
    publishOccupied(last_header_.stamp);
  }
}

// ----------------------------------------------------------------- services

bool BackgroundMapNode::computeGains(semantic_exploration::ComputeGains::Request& req,
                                     semantic_exploration::ComputeGains::Response& res) {
  const int w = req.width, h = req.height;
  const std::string why = semexp::SphericalGrid::checkRequest(static_cast<long>(req.positions.size()), w, h);
  if (!why.empty()) {
    drops_.drop(w > 0 && h > 0 ? "request_too_large" : "bad_gain_request", "compute_gains: " + why);
    return false;
  }
  const std::size_t n = req.positions.size(), per = static_cast<std::size_t>(w) * h;
  if (!req.max_depth_m.empty() && req.max_depth_m.size() != n * per) {
    drops_.drop("bad_gain_request", "max_depth_m has " + std::to_string(req.max_depth_m.size()) + " values, expected " +
                                        std::to_string(n * per) + " (or none)");
    return false;
  }
  std::vector<Eigen::Vector3d> pos;
  pos.reserve(n);
  for (const auto& p : req.positions) pos.emplace_back(p.x, p.y, p.z);
  semexp::SphericalGrid grid;
  grid.width = w;
  grid.height = h;
  grid.vfov_rad = camera_.vfov_rad();
  semexp::GainSettings gs;
  gs.d_min_m = camera_.d_min_m;
  gs.d_max_m = camera_.d_max_m;
  gs.d_desired_m = exploration_.d_bg_m;
  std::vector<semexp::GainImages> gains;
  try {
    gains = map_->computeGains(pos, grid, gs, req.max_depth_m);
  } catch (const std::exception& e) {
    drops_.drop("bad_gain_request", e.what());
    return false;
  }
  std_msgs::Header header;
  header.stamp = ros::Time::now();
  header.frame_id = frames_.world;
  for (const auto& g : gains) {
    res.entropy_gain.push_back(floatImageMsg(header, g.entropy, w, h));
    res.distance_gain.push_back(floatImageMsg(header, g.distance, w, h));
    res.hit_depth.push_back(floatImageMsg(header, g.hit_depth_m, w, h));
  }
  return true;
}

bool BackgroundMapNode::getMap(semantic_exploration::GetMap::Request& req, semantic_exploration::GetMap::Response& res) {
  res.map = toMsg(map_->snapshot(req.compact), last_header_.stamp, frames_.world);
  return true;
}

bool BackgroundMapNode::save(semantic_exploration::SaveMap::Request& req, semantic_exploration::SaveMap::Response& res) {
  if (const std::string why = checkSaveDirectory(req.directory); !why.empty()) {
    res.success = false;
    res.message = "background_map: save refused: " + why;
    ROS_ERROR("%s", res.message.c_str());
    return true;
  }
  try {
    namespace fs = std::filesystem;
    const fs::path dir(req.directory);
    fs::create_directories(dir);
    const std::string bt = (dir / "background_map.bt").string();
    const std::string own = (dir / "background_map.semexpmap").string();
    const std::string cloud = (dir / "occupied.ply").string();
    map_->exportOctomap(bt);
    map_->save(own);
    map_->exportOccupiedPly(cloud);
    res.files = {bt, own, cloud};
    res.success = true;
    res.message = "wrote " + bt + " (OctoMap), " + own + " (own format) and " + cloud + " (occupied voxel centres)";
  } catch (const std::exception& e) {
    res.success = false;
    res.message = std::string("background_map: save failed: ") + e.what();
    ROS_ERROR("%s", res.message.c_str());
  }
  return true;
}

}  // namespace semexp_ros

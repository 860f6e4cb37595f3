#include "semantic_exploration/ros/background_map_node.hpp"

#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "semantic_exploration/MapBlocks.h"
#include "semantic_exploration/MapStats.h"
#include "semantic_exploration/ros/conversions.hpp"

namespace semexp_ros {

namespace {

constexpr double kColourSyncTolerance_s = 0.005;  // colour and depth of one frame share (almost) one stamp
// Private parameter: the /run_id of the launch whose start this node's first instance marked free.
constexpr const char* kStartFreeMarkedParam = "start_free_marked_run_id";

}  // namespace

BackgroundMapNode::BackgroundMapNode(ros::NodeHandle& nh, ros::NodeHandle& pnh)
    : CameraNode(nh, pnh, BeforeCameraInfo::kRefuse, true),
      config_(loadBackgroundMap(params())),
      exploration_(loadExploration(params())),
      node_config_(loadBackgroundMapNode(params())),
      map_(std::make_unique<semexp::OccupancyMap>(config_, bounds_)),
      evidence_(std::make_unique<semexp::FrontierEvidence>(loadFrontierEvidence(params()))),
      surface_share_period_(node_config_.surface_share_period_s) {

  occupied_pub_ = pnh.advertise<sensor_msgs::PointCloud2>(
      "occupied", 1, [this](const ros::SingleSubscriberPublisher& sub) { occupiedConnected(sub); },
      ros::SubscriberStatusCallback(), ros::VoidConstPtr(), true);
  frontiers_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("frontiers", 1, true);
  retired_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("retired_frontiers", 1, true);
  update_pub_ = pnh.advertise<semantic_exploration::MapBlocks>("map_update", 50);
  stats_pub_ = pnh.advertise<semantic_exploration::MapStats>("stats", 10);
  gains_srv_ = pnh.advertiseService("compute_gains", &BackgroundMapNode::computeGains, this);
  get_map_srv_ = pnh.advertiseService("get_map", &BackgroundMapNode::getMap, this);
  save_srv_ = pnh.advertiseService("save", &BackgroundMapNode::save, this);
  depth_sub_ = nh.subscribe("camera/depth/image_raw", 2, &BackgroundMapNode::depthCallback, this);
  if (config_.integrate_colour) rgb_sub_ = nh.subscribe("camera/rgb/image_raw", 5, &BackgroundMapNode::rgbCallback, this);
  flush_timer_ = nh.createWallTimer(ros::WallDuration(std::max(0.005, 0.5 * node_config_.colour_wait_s)), &BackgroundMapNode::flushTimer, this);
  last_header_.frame_id = frames_.world;
  // The paper's free sphere holds at the mission's start only. An instance respawned by its launch
  // mid-flight (same /run_id) starts wherever the MAV is, perhaps 0.2 m above the floor, and a sphere
  // there would mark the unseen floor free for the planner to fly into. The first instance records
  // the run it marked the sphere in; a later one of the same run leaves it out and takes back the
  // map it lost from the planner's replica instead.
  nh.param<std::string>("/run_id", run_id_, "");
  std::string marked_in;
  pnh.param<std::string>(kStartFreeMarkedParam, marked_in, "");
  respawned_ = !run_id_.empty() && marked_in == run_id_;
  if (respawned_) restoreMap(nh);
  ROS_INFO("background_map: resolution %.3f m, bounds [%.1f %.1f %.1f] - [%.1f %.1f %.1f] m, colour %s",
           config_.resolution_m, bounds_.min_m.x(), bounds_.min_m.y(), bounds_.min_m.z(), bounds_.max_m.x(),
           bounds_.max_m.y(), bounds_.max_m.z(), config_.integrate_colour ? "on" : "off");
}

// ----------------------------------------------------------------- restart

void BackgroundMapNode::restoreMap(ros::NodeHandle& nh) {
  const std::string& service = node_config_.restore_map_service;
  if (service.empty()) {
    ROS_WARN("background_map: restarted within run %s; restore_map_service is empty, so the map starts empty "
             "(and without the start's free sphere, which belongs to the mission's start)", run_id_.c_str());
    return;
  }
  const std::string resolved = nh.resolveName(service);
  std::string why;
  semantic_exploration::GetMap srv;
  srv.request.compact = true;
  // Bounded: the planner may itself wait (up to its service_timeout_s) on this node's services, which
  // answer only once this constructor is done. A call given up is joined when the node shuts down.
  restore_caller_ = std::make_unique<ServiceCaller>(nh, node_config_.restore_wait_s, drops_);
  if (restore_caller_->call(service, srv, why) == ServiceCaller::Result::kOk) {
    semexp::MapBlocksData blocks;
    why = fromMapBlocksMsg(srv.response.map, blocks);
    if (why.empty() && !map_->applyBlocks(blocks))
      why = "its geometry (resolution, block size, origin) differs from this map's";
    if (!why.empty()) {
      drops_.drop("bad_restored_map", resolved + ": " + why);
    } else {
      map_->updateFrontiers();
      ROS_WARN("background_map: restarted within run %s: took back %zu blocks (%zu uniform) of occupancy from %s "
               "(%.1f m^3 free, %zu frontier voxels); colour and observation distances start anew",
               run_id_.c_str(), blocks.blockCount() + blocks.uniform_values.size(), blocks.uniform_values.size(),
               resolved.c_str(), map_->freeVolume(), map_->frontierCount());
      return;
    }
  }
  ROS_WARN("background_map: restarted within run %s: could not take the map back from %s (%s); the map starts "
           "empty, without the start's free sphere", run_id_.c_str(), resolved.c_str(), why.c_str());
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
  if (pending_depth_ && (ros::WallTime::now() - pending_since_).toSec() >= node_config_.colour_wait_s) {
    const auto d = pending_depth_;
    pending_depth_.reset();
    processFrame(d, nullptr);
  }
  // Frames may stop (the MAV hovers, a bag ends): the last change still goes out once its period is over.
  if (map_ && (frontiers_dirty_ || occupied_dirty_)) publishClouds(last_header_.stamp);
}

// -------------------------------------------------------------- integration

void BackgroundMapNode::processFrame(const sensor_msgs::ImageConstPtr& msg, const sensor_msgs::ImageConstPtr& rgb_msg) {
  // The integration pool's threads work for this frame too: their CPU counts (not only this thread's).
  const FrameTimer timer([this] { return map_->workerCpuSeconds(); });
  // Stats before the report: a listener woken by the report finds the drop counted.
  const auto fail = [&](const Refusal& why) {
    drops_.drop(why.reason, why.detail);
    publishStats(msg->header);
    reportFrame(msg->header, false, timer);
  };
  cv::Mat depth_m;
  if (const Refusal why = readDepth(*msg, depth_m)) return fail(why);
  cv::Mat rgb;
  if (rgb_msg) {
    std::string err = colourToRgb(*rgb_msg, rgb);
    if (err.empty() && rgb.size() != depth_m.size()) err = "colour and depth differ in size";
    if (!err.empty()) {
      drops_.drop("bad_rgb", err + " (integrating depth without colour)");
      rgb.release();
    }
  }
  Eigen::Isometry3d T_WC;
  if (const Refusal why = cameraPose(msg->header, T_WC)) return fail(why);
  const auto t_int = ros::WallTime::now();
  semexp::IntegrationStats st;
  try {
    st = map_->integrate(depth_m, rgb, camera_, T_WC);
  } catch (const std::exception& e) {
    return fail({"bad_input", e.what()});
  }
  if (frames_integrated_ == 0 && !respawned_) {
    if (node_config_.start_free_radius_m > 0) {
      // The paper assumes free space around the start: the camera cannot see the MAV's own position.
      map_->markFreeSphere(T_WC.translation(), node_config_.start_free_radius_m);
      ROS_INFO("background_map: unknown space within %.2f m of the first camera pose marked free",
               node_config_.start_free_radius_m);
    }
    ros::NodeHandle("~").setParam(kStartFreeMarkedParam, run_id_);
  }
  last_integration_ms_ = static_cast<float>((ros::WallTime::now() - t_int).toSec() * 1e3);
  const auto t_fr = ros::WallTime::now();
  map_->updateFrontiers();
  try {
    const cv::Mat depth = depth_m.isContinuous() ? depth_m : depth_m.clone();
    evidence_->look(*map_, depth.ptr<float>(), camera_, T_WC);
  } catch (const std::exception& e) {  // the frame is integrated; only this frame's looks are lost
    ROS_ERROR_THROTTLE(5.0, "background_map: frontier evidence skipped for a frame: %s", e.what());
  }
  last_frontier_ms_ = static_cast<float>((ros::WallTime::now() - t_fr).toSec() * 1e3);
  invalid_depth_pixels_ += st.invalid_pixels;
  if (st.invalid_pixels > 0)
    ROS_DEBUG_THROTTLE(5.0, "background_map: %zu invalid depth pixels in the last frame (they carve nothing)",
                       st.invalid_pixels);
  ++frames_integrated_;
  last_header_ = msg->header;
  last_header_.frame_id = frames_.world;
  if (map_->pendingUpdateCount() > 0) {
    const semantic_exploration::MapBlocks update = toMapBlocksMsg(map_->takeUpdate(), msg->header.stamp, frames_.world);
    last_update_sequence_ = update.sequence;
    update_pub_.publish(update);
  }
  // The termination's background share, counted again only in the cells changed since the last count, paced
  // by image stamps; the planner reads it once per iteration.
  if (surface_share_period_.due(msg->header.stamp)) surface_ = map_->trackSurfaceObservedWithin(exploration_.d_bg_m);
  // Clouds before the stats: the stats name the newest frontier cloud (frontiers_stamp), which must be this
  // frame's when it fell due, or a planner that waits for it could plan on the previous frame's frontiers.
  frontiers_dirty_ = occupied_dirty_ = true;
  publishClouds(msg->header.stamp);
  publishStats(msg->header);
  reportFrame(msg->header, true, timer);
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
  s.surface_observed_share = surface_share_period_.started() ? surface_.share() : -1.0;
  s.block_count = static_cast<std::uint32_t>(map_->blockCount());
  s.memory_bytes = map_->memoryBytes();
  s.integration_time_ms = last_integration_ms_;
  s.frontier_time_ms = last_frontier_ms_;
  s.frames_integrated = frames_integrated_;
  s.map_update_sequence = last_update_sequence_;
  s.frontiers_stamp = last_frontiers_stamp_;
  s.dropped_bad_depth = drops_.count("bad_depth");
  s.dropped_size_mismatch = drops_.count("size_mismatch");
  s.dropped_no_tf = drops_.count("no_tf");
  s.dropped_out_of_bounds = drops_.count("out_of_bounds");
  s.dropped_no_camera_info = drops_.count("no_camera_info");
  s.invalid_depth_pixels = invalid_depth_pixels_;
  s.frame_cpu_median_ms = static_cast<float>(cpuBudget().median_ms());
  s.frame_cpu_p95_ms = static_cast<float>(cpuBudget().p95_ms());
  stats_pub_.publish(s);
}

void BackgroundMapNode::publishClouds(const ros::Time& stamp) {
  // Each cloud keeps its own dirty flag: the frontier cloud falls due more often than the occupied one, and
  // the map change that made both dirty must still reach the occupied cloud.
  const ros::WallTime now = ros::WallTime::now();
  const auto due = [&](const ros::WallTime& last, double period_s) {
    return last.isZero() || (now - last).toSec() >= period_s;
  };
  if (frontiers_dirty_ && due(last_frontier_pub_, node_config_.frontier_period_s)) {
    std::vector<Eigen::Vector3d> active, retired;
    active.reserve(map_->frontierCount());
    map_->forEachFrontier([&](const Eigen::Vector3d& c, double) {
      (evidence_->retired(c) ? retired : active).push_back(c);
    });
    frontiers_pub_.publish(toPointCloud(active, stamp, frames_.world));
    last_frontiers_stamp_ = stamp;
    retired_pub_.publish(toPointCloud(retired, stamp, frames_.world));
    last_frontier_pub_ = now;
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
  const std::vector<Eigen::Vector3d> pos = fromPoints(req.positions);
  semexp::SphericalGrid grid;
  grid.width = w;
  grid.height = h;
  grid.vfov_rad = camera_.vfov_rad();
  semexp::GainSettings gs;
  gs.d_min_m = camera_.d_min_m;
  gs.d_max_m = camera_.d_max_m;
  gs.d_desired_m = exploration_.d_bg_m;
  gs.threads = config_.gain_threads;
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
  res.map = toMapBlocksMsg(map_->snapshot(req.compact), last_header_.stamp, frames_.world);
  return true;
}

bool BackgroundMapNode::save(semantic_exploration::SaveMap::Request& req, semantic_exploration::SaveMap::Response& res) {
  if (saveRefused(req.directory, res)) return true;
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

#include "semantic_exploration/ros/planner_node.hpp"

#include <nav_msgs/Path.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <stdexcept>

#include "semantic_exploration/CandidateViewArray.h"
#include "semantic_exploration/ComputeGains.h"
#include "semantic_exploration/ExplorationStatus.h"
#include "semantic_exploration/GetHistoryMasks.h"
#include "semantic_exploration/GetMap.h"

namespace semexp_ros {

using semantic_exploration::ExplorationStatus;

namespace {

geometry_msgs::Quaternion yawQuaternion(double yaw) {
  geometry_msgs::Quaternion q;
  q.w = std::cos(0.5 * yaw);
  q.z = std::sin(0.5 * yaw);
  return q;
}

geometry_msgs::Point toPoint(const Eigen::Vector3d& p) {
  geometry_msgs::Point m;
  m.x = p.x();
  m.y = p.y();
  m.z = p.z();
  return m;
}

nav_msgs::Path toPath(const std::vector<Eigen::Vector3d>& path, const std::vector<double>& yaw,
                      const std::string& frame, const ros::Time& stamp) {
  nav_msgs::Path out;
  out.header.frame_id = frame;
  out.header.stamp = stamp;
  for (std::size_t i = 0; i < path.size(); ++i) {
    geometry_msgs::PoseStamped ps;
    ps.header = out.header;
    ps.pose.position = toPoint(path[i]);
    ps.pose.orientation = yawQuaternion(i < yaw.size() ? yaw[i] : (yaw.empty() ? 0.0 : yaw.back()));
    out.poses.push_back(ps);
  }
  return out;
}

// 32FC1 image -> GainImage of the expected size; throws on anything else.
semexp::GainImage toGainImage(const sensor_msgs::Image& img, int w, int h, const char* what) {
  if (img.width == 0 && img.height == 0) return semexp::GainImage();  // "no such gain"
  if (img.encoding != sensor_msgs::image_encodings::TYPE_32FC1 || static_cast<int>(img.width) != w ||
      static_cast<int>(img.height) != h || img.step < img.width * 4 ||
      img.data.size() < static_cast<std::size_t>(img.step) * img.height || img.is_bigendian)
    throw std::runtime_error(std::string(what) + " image is not a " + std::to_string(w) + "x" + std::to_string(h) +
                             " 32FC1 image (got " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                             " " + img.encoding + ")");
  semexp::GainImage out(w, h);
  for (int v = 0; v < h; ++v)
    std::memcpy(&out.values[static_cast<std::size_t>(v) * w], &img.data[static_cast<std::size_t>(v) * img.step],
                static_cast<std::size_t>(w) * sizeof(float));
  return out;
}

std_msgs::ColorRGBA colour(float r, float g, float b, float a) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

}  // namespace

PlannerNode::PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh) {
  const auto p = ParamReader::fromNodeHandle(pnh);
  config_ = loadPlanner(p);
  exploration_ = loadExploration(p);
  camera_ = loadCamera(p);
  bounds_ = loadBounds(p);
  frames_ = loadFrames(p);
  poses_ = std::make_unique<PoseSource>(loadTf(p), false);  // the latest pose, never an interpolated one: no gap guard
  p.get("planner/service_timeout_s", service_timeout_s_);
  if (!(service_timeout_s_ > 0)) throw semexp::ConfigError("planner/service_timeout_s", "must be > 0 s");
  p.get("planner/retry_period_s", retry_period_s_);
  if (!(retry_period_s_ > 0)) throw semexp::ConfigError("planner/retry_period_s", "must be > 0 s");
  p.getAtLeast("planner/goal_timeout_factor", goal_timeout_factor_, 1.0, "(a factor)");

  path_pub_ = pnh.advertise<nav_msgs::Path>("path", 1, true);
  candidates_pub_ = pnh.advertise<semantic_exploration::CandidateViewArray>("candidates", 1, true);
  markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("candidate_markers", 1, true);
  status_pub_ = pnh.advertise<ExplorationStatus>("status", 10, true);
  const char* gains[4] = {"gain_images/entropy", "gain_images/background", "gain_images/object",
                          "gain_images/combined"};
  for (int i = 0; i < 4; ++i) gain_pubs_[i] = pnh.advertise<sensor_msgs::Image>(gains[i], 1, true);
  plan_srv_ = pnh.advertiseService("plan_once", &PlannerNode::planOnce, this);
  update_sub_ = nh.subscribe("background_map/map_update", 50, &PlannerNode::mapUpdateCallback, this);
  frontiers_sub_ = nh.subscribe("background_map/frontiers", 1, &PlannerNode::frontiersCallback, this);
  objects_sub_ = nh.subscribe("object_map/objects", 1, &PlannerNode::objectsCallback, this);
  goal_sub_ = nh.subscribe("mav/goal_reached", 1, &PlannerNode::goalReachedCallback, this);
  stats_sub_ = nh.subscribe("background_map/stats", 1, &PlannerNode::statsCallback, this);
  rejected_sub_ = nh.subscribe("mav/path_rejected", 5, &PlannerNode::pathRejectedCallback, this);
  timer_ = nh.createTimer(ros::Duration(0.2), &PlannerNode::timerCallback, this);
  ROS_INFO("planner: n %d, P_fr %.2f, a_ent/a_bg/a_obj %.2f/%.2f/%.2f, d_bg %.1f m, d_obj %.1f m",
           config_.n_candidates, config_.p_frontier, config_.a_ent, config_.a_bg, config_.a_obj,
           exploration_.d_bg_m, exploration_.d_obj_m);
  state_ = ExplorationStatus::STATE_WAITING;
  publishStatus(state_, "waiting for the map");
}

PlannerNode::~PlannerNode() {
  for (auto& c : pending_calls_)
    if (c.worker.joinable()) c.worker.join();
}

void PlannerNode::publishStatus(uint8_t state, const std::string& message) {
  ExplorationStatus s;
  s.header.stamp = ros::Time::now();
  s.header.frame_id = frames_.world;
  s.state = state;
  s.iteration = iteration_;
  s.message = message;
  s.service_timeouts = static_cast<uint32_t>(drops_.count("service_timeout"));
  status_pub_.publish(s);
}

// ---------------------------------------------------------------- bounded service calls

struct PlannerNode::CallState {
  std::mutex mutex;
  std::condition_variable done_cv;
  bool available = false;  ///< the service was found
  bool done = false;       ///< the worker has finished
  bool ok = false;         ///< the call returned an answer
};

void PlannerNode::reapCalls() {
  for (auto it = pending_calls_.begin(); it != pending_calls_.end();) {
    bool done = false;
    {
      std::lock_guard<std::mutex> lock(it->state->mutex);
      done = it->state->done;
    }
    if (!done) {
      ++it;
      continue;
    }
    it->worker.join();
    it = pending_calls_.erase(it);
  }
}

template <class Srv>
PlannerNode::CallResult PlannerNode::callService(const std::string& service, Srv& srv, std::string& why) {
  reapCalls();
  char buf[256];
  const auto earlier = timed_out_now_.find(service);
  if (earlier != timed_out_now_.end()) {  // waiting again in the same iteration would only double the stall
    why = earlier->second;
    return CallResult::kTimedOut;
  }
  const auto pending = std::count_if(pending_calls_.begin(), pending_calls_.end(),
                                     [&service](const PendingCall& c) { return c.service == service; });
  if (pending >= kMaxPendingCalls) {
    std::snprintf(buf, sizeof(buf), "service %s not called: %d earlier calls are still unanswered", service.c_str(),
                  static_cast<int>(pending));
    why = buf;
    drops_.drop("service_busy", why);
    return CallResult::kBusy;
  }
  // The worker owns its client, request and response: a call abandoned here
  // may answer later into its own copy, which nobody reads. A fresh
  // non-persistent client per call finds a restarted service again and is
  // never used by two threads at once. It is built directly rather than
  // through the NodeHandle, which would keep a record of every client made
  // (one per call) and, used from a worker after shutdown, start roscpp again.
  auto state = std::make_shared<CallState>();
  auto call = std::make_shared<Srv>(srv);
  ros::ServiceClient client(nh_.resolveName(service), false, ros::M_string(),
                            ros::service_traits::md5sum<Srv>());
  const double timeout_s = service_timeout_s_;
  std::thread worker([state, call, client, timeout_s]() mutable {
    const bool available = client.waitForExistence(ros::Duration(timeout_s));
    {
      std::lock_guard<std::mutex> lock(state->mutex);
      state->available = available;
    }
    const bool ok = available && client.call(*call);
    {
      std::lock_guard<std::mutex> lock(state->mutex);
      state->ok = ok;
      state->done = true;
    }
    state->done_cv.notify_all();
  });
  std::unique_lock<std::mutex> lock(state->mutex);
  const bool done =
      state->done_cv.wait_for(lock, std::chrono::duration<double>(timeout_s), [&state] { return state->done; });
  const bool available = state->available, ok = state->ok;
  lock.unlock();
  if (done) {
    worker.join();
    if (ok) {
      srv.response = std::move(call->response);
      return CallResult::kOk;
    }
    if (!available) {
      std::snprintf(buf, sizeof(buf), "service %s timed out after %.1f s (not available)", service.c_str(), timeout_s);
      why = buf;
      timed_out_now_[service] = why;
      drops_.drop("service_timeout", why);
      return CallResult::kUnavailable;
    }
    why = "service " + service + " failed";
    drops_.drop("service_failed", why);
    return CallResult::kFailed;
  }
  std::snprintf(buf, sizeof(buf), "service %s timed out after %.1f s%s", service.c_str(), timeout_s,
                available ? " (no answer)" : " (not available)");
  why = buf;
  pending_calls_.push_back(PendingCall{service, state, std::move(worker)});
  timed_out_now_[service] = why;
  drops_.drop("service_timeout", why);
  return CallResult::kTimedOut;
}

// ---------------------------------------------------------------- map input

bool PlannerNode::applyBlocks(const semantic_exploration::MapBlocks& msg, bool& gap) {
  gap = false;
  if (msg.encoding != semantic_exploration::MapBlocks::ENCODING_LOG_ODDS_I8) {
    drops_.drop("bad_map_encoding", "MapBlocks encoding " + std::to_string(msg.encoding) + " unsupported");
    return false;
  }
  semexp::MapReplica::Update u;
  u.sequence = msg.sequence;
  u.full = msg.full;
  u.resolution_m = msg.resolution_m;
  u.block_size = msg.block_size;
  u.origin_W = {msg.origin.x, msg.origin.y, msg.origin.z};
  u.coords = msg.coords.data();
  u.coord_count = msg.coords.size();
  u.payload = msg.payload.data();
  u.payload_size = msg.payload.size();
  switch (replica_.apply(u)) {
    case semexp::MapReplica::Result::kApplied: return true;
    case semexp::MapReplica::Result::kStale: return false;
    case semexp::MapReplica::Result::kGap: gap = true; return false;
    case semexp::MapReplica::Result::kBadInput: drops_.drop("bad_map_update", replica_.last_error()); return false;
  }
  return false;
}

bool PlannerNode::resync() {
  semantic_exploration::GetMap srv;
  std::string why;
  timed_out_now_.erase("background_map/get_map");  // a resync is not part of an iteration
  if (callService("background_map/get_map", srv, why) != CallResult::kOk) {
    drops_.drop("resync_failed", why + "; the replica may be stale until the next gap");
    return false;
  }
  bool gap = false;
  srv.response.map.full = true;
  const bool ok = applyBlocks(srv.response.map, gap);
  if (ok) ROS_INFO("planner: map replica resynced at sequence %lu (%zu blocks)",
                   static_cast<unsigned long>(replica_.sequence()), replica_.block_count());
  return ok;
}

void PlannerNode::mapUpdateCallback(const semantic_exploration::MapBlocksConstPtr& msg) {
  bool gap = false;
  if (!applyBlocks(*msg, gap) && gap) {
    ROS_WARN("planner: map update %lu after %lu: resyncing", static_cast<unsigned long>(msg->sequence),
             static_cast<unsigned long>(replica_.sequence()));
    resync();
  }
}

void PlannerNode::frontiersCallback(const sensor_msgs::PointCloud2ConstPtr& msg) {
  bool has_x = false, has_y = false, has_z = false;
  for (const auto& f : msg->fields) {
    if (f.datatype != sensor_msgs::PointField::FLOAT32) continue;
    has_x = has_x || f.name == "x";
    has_y = has_y || f.name == "y";
    has_z = has_z || f.name == "z";
  }
  if (!has_x || !has_y || !has_z ||
      msg->data.size() < static_cast<std::size_t>(msg->row_step) * msg->height) {
    drops_.drop("bad_frontiers", "frontier cloud without float x, y, z or with a short buffer");
    return;
  }
  std::vector<Eigen::Vector3d> f;
  f.reserve(static_cast<std::size_t>(msg->width) * msg->height);
  for (sensor_msgs::PointCloud2ConstIterator<float> x(*msg, "x"), y(*msg, "y"), z(*msg, "z"); x != x.end();
       ++x, ++y, ++z) {
    const Eigen::Vector3d p(*x, *y, *z);
    if (p.allFinite()) f.push_back(p);
  }
  frontiers_W_ = std::move(f);
  have_frontiers_ = true;
}

void PlannerNode::objectsCallback(const semantic_exploration::ObjectArrayConstPtr& msg) {
  std::vector<semexp::ObjectSummary> objs;
  for (const auto& o : msg->objects) {
    semexp::ObjectSummary s;
    s.id = o.id;
    s.bbox_min_W = {o.bbox_min.x, o.bbox_min.y, o.bbox_min.z};
    s.bbox_max_W = {o.bbox_max.x, o.bbox_max.y, o.bbox_max.z};
    s.centroid_W = {o.centroid.x, o.centroid.y, o.centroid.z};
    s.observed_fraction = o.observed_fraction;
    if (s.bbox_min_W.allFinite() && s.bbox_max_W.allFinite() && s.centroid_W.allFinite()) objs.push_back(s);
  }
  objects_ = std::move(objs);
}

void PlannerNode::statsCallback(const semantic_exploration::MapStatsConstPtr& msg) {
  if (std::isfinite(msg->explored_volume_m3) && msg->explored_volume_m3 >= 0)
    explored_volume_m3_ = msg->explored_volume_m3;
}

// ---------------------------------------------------------------- triggers

void PlannerNode::goalReachedCallback(const geometry_msgs::PoseStampedConstPtr&) {
  if (finished_ || state_ != ExplorationStatus::STATE_EXECUTING) return;
  std::string message;
  iterate(message);
}

void PlannerNode::pathRejectedCallback(const std_msgs::StringConstPtr& msg) {
  if (finished_ || state_ != ExplorationStatus::STATE_EXECUTING) return;
  // Replan on the next timer tick after retry_period_s, not at once: the
  // same map would likely give the same path.
  ROS_WARN("planner: the executor rejected the path (%s); replanning in %.1f s", msg->data.c_str(), retry_period_s_);
  state_ = ExplorationStatus::STATE_WAITING;
  last_attempt_ = ros::WallTime::now();
  publishStatus(state_, "path rejected by the executor: " + msg->data);
}

void PlannerNode::timerCallback(const ros::TimerEvent&) {
  if (finished_) return;
  if (state_ == ExplorationStatus::STATE_EXECUTING) {
    const double waited = (ros::Time::now() - executing_since_).toSec();
    if (waited < goal_timeout_factor_ * expected_duration_s_ + 10.0) return;
    ROS_WARN("planner: goal not reached after %.1f s (expected %.1f s); replanning", waited, expected_duration_s_);
  } else if ((ros::WallTime::now() - last_attempt_).toSec() < retry_period_s_) {
    return;
  }
  std::string message;
  iterate(message);  // reports "waiting for the map" itself while the replica is empty
}

bool PlannerNode::planOnce(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::string message;
  res.success = iterate(message);
  res.message = message;
  return true;
}

// ---------------------------------------------------------------- providers

void PlannerNode::addServiceNote(const std::string& note) {
  // The intermediate-yaw call may fail the same way as the candidates' call.
  if (std::find(service_notes_.begin(), service_notes_.end(), note) == service_notes_.end())
    service_notes_.push_back(note);
}

std::vector<semexp::GainSet> PlannerNode::computeGains(const std::vector<Eigen::Vector3d>& positions) {
  const int w = config_.raycast_width, h = config_.raycast_height;
  semantic_exploration::ComputeGains bg;
  bg.request.width = static_cast<uint16_t>(w);
  bg.request.height = static_cast<uint16_t>(h);
  for (const auto& p : positions) bg.request.positions.push_back(toPoint(p));
  std::string why;
  if (callService("background_map/compute_gains", bg, why) != CallResult::kOk) throw std::runtime_error(why);
  const auto& r = bg.response;
  if (r.entropy_gain.size() != positions.size() || r.distance_gain.size() != positions.size())
    throw std::runtime_error("background_map/compute_gains returned " + std::to_string(r.entropy_gain.size()) +
                             " images for " + std::to_string(positions.size()) + " positions");
  std::vector<semexp::GainSet> out(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    out[i].entropy = toGainImage(r.entropy_gain[i], w, h, "entropy gain");
    out[i].background = toGainImage(r.distance_gain[i], w, h, "background gain");
  }
  if (config_.a_obj <= 0) return out;  // classic mode: no object raycast needed

  // Object gains, occluded by the background: rays stop just behind its first
  // occupied voxel, or where they leave an object's box if that voxel is the
  // object's own.
  semantic_exploration::ComputeGains obj;
  obj.request = bg.request;
  semexp::SphericalGrid grid;
  grid.width = w;
  grid.height = h;
  grid.vfov_rad = camera_.vfov_rad();  // as the map servers lay out their images
  if (r.hit_depth.size() == positions.size()) {
    obj.request.max_depth_m.reserve(positions.size() * static_cast<std::size_t>(w) * h);
    for (std::size_t i = 0; i < positions.size(); ++i) {
      const semexp::GainImage d = toGainImage(r.hit_depth[i], w, h, "hit depth");
      if (d.empty()) {
        obj.request.max_depth_m.clear();
        break;
      }
      const std::vector<float> limits =
          semexp::object_ray_limits_m(positions[i], grid, d.values, replica_.resolution_m(), objects_);
      obj.request.max_depth_m.insert(obj.request.max_depth_m.end(), limits.begin(), limits.end());
    }
  }
  if (callService("object_map/compute_gains", obj, why) != CallResult::kOk) {
    addServiceNote(why + ": planned without object gains");
    return out;
  }
  if (obj.response.distance_gain.size() != positions.size()) {
    drops_.drop("no_object_gains", "object_map/compute_gains returned " +
                                       std::to_string(obj.response.distance_gain.size()) + " images for " +
                                       std::to_string(positions.size()) + " positions; planning without object gains");
    addServiceNote("object_map/compute_gains answered with the wrong number of images");
    return out;
  }
  for (std::size_t i = 0; i < positions.size(); ++i)
    out[i].object = toGainImage(obj.response.distance_gain[i], w, h, "object gain");
  return out;
}

std::vector<std::vector<std::uint8_t>> PlannerNode::historyMasks(const std::vector<Eigen::Vector3d>& positions) {
  const int w = config_.raycast_width, h = config_.raycast_height;
  semantic_exploration::GetHistoryMasks srv;
  srv.request.width = static_cast<uint16_t>(w);
  srv.request.height = static_cast<uint16_t>(h);
  for (const auto& p : positions) srv.request.positions.push_back(toPoint(p));
  std::string why;
  if (callService("depth_history/get_masks", srv, why) != CallResult::kOk) {
    addServiceNote(why + ": planned without the history");
    return {};
  }
  if (srv.response.masks.size() != positions.size()) {
    drops_.drop("no_history", "depth_history/get_masks returned " + std::to_string(srv.response.masks.size()) +
                                  " masks for " + std::to_string(positions.size()) +
                                  " positions; planning without the history");
    addServiceNote("depth_history/get_masks answered with the wrong number of masks");
    return {};
  }
  std::vector<std::vector<std::uint8_t>> out(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const auto& m = srv.response.masks[i];
    if (static_cast<int>(m.width) != w || static_cast<int>(m.height) != h || m.step < m.width ||
        m.data.size() < static_cast<std::size_t>(m.step) * m.height) {
      drops_.drop("bad_history_mask", "history mask of the wrong size ignored");
      continue;
    }
    out[i].resize(static_cast<std::size_t>(w) * h);
    for (int v = 0; v < h; ++v)
      std::memcpy(&out[i][static_cast<std::size_t>(v) * w], &m.data[static_cast<std::size_t>(v) * m.step],
                  static_cast<std::size_t>(w));
  }
  return out;
}

// ---------------------------------------------------------------- iteration

bool PlannerNode::pathSafe(const std::vector<Eigen::Vector3d>& path, bool escaped, std::string& why) const {
  // Last guard before publishing: no point of the path within R plus the
  // clearance margin of an occupied voxel (unknown allowed), R/2 on an escape
  // segment out of an invalid start (as the path planner checks it).
  const double step = std::max(0.5 * replica_.resolution_m(), 1e-3);
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const double radius = (escaped && i == 0) ? 0.5 * config_.mav_radius_m : config_.clearance_radius_m();
    const double len = (path[i + 1] - path[i]).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
    for (int k = 0; k <= n; ++k) {
      const Eigen::Vector3d q = path[i] + (path[i + 1] - path[i]) * (static_cast<double>(k) / n);
      if (!replica_.sphere_not_occupied(q, radius)) {
        char buf[160];
        std::snprintf(buf, sizeof(buf), "occupied voxel within %.3f m of (%.2f, %.2f, %.2f) on segment %zu of %zu",
                      radius, q.x(), q.y(), q.z(), i + 1, path.size() - 1);
        why = buf;
        return false;
      }
    }
  }
  if (path.empty()) why = "empty path";
  return !path.empty();
}

bool PlannerNode::iterate(std::string& message) {
  last_attempt_ = ros::WallTime::now();
  const ros::Time now = ros::Time::now();
  if (replica_.empty()) {
    message = "waiting for the map (the replica is empty)";
    publishStatus(ExplorationStatus::STATE_WAITING, message);
    return false;
  }
  Eigen::Isometry3d T_WB;
  const std::string err = poses_->lookup(frames_.world, frames_.body, ros::Time(0), T_WB);
  if (!err.empty()) {
    message = "waiting for the MAV pose: " + err;
    publishStatus(ExplorationStatus::STATE_WAITING, message);
    return false;
  }
  if (!planner_ || planner_resolution_m_ != replica_.resolution_m()) {
    planner_ = std::make_unique<semexp::ExplorationPlanner>(config_, exploration_, bounds_, camera_,
                                                             replica_.resolution_m());
    planner_resolution_m_ = replica_.resolution_m();
  }
  if (!have_frontiers_) {
    message = "waiting for the first frontier cloud";
    publishStatus(ExplorationStatus::STATE_WAITING, message);
    return false;
  }
  if (!started_) {
    started_ = true;
    start_time_ = now;
  }
  ++iteration_;
  timed_out_now_.clear();
  service_notes_.clear();
  state_ = ExplorationStatus::STATE_PLANNING;
  publishStatus(state_, "planning");

  semexp::ExplorationInputs in;
  in.position_W = T_WB.translation();
  in.yaw_rad = std::atan2(T_WB.linear()(1, 0), T_WB.linear()(0, 0));
  in.elapsed_s = (now - start_time_).toSec();
  in.frontiers_W = frontiers_W_;
  in.objects = objects_;
  in.explored_volume_m3 = explored_volume_m3_;

  semexp::ExplorationProviders prov;
  const semexp::MapReplica& replica = replica_;
  const semexp::Bounds bounds = bounds_;
  prov.is_free = [&replica, bounds](const Eigen::Vector3d& p, double r) {
    return bounds.contains(p) && replica.sphere_free(p, r);
  };
  prov.not_occupied = [&replica](const Eigen::Vector3d& p, double r) { return replica.sphere_not_occupied(p, r); };
  prov.gains = [this](const std::vector<Eigen::Vector3d>& ps) { return computeGains(ps); };
  prov.history = [this](const std::vector<Eigen::Vector3d>& ps) { return historyMasks(ps); };

  semexp::IterationResult r;
  try {
    r = planner_->plan(in, prov);
  } catch (const std::exception& e) {
    r = semexp::IterationResult();
    r.provider_error = true;
    r.message = std::string("planning failed: ") + e.what();
  }
  // Failures of optional services do not stop the iteration; say so.
  for (const auto& note : service_notes_) r.message += "; " + note;
  bool published = false;
  std::string unsafe;
  if (r.winner >= 0 &&
      !pathSafe(r.path_W, r.candidates[static_cast<std::size_t>(r.winner)].plan.escaped, unsafe)) {
    r.message = "the chosen path failed the final occupancy check (" + unsafe + ") and was not published; " +
                r.message;
    r.winner = -1;
  }
  if (r.winner >= 0) {
    path_pub_.publish(toPath(r.path_W, r.path_yaw_rad, frames_.world, now));
    published = true;
    const auto& w = r.candidates[static_cast<std::size_t>(r.winner)];
    expected_duration_s_ = w.path_time_s;
    executing_since_ = now;
    // One line per iteration: what won and why, so a run's log shows where the MAV went and for which gain.
    const char* source = w.sample.source == semexp::CandidateSource::kObject ? "object" : "frontier";
    ROS_INFO("planner: iteration %u: %s candidate%s%s (%d of %zu reachable) at (%.2f, %.2f, %.2f) yaw %.2f: "
             "gain %.3f (entropy %.3f, bg %.3f, obj %.3f), %s path %.1f s, utility %.4f",
             iteration_, source, w.sample.source == semexp::CandidateSource::kObject ? " of object " : "",
             w.sample.source == semexp::CandidateSource::kObject ? std::to_string(w.sample.object_id).c_str() : "",
             r.candidates_reachable, r.candidates.size(), w.position_W.x(), w.position_W.y(), w.position_W.z(),
             w.yaw_rad, w.gain, w.gain_entropy, w.gain_bg, w.gain_obj, semexp::PlannedPath::name(w.plan.status),
             w.path_time_s, w.utility);
  }
  publishResult(r, now, in.yaw_rad);

  if (r.finished) {
    finished_ = true;
    state_ = ExplorationStatus::STATE_FINISHED;
    ROS_INFO("planner: exploration finished after %u iterations: %s (%s)", iteration_,
             r.termination_reason.c_str(), r.message.c_str());
  } else {
    state_ = published ? ExplorationStatus::STATE_EXECUTING : ExplorationStatus::STATE_WAITING;
    if (!published) ROS_WARN("planner: iteration %u: %s", iteration_, r.message.c_str());
  }
  ExplorationStatus s;
  s.header.stamp = now;
  s.header.frame_id = frames_.world;
  s.state = state_;
  s.iteration = iteration_;
  s.termination_reason = r.termination_reason;
  s.message = r.message;
  s.candidates_sampled = static_cast<uint32_t>(r.candidates.size());
  s.candidates_reachable = static_cast<uint32_t>(r.candidates_reachable);
  s.planning_time_s = static_cast<float>(r.total_s);
  s.sampling_time_s = static_cast<float>(r.sampling_s);
  s.path_planning_time_s = static_cast<float>(r.path_planning_s);
  s.gains_time_s = static_cast<float>(r.gains_s);
  s.yaw_time_s = static_cast<float>(r.yaw_s);
  s.service_timeouts = static_cast<uint32_t>(drops_.count("service_timeout"));
  status_pub_.publish(s);
  message = r.message;
  last_attempt_ = ros::WallTime::now();  // the retry period is the pause after an attempt, however long it took
  return published;
}

void PlannerNode::publishResult(const semexp::IterationResult& r, const ros::Time& stamp, double current_yaw) {
  const int w = config_.raycast_width, h = config_.raycast_height;
  semantic_exploration::CandidateViewArray arr;
  arr.header.stamp = stamp;
  arr.header.frame_id = frames_.world;
  arr.winner = r.winner;
  double max_u = 0.0;
  for (const auto& c : r.candidates) max_u = std::max(max_u, c.utility);

  visualization_msgs::MarkerArray markers;
  visualization_msgs::Marker clear;
  clear.header = arr.header;
  clear.action = visualization_msgs::Marker::DELETEALL;
  markers.markers.push_back(clear);
  int id = 0;
  for (std::size_t i = 0; i < r.candidates.size(); ++i) {
    const auto& c = r.candidates[i];
    semantic_exploration::CandidateView v;
    v.position = toPoint(c.position_W);
    v.yaw_rad = static_cast<float>(c.yaw_rad);
    v.gain_entropy = static_cast<float>(c.gain_entropy);
    v.gain_bg = static_cast<float>(c.gain_bg);
    v.gain_obj = static_cast<float>(c.gain_obj);
    v.gain = static_cast<float>(c.gain);
    v.path_time_s = static_cast<float>(c.path_time_s);
    v.utility = static_cast<float>(c.utility);
    v.source = c.sample.source == semexp::CandidateSource::kObject ? semantic_exploration::CandidateView::SOURCE_OBJECT
                                                                   : semantic_exploration::CandidateView::SOURCE_FRONTIER;
    v.object_id = c.sample.object_id;
    v.reachable = c.reachable;
    std::vector<double> yaws(c.plan.path_W.size(), c.yaw_rad);
    if (!yaws.empty()) yaws.front() = current_yaw;
    if (static_cast<int>(i) == r.winner) yaws = r.path_yaw_rad;
    v.path = toPath(c.plan.path_W, yaws, frames_.world, stamp);
    arr.candidates.push_back(v);

    // Sphere coloured by utility (red low, green high; grey unreachable),
    // an arrow along its yaw and its utility as text.
    const float f = max_u > 0 ? static_cast<float>(c.utility / max_u) : 0.f;
    visualization_msgs::Marker m;
    m.header = arr.header;
    m.ns = "candidates";
    m.id = id++;
    m.type = visualization_msgs::Marker::SPHERE;
    m.pose.position = v.position;
    m.pose.orientation.w = 1.0;
    m.scale.x = m.scale.y = m.scale.z = static_cast<int>(i) == r.winner ? 0.3 : 0.15;
    m.color = c.reachable ? colour(1.f - f, f, 0.f, 0.9f) : colour(0.5f, 0.5f, 0.5f, 0.5f);
    markers.markers.push_back(m);
    if (c.reachable) {
      visualization_msgs::Marker a = m;
      a.ns = "candidate_yaw";
      a.id = id++;
      a.type = visualization_msgs::Marker::ARROW;
      a.pose.orientation = yawQuaternion(c.yaw_rad);
      a.scale.x = 0.4;
      a.scale.y = a.scale.z = 0.04;
      markers.markers.push_back(a);
      visualization_msgs::Marker t = m;
      t.ns = "candidate_utility";
      t.id = id++;
      t.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
      t.pose.position.z += 0.25;
      t.scale.x = t.scale.y = t.scale.z = 0.15;
      t.color = colour(1.f, 1.f, 1.f, 1.f);
      char buf[32];
      std::snprintf(buf, sizeof(buf), "%.3f", c.utility);
      t.text = buf;
      markers.markers.push_back(t);
    }
  }
  if (r.winner >= 0) {
    visualization_msgs::Marker line;
    line.header = arr.header;
    line.ns = "winner_path";
    line.id = id++;
    line.type = visualization_msgs::Marker::LINE_STRIP;
    line.pose.orientation.w = 1.0;
    line.scale.x = 0.04;
    line.color = colour(0.2f, 0.4f, 1.f, 1.f);
    for (const auto& p : r.path_W) line.points.push_back(toPoint(p));
    markers.markers.push_back(line);
  }
  candidates_pub_.publish(arr);
  markers_pub_.publish(markers);
  if (r.winner >= 0) {
    std_msgs::Header gain_header;
    gain_header.frame_id = frames_.world;
    gain_header.stamp = stamp;
    gain_pubs_[0].publish(floatImageMsg(gain_header, r.winner_gains.entropy.values, w, h));
    gain_pubs_[1].publish(floatImageMsg(gain_header, r.winner_gains.background.values, w, h));
    gain_pubs_[2].publish(floatImageMsg(gain_header, r.winner_gains.object.values, w, h));
    gain_pubs_[3].publish(floatImageMsg(gain_header, r.winner_combined.values, w, h));
  }
}

}  // namespace semexp_ros

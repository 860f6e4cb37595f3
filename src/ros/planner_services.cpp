#include "semantic_exploration/ros/planner_services.hpp"

#include <algorithm>
#include <stdexcept>

#include "semantic_exploration/ComputeGains.h"
#include "semantic_exploration/GetHistoryMasks.h"
#include "semantic_exploration/ros/conversions.hpp"

namespace semexp_ros {

PlannerServices::PlannerServices(const ros::NodeHandle& nh, const semexp::PlannerConfig& config,
                                 const semexp::PinholeCamera& camera, double timeout_s, DropCounter& drops)
    : config_(config), camera_(camera), drops_(drops), caller_(nh, timeout_s, drops) {}

void PlannerServices::newIteration() {
  caller_.newRound();
  notes_.clear();
}

void PlannerServices::addNote(const std::string& note) {
  // The intermediate-yaw call may fail the same way as the candidates' call.
  if (std::find(notes_.begin(), notes_.end(), note) == notes_.end()) notes_.push_back(note);
}

std::vector<semexp::GainSet> PlannerServices::gains(const std::vector<Eigen::Vector3d>& positions,
                                                    const std::vector<semexp::ObjectSummary>& objects,
                                                    double background_resolution_m) {
  const int w = config_.raycast_width, h = config_.raycast_height;
  semantic_exploration::ComputeGains bg;
  bg.request.width = static_cast<uint16_t>(w);
  bg.request.height = static_cast<uint16_t>(h);
  for (const auto& p : positions) bg.request.positions.push_back(toPoint(p));
  std::string why;
  if (caller_.call("background_map/compute_gains", bg, why) != ServiceCaller::Result::kOk)
    throw std::runtime_error(why);
  const auto& r = bg.response;
  std::vector<semexp::GainSet> out = toBackgroundGains(r, positions.size(), w, h);
  if (config_.a_obj <= 0) return out;  // classic mode: no object raycast needed

  // Object gains are optional: whatever goes wrong with them, plan without.
  try {
    addObjectGains(bg, positions, objects, background_resolution_m, out);
  } catch (const std::exception& e) {
    for (auto& g : out) g.object = semexp::GainImage();
    drops_.drop("bad_object_gains", std::string(e.what()) + "; planning without object gains");
    addNote(std::string("object gains unusable (") + e.what() + "): planned without object gains");
  }
  return out;
}

void PlannerServices::addObjectGains(const semantic_exploration::ComputeGains& bg,
                                     const std::vector<Eigen::Vector3d>& positions,
                                     const std::vector<semexp::ObjectSummary>& objects,
                                     double background_resolution_m, std::vector<semexp::GainSet>& out) {
  const int w = config_.raycast_width, h = config_.raycast_height;
  const auto& r = bg.response;
  std::string why;
  // Object gains, occluded by the background (semexp::objectRayLimitsBatch).
  semantic_exploration::ComputeGains obj;
  obj.request = bg.request;
  if (r.hit_depth.size() == positions.size()) {
    std::vector<semexp::GainImage> hits;
    for (const auto& d : r.hit_depth) hits.push_back(toGainImage(d, w, h, "hit depth"));
    semexp::SphericalGrid grid;
    grid.width = w;
    grid.height = h;
    grid.vfov_rad = camera_.vfov_rad();  // as the map servers lay out their images
    obj.request.max_depth_m = semexp::objectRayLimitsBatch(positions, grid, hits, background_resolution_m, objects);
  }
  if (caller_.call("object_map/compute_gains", obj, why) != ServiceCaller::Result::kOk) {
    addNote(why + ": planned without object gains");
    return;
  }
  if (obj.response.distance_gain.size() != positions.size()) {
    drops_.drop("no_object_gains", "object_map/compute_gains returned " +
                                       std::to_string(obj.response.distance_gain.size()) + " images for " +
                                       std::to_string(positions.size()) + " positions; planning without object gains");
    addNote("object_map/compute_gains answered with the wrong number of images");
    return;
  }
  for (std::size_t i = 0; i < positions.size(); ++i)
    out[i].object = toGainImage(obj.response.distance_gain[i], w, h, "object gain");
}

std::vector<std::vector<std::uint8_t>> PlannerServices::history(const std::vector<Eigen::Vector3d>& positions) {
  const int w = config_.raycast_width, h = config_.raycast_height;
  semantic_exploration::GetHistoryMasks srv;
  srv.request.width = static_cast<uint16_t>(w);
  srv.request.height = static_cast<uint16_t>(h);
  for (const auto& p : positions) srv.request.positions.push_back(toPoint(p));
  std::string why;
  if (caller_.call("depth_history/get_masks", srv, why) != ServiceCaller::Result::kOk) {
    addNote(why + ": planned without the history");
    return {};
  }
  if (srv.response.masks.size() != positions.size()) {
    drops_.drop("no_history", "depth_history/get_masks returned " + std::to_string(srv.response.masks.size()) +
                                  " masks for " + std::to_string(positions.size()) +
                                  " positions; planning without the history");
    addNote("depth_history/get_masks answered with the wrong number of masks");
    return {};
  }
  std::size_t bad = 0;
  auto out = toHistoryMasks(srv.response.masks, w, h, bad);
  if (bad > 0) drops_.drop("bad_history_mask", "history mask of the wrong size ignored", bad);
  return out;
}

bool PlannerServices::getMap(semantic_exploration::GetMap& srv) {
  std::string why;
  caller_.forgetTimeout("background_map/get_map");  // a resync is not part of an iteration
  srv.request.compact = true;  // uniform blocks as one value: the answer grows with the map's detail, not its volume
  if (caller_.call("background_map/get_map", srv, why) == ServiceCaller::Result::kOk) return true;
  drops_.drop("resync_failed", why + "; the replica may be stale until the next update calls for a resync");
  return false;
}

}  // namespace semexp_ros

#pragma once
/// @file planner_services.hpp
/// The planner's side of the map servers' services, as the core's providers
/// see it: batched gain images (`background_map/compute_gains`, then
/// `object_map/compute_gains` with the background's hit depths as occlusion
/// limits), invalid-depth history masks (`depth_history/get_masks`) and the
/// full map for a replica resync (`background_map/get_map`). Every call is
/// bounded in time (ServiceCaller). Background gains are required (a failure
/// throws, which the core reports as a provider error); object gains and
/// history masks are optional: without them the iteration goes on, and
/// notes() says why for the iteration's status.

#include <ros/ros.h>

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "semantic_exploration/ComputeGains.h"
#include "semantic_exploration/GetMap.h"
#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/planner_config.hpp"
#include "semantic_exploration/core/planning/interfaces.hpp"
#include "semantic_exploration/ros/node_common.hpp"
#include "semantic_exploration/ros/service_caller.hpp"

namespace semexp_ros {

class PlannerServices {
 public:
  /// Images are config.raycast_width x raycast_height in the SphericalGrid
  /// layout with the camera's vertical field of view; timeout_s bounds each call.
  PlannerServices(const ros::NodeHandle& nh, const semexp::PlannerConfig& config, const semexp::PinholeCamera& camera,
                  double timeout_s, DropCounter& drops);

  /// Starts a planning iteration: forgets the last one's timeouts and notes.
  void newIteration();
  /// Gains at each position. Object gains only with a_obj > 0; `objects` and
  /// the background resolution (m) give the occlusion limits. Throws
  /// std::runtime_error if background gains cannot be had.
  std::vector<semexp::GainSet> gains(const std::vector<Eigen::Vector3d>& positions_W,
                                     const std::vector<semexp::ObjectSummary>& objects,
                                     double background_resolution_m);
  /// History masks per position, or none (all directions valid) if the service fails.
  std::vector<std::vector<std::uint8_t>> history(const std::vector<Eigen::Vector3d>& positions_W);
  /// The whole background map; false (counted as resync_failed) if the call fails.
  bool getMap(semantic_exploration::GetMap& srv);
  /// Failures of optional services in this iteration, each once.
  const std::vector<std::string>& notes() const { return notes_; }

 private:
  void addNote(const std::string& note);
  /// Chains object_map/compute_gains to the background's answer `bg` and fills
  /// out[i].object; throws on malformed images (the caller goes on without).
  void addObjectGains(const semantic_exploration::ComputeGains& bg, const std::vector<Eigen::Vector3d>& positions_W,
                      const std::vector<semexp::ObjectSummary>& objects, double background_resolution_m,
                      std::vector<semexp::GainSet>& out);

  semexp::PlannerConfig config_;
  semexp::PinholeCamera camera_;
  DropCounter& drops_;
  ServiceCaller caller_;
  std::vector<std::string> notes_;
};

}  // namespace semexp_ros

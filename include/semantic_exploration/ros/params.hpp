#pragma once
/// @file params.hpp
/// The one place that turns ROS parameters into the core Config structs
/// (loaders in src/ros/params.cpp, ParamReader in src/ros/param_reader.cpp).
///
/// Every node reads its private namespace (launch files load config/*.yaml
/// there), so a setting has the same name in YAML, code and docs, e.g.
/// `background_map/resolution_m`. A present parameter of the wrong type, a
/// missing required one or a value rejected by Config::validate() throws
/// semexp::ConfigError naming the parameter; nodes exit on it at startup.

#include <xmlrpcpp/XmlRpcValue.h>

#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "semantic_exploration/core/background_map_config.hpp"
#include "semantic_exploration/core/bounds.hpp"
#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/class_table.hpp"
#include "semantic_exploration/core/depth_history_config.hpp"
#include "semantic_exploration/core/detector/detector_config.hpp"
#include "semantic_exploration/core/exploration_config.hpp"
#include "semantic_exploration/core/matching_config.hpp"
#include "semantic_exploration/core/object_map_config.hpp"
#include "semantic_exploration/core/planner_config.hpp"
#include "semantic_exploration/core/frontier_evidence.hpp"
#include "semantic_exploration/core/planning/frontier_retirement.hpp"
#include "semantic_exploration/core/planning/object_retirement.hpp"
#include "semantic_exploration/core/planning/termination.hpp"
#include "semantic_exploration/core/planning/trajectory.hpp"

namespace ros {
class NodeHandle;
}

namespace semexp_ros {

/// Names of the tf frames (REP-103/105).
struct FrameNames {
  std::string world = "world";
  std::string body = "body";
  std::string camera = "camera";
};

/// How a node gets poses from tf2.
struct TfSettings {
  double timeout_s = 0.1;  ///< `tf_timeout_s`: wait for a pose at an image stamp, wall s
  double max_gap_s = 0.2;  ///< `max_tf_gap_s`: refuse a pose interpolated across a wider gap (TfGapGuard), s; 0 = off
};

/// Settings of the planner node itself (not of the core planner).
struct PlannerNodeConfig {
  double service_timeout_s = 5.0;    ///< `planner/service_timeout_s`: longest a service call may take, finding it included, wall s
  double retry_period_s = 1.0;       ///< `planner/retry_period_s`: pause after an iteration without a path, wall s
  double goal_timeout_factor = 3.0;  ///< `planner/goal_timeout_factor`: replan if the goal is not reached in factor x path time + 10 s
};

/// Settings of the background_map node itself (not of the core map).
struct BackgroundMapNodeConfig {
  double frontier_period_s = 0.5;    ///< `background_map/frontier_period_s`: minimum period between ~frontiers clouds, s
  /// `background_map/surface_share_period_s`: minimum period between measurements of the surface share seen from
  /// <= d_bg (MapStats), s of the depth images' stamps; 0 = every frame.
  double surface_share_period_s = 2.0;
  double colour_wait_s = 0.05;       ///< `background_map/colour_wait_s`: how long a depth frame waits for its colour image, wall s
  double start_free_radius_m = 0.5;  ///< `background_map/start_free_radius_m`: unknown space this close to the first camera pose is free, m
  /// `background_map/restore_map_service`: where an instance respawned within its launch's run gets the map
  /// it lost (GetMap; the planner's replica); "" = start that instance with an empty map.
  std::string restore_map_service = "planner/get_map";
  double restore_wait_s = 10.0;  ///< `background_map/restore_wait_s`: how long a respawned instance waits for it, wall s
};

/// Settings of the depth_history node itself.
struct DepthHistoryNodeConfig {
  double marker_period_s = 1.0;  ///< `depth_history/marker_period_s`: minimum period between ~markers updates, s
};

/// How object_map and instance_matching pair their input streams.
struct ImageSyncConfig {
  double max_interval_s = 0.02;  ///< `sync_max_interval_s`: messages of one frame lie at most this far apart, s
};

/// One parameter a loader read: its path and the default it had in code
/// (the value before reading, as text: numbers with full precision, true /
/// false, strings in double quotes, lists in brackets, "" for a map).
struct ParamRead {
  std::string path;
  std::string default_text;
};

/// Reads typed values out of a parameter tree (the node's private namespace).
class ParamReader {
 public:
  explicit ParamReader(const XmlRpc::XmlRpcValue& root) : root_(root) {}
  /// Reads the whole private namespace of `pnh`.
  static ParamReader fromNodeHandle(const ros::NodeHandle& pnh);

  /// True if `path` ("a/b/c") exists.
  bool has(const std::string& path) const;
  /// Optional parameters: leave `out` unchanged if absent, throw if present with a wrong type.
  void get(const std::string& path, double& out) const;
  void get(const std::string& path, int& out) const;
  void get(const std::string& path, bool& out) const;
  void get(const std::string& path, std::string& out) const;
  void get(const std::string& path, std::vector<std::string>& out) const;
  void get(const std::string& path, std::vector<double>& out) const;
  /// Optional number that must be >= `min_value` (`unit` names its unit in the error).
  void getAtLeast(const std::string& path, double& out, double min_value, const std::string& unit) const;
  /// Optional number that must lie in (0, max_value] (`unit` names its unit in the error).
  void getPositiveAtMost(const std::string& path, double& out, double max_value, const std::string& unit) const;
  /// Optional map name -> value (`what` describes it in the error, e.g. "class name -> resolution in m"):
  /// replaces `out` as a whole if present; each entry is read as `path/name`.
  template <typename T>
  void getMap(const std::string& path, std::map<std::string, T>& out, const std::string& what) const {
    const XmlRpc::XmlRpcValue* v = find(path);
    if (!v) return;
    if (v->getType() != XmlRpc::XmlRpcValue::TypeStruct) throw semexp::ConfigError(path, "must be a map " + what);
    out.clear();
    auto& m = const_cast<XmlRpc::XmlRpcValue&>(*v);  // XmlRpc's iterators are non-const
    for (auto it = m.begin(); it != m.end(); ++it) {
      T value{};
      get(path + "/" + it->first, value);
      out[it->first] = value;
    }
  }
  /// Required parameters: throw ConfigError("missing") if absent.
  template <typename T>
  void require(const std::string& path, T& out) const {
    record(path, "required");
    if (!has(path)) throw semexp::ConfigError(path, "is required but missing");
    // Recorded once, as required: what `out` held is no default. The log is back even if get() throws.
    struct Pause {
      std::vector<ParamRead>*& log;
      std::vector<ParamRead>* const saved;
      ~Pause() { log = saved; }
    } pause{log_, log_};
    log_ = nullptr;
    get(path, out);
  }

  /// The value at `path`, or nullptr.
  const XmlRpc::XmlRpcValue* find(const std::string& path) const;

  /// From now on every get(), getAtLeast() and require() also appends what it
  /// read to `log` (null: stop), so that a tool can list the parameters.
  void recordReads(std::vector<ParamRead>* log) { log_ = log; }

 private:
  void record(const std::string& path, std::string default_text) const;
  XmlRpc::XmlRpcValue root_;
  mutable std::vector<ParamRead>* log_ = nullptr;
};

// Each loader reads its section and validates it (throws semexp::ConfigError).
semexp::PinholeCamera loadCamera(const ParamReader& p);  ///< `camera/*`; intrinsics required
semexp::Bounds loadBounds(const ParamReader& p);         ///< `bounds/*`
semexp::ClassTable loadClasses(const ParamReader& p);    ///< `classes/*`
semexp::ExplorationConfig loadExploration(const ParamReader& p);      ///< `exploration/*`
semexp::BackgroundMapConfig loadBackgroundMap(const ParamReader& p);  ///< `background_map/*`
semexp::ObjectMapConfig loadObjectMap(const ParamReader& p);          ///< `object_map/*`
semexp::MatchingConfig loadMatching(const ParamReader& p);            ///< `matching/*`
semexp::DepthHistoryConfig loadDepthHistory(const ParamReader& p);    ///< `depth_history/*`
semexp::PlannerConfig loadPlanner(const ParamReader& p);              ///< `planner/*`
/// `detector/*`; also checks that every class_map value is one of `classes`' names.
semexp::DetectorConfig loadDetector(const ParamReader& p, const semexp::ClassTable& classes);
FrameNames loadFrames(const ParamReader& p);                          ///< `frames/*`
TfSettings loadTf(const ParamReader& p);                              ///< `tf_timeout_s`, `max_tf_gap_s`
PlannerNodeConfig loadPlannerNode(const ParamReader& p);  ///< `planner/{service_timeout_s,retry_period_s,goal_timeout_factor}`
semexp::TerminationConfig loadTermination(const ParamReader& p);               ///< `termination/*`
semexp::FrontierRetirementConfig loadFrontierRetirement(const ParamReader& p);  ///< `frontier_retirement/*`
semexp::ObjectRetirementConfig loadObjectRetirement(const ParamReader& p);  ///< `object_retirement/*`
semexp::FrontierEvidenceConfig loadFrontierEvidence(const ParamReader& p);      ///< `frontier_evidence/*`

/// `planner/{a_max_mps2,alpha_max_radps2,trajectory_sample_period_s}`: the trajectory's limits besides v_max, omega_max.
semexp::TrajectoryConfig loadTrajectory(const ParamReader& p);

/// Settings of the setpoint_streamer node (`setpoint_streamer/*`).
struct SetpointStreamerConfig {
  double rate_hz = 20.0;                ///< `rate_hz`: setpoints per second (of ROS time), Hz
  double pose_timeout_s = 0.5;          ///< `pose_timeout_s`: stop streaming when the newest pose is older, s
  double max_start_offset_m = 0.5;      ///< `max_start_offset_m`: refuse a trajectory starting farther from the MAV, m
  double goal_tolerance_m = 0.1;        ///< `goal_tolerance_m`: goal reached within this distance of the end, m
  double goal_yaw_tolerance_rad = 0.1;  ///< `goal_yaw_tolerance_rad`: and this yaw error, rad
};
SetpointStreamerConfig loadSetpointStreamer(const ParamReader& p);  ///< `setpoint_streamer/*`

/// `display_cut/max_z_m`: the display_cut node shows the map up to this height in world, m.
double loadDisplayCut(const ParamReader& p);

/// `background_map/{frontier_period_s,surface_share_period_s,colour_wait_s,start_free_radius_m}`
BackgroundMapNodeConfig loadBackgroundMapNode(const ParamReader& p);
/// `depth_history/marker_period_s`; also checks that `history`'s image size
/// is the planner's raycast size (`planner/raycast_{width,height}`) when a
/// planner section is present: get_masks answers only its own size.
DepthHistoryNodeConfig loadDepthHistoryNode(const ParamReader& p, const semexp::DepthHistoryConfig& history);
ImageSyncConfig loadImageSync(const ParamReader& p);  ///< `sync_max_interval_s`

/// Every loader above by name, each reading all its parameters from `p`
/// (whose errors it throws): for test/tools/list_params, which lists what
/// the nodes read so that a test can compare it with the YAML files.
std::vector<std::pair<std::string, std::function<void(const ParamReader&)>>> allLoaders();

}  // namespace semexp_ros

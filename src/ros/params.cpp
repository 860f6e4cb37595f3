// Every loader of params.hpp: each reads one section of the node's private
// namespace into its Config struct and validates it. Sections every node
// reads first, then the map nodes' (background_map ... display_cut), then the
// planner's (exploration ... setpoint_streamer); allLoaders() last.
#include "semantic_exploration/ros/params.hpp"

#include <cmath>
#include <cstdint>
#include <string>

namespace semexp_ros {

using semexp::ConfigError;

namespace {

Eigen::Vector3d getVec3(const ParamReader& p, const std::string& path, const Eigen::Vector3d& def) {
  std::vector<double> v = {def.x(), def.y(), def.z()};
  p.get(path, v);
  if (v.size() != 3) throw ConfigError(path, "must be a list of 3 numbers [x, y, z]");
  return {v[0], v[1], v[2]};
}

}  // namespace

semexp::PinholeCamera loadCamera(const ParamReader& p) {
  semexp::PinholeCamera c;
  p.require("camera/width", c.width);
  p.require("camera/height", c.height);
  p.require("camera/fx", c.fx);
  p.require("camera/fy", c.fy);
  p.require("camera/cx", c.cx);
  p.require("camera/cy", c.cy);
  p.get("camera/d_min_m", c.d_min_m);
  p.get("camera/d_max_m", c.d_max_m);
  c.validate("camera/");
  return c;
}

semexp::Bounds loadBounds(const ParamReader& p) {
  semexp::Bounds b;
  b.min_m = getVec3(p, "bounds/min_m", b.min_m);
  b.max_m = getVec3(p, "bounds/max_m", b.max_m);
  b.validate("bounds/");
  return b;
}

semexp::ClassTable loadClasses(const ParamReader& p) {
  semexp::ClassTable t;
  p.get("classes/names", t.names);
  p.get("classes/of_interest", t.of_interest);
  p.get("classes/default_resolution_m", t.default_resolution_m);
  p.getMap("classes/resolution_m", t.resolution_m, "class name -> resolution in m");
  t.validate("classes/");
  return t;
}

FrameNames loadFrames(const ParamReader& p) {
  FrameNames f;
  p.get("frames/world", f.world);
  p.get("frames/body", f.body);
  p.get("frames/camera", f.camera);
  if (f.world.empty()) throw ConfigError("frames/world", "must not be empty");
  if (f.body.empty()) throw ConfigError("frames/body", "must not be empty");
  if (f.camera.empty()) throw ConfigError("frames/camera", "must not be empty");
  return f;
}

TfSettings loadTf(const ParamReader& p) {
  TfSettings t;
  p.getAtLeast("tf_timeout_s", t.timeout_s, 0.0, "s");
  p.getAtLeast("max_tf_gap_s", t.max_gap_s, 0.0, "s");
  return t;
}

ImageSyncConfig loadImageSync(const ParamReader& p) {
  ImageSyncConfig c;
  p.getAtLeast("sync_max_interval_s", c.max_interval_s, 0.0, "s");
  return c;
}

// ------------------------------------------------------------ map nodes

semexp::BackgroundMapConfig loadBackgroundMap(const ParamReader& p) {
  semexp::BackgroundMapConfig c;
  const std::string n = "background_map/";
  p.get(n + "resolution_m", c.resolution_m);
  p.get(n + "block_size", c.block_size);
  p.get(n + "log_odds_free", c.log_odds_free);
  p.get(n + "log_odds_occupied", c.log_odds_occupied);
  p.get(n + "log_odds_min", c.log_odds_min);
  p.get(n + "log_odds_max", c.log_odds_max);
  p.get(n + "surface_band_m", c.surface_band_m);
  p.get(n + "integrate_colour", c.integrate_colour);
  p.get(n + "integrate_min_distance", c.integrate_min_distance);
  p.get(n + "surface_front_m", c.surface_front_m);
  p.get(n + "surface_front_quadratic_per_m", c.surface_front_quadratic_per_m);
  p.get(n + "free_margin_quadratic_per_m", c.free_margin_quadratic_per_m);
  p.get(n + "publish_period_s", c.publish_period_s);
  p.get(n + "integration_threads", c.integration_threads);
  p.get(n + "gain_threads", c.gain_threads);
  c.validate(n);
  return c;
}

BackgroundMapNodeConfig loadBackgroundMapNode(const ParamReader& p) {
  BackgroundMapNodeConfig c;
  const std::string n = "background_map/";
  p.getAtLeast(n + "frontier_period_s", c.frontier_period_s, 0.0, "s");
  p.getAtLeast(n + "surface_share_period_s", c.surface_share_period_s, 0.0, "s");
  // Longer would leave the termination's background condition on a share older than several iterations.
  semexp::require(c.surface_share_period_s <= 60.0, n + "surface_share_period_s", "must be <= 60 s");
  p.getAtLeast(n + "colour_wait_s", c.colour_wait_s, 0.0, "s");
  p.getAtLeast(n + "start_free_radius_m", c.start_free_radius_m, 0.0, "m");
  p.get(n + "restore_map_service", c.restore_map_service);
  p.getAtLeast(n + "restore_wait_s", c.restore_wait_s, 0.0, "s");
  // ServiceCaller bounds the call by it: 0 would give up before asking.
  if (!c.restore_map_service.empty()) semexp::require(c.restore_wait_s > 0.0, n + "restore_wait_s", "must be > 0 s");
  return c;
}

semexp::ObjectMapConfig loadObjectMap(const ParamReader& p) {
  semexp::ObjectMapConfig c;
  const std::string n = "object_map/";
  p.get(n + "truncation_voxels", c.truncation_voxels);
  p.get(n + "max_weight", c.max_weight);
  p.get(n + "block_size", c.block_size);
  p.get(n + "publish_period_s", c.publish_period_s);
  p.get(n + "behind_surface_voxels", c.behind_surface_voxels);
  p.get(n + "behind_surface_quadratic_per_m", c.behind_surface_quadratic_per_m);
  p.get(n + "full_weight_depth_m", c.full_weight_depth_m);
  p.get(n + "render_depth_tolerance_m", c.render_depth_tolerance_m);
  p.get(n + "render_depth_tolerance_rel", c.render_depth_tolerance_rel);
  p.get(n + "merge_fraction", c.merge_fraction);
  p.get(n + "piece_max_share", c.piece_max_share);
  p.get(n + "piece_max_distance_m", c.piece_max_distance_m);
  p.get(n + "min_new_object_pixels", c.min_new_object_pixels);
  p.get(n + "mask_depth_edge_m", c.mask_depth_edge_m);
  p.get(n + "mask_depth_edge_rel", c.mask_depth_edge_rel);
  p.get(n + "mask_depth_edge_window_px", c.mask_depth_edge_window_px);
  p.get(n + "split_gap_m", c.split_gap_m);
  p.get(n + "foreground_border_px", c.foreground_border_px);
  p.get(n + "foreground_prior", c.foreground_prior);
  p.get(n + "foreground_prior_weight", c.foreground_prior_weight);
  p.get(n + "mesh_fragment_gap_m", c.mesh_fragment_gap_m);
  p.get(n + "mesh_min_weight", c.mesh_min_weight);
  p.get(n + "mesh_max_sdf_std_m", c.mesh_max_sdf_std_m);
  p.get(n + "mesh_min_foreground", c.mesh_min_foreground);
  p.get(n + "save_tsdf", c.save_tsdf);
  p.get(n + "depth_noise/sigma_min_m", c.depth_noise.sigma_min_m);
  p.get(n + "depth_noise/s_per_m", c.depth_noise.s_per_m);
  p.get(n + "depth_noise/sigma_max_m", c.depth_noise.sigma_max_m);
  c.validate(n);
  return c;
}

semexp::MatchingConfig loadMatching(const ParamReader& p) {
  semexp::MatchingConfig c;
  p.get("matching/iou_threshold", c.iou_threshold);
  p.get("matching/min_mask_pixels", c.min_mask_pixels);
  p.get("matching/fragment_fraction", c.fragment_fraction);
  c.validate("matching/");
  return c;
}

semexp::DepthHistoryConfig loadDepthHistory(const ParamReader& p) {
  semexp::DepthHistoryConfig c;
  p.get("depth_history/cell_size_m", c.cell_size_m);
  p.get("depth_history/width", c.width);
  p.get("depth_history/height", c.height);
  c.validate("depth_history/");
  return c;
}

DepthHistoryNodeConfig loadDepthHistoryNode(const ParamReader& p, const semexp::DepthHistoryConfig& history) {
  DepthHistoryNodeConfig c;
  p.getAtLeast("depth_history/marker_period_s", c.marker_period_s, 0.0, "s");
  // The planner asks get_masks for its raycast images, and get_masks answers only its own size: a mismatch would
  // fail every planning iteration, so it fails here (every node loads the whole YAML, planner section included).
  if (!p.has("planner")) return c;  // no planner configured alongside
  semexp::PlannerConfig planner;
  p.get("planner/raycast_width", planner.raycast_width);
  p.get("planner/raycast_height", planner.raycast_height);
  if (history.width != planner.raycast_width)
    throw ConfigError("depth_history/width", "is " + std::to_string(history.width) + " but planner/raycast_width is " +
                                                 std::to_string(planner.raycast_width) + "; they must be equal");
  if (history.height != planner.raycast_height)
    throw ConfigError("depth_history/height", "is " + std::to_string(history.height) +
                                                  " but planner/raycast_height is " +
                                                  std::to_string(planner.raycast_height) + "; they must be equal");
  return c;
}

semexp::FrontierEvidenceConfig loadFrontierEvidence(const ParamReader& p) {
  semexp::FrontierEvidenceConfig c;
  const std::string n = "frontier_evidence/";
  p.get(n + "enabled", c.enabled);
  p.get(n + "view_range_m", c.view_range_m);
  p.get(n + "looks_to_retire", c.looks_to_retire);
  p.get(n + "min_look_separation_m", c.min_look_separation_m);
  p.get(n + "min_look_rotation_rad", c.min_look_rotation_rad);
  p.get(n + "occlusion_margin_m", c.occlusion_margin_m);
  c.validate(n);
  return c;
}

semexp::DetectorConfig loadDetector(const ParamReader& p, const semexp::ClassTable& classes) {
  semexp::DetectorConfig c;
  const std::string n = "detector/";
  p.get(n + "model_path", c.model_path);
  std::vector<double> size = {static_cast<double>(c.input_size[0]), static_cast<double>(c.input_size[1])};
  p.get(n + "input_size", size);
  {
    if (size.size() != 2 || size[0] != std::floor(size[0]) || size[1] != std::floor(size[1]))
      throw ConfigError(n + "input_size", "must be [width, height] in whole px");
    c.input_size = {{static_cast<int>(size[0]), static_cast<int>(size[1])}};
  }
  p.get(n + "conf_threshold", c.conf_threshold);
  p.get(n + "nms_iou", c.nms_iou);
  p.get(n + "mask_threshold", c.mask_threshold);
  p.get(n + "model_classes", c.model_classes);
  p.getMap(n + "class_map", c.class_map, "model class name -> project class name");
  p.get(n + "backend", c.backend);
  p.get(n + "target", c.target);
  c.validate(n);
  for (const auto& kv : c.class_map)
    if (!classes.id(kv.second))
      throw ConfigError(n + "class_map", "maps '" + kv.first + "' to '" + kv.second + "', which is not in classes/names");
  return c;
}

double loadDisplayCut(const ParamReader& p) {
  double max_z_m = 2.0;
  p.get("display_cut/max_z_m", max_z_m);
  if (!std::isfinite(max_z_m)) throw ConfigError("display_cut/max_z_m", "must be a finite height, m");
  return max_z_m;
}

// ------------------------------------------------------------ planner

semexp::ExplorationConfig loadExploration(const ParamReader& p) {
  semexp::ExplorationConfig c;
  p.get("exploration/d_bg_m", c.d_bg_m);
  p.get("exploration/d_obj_m", c.d_obj_m);
  c.validate("exploration/");
  return c;
}

semexp::PlannerConfig loadPlanner(const ParamReader& p) {
  semexp::PlannerConfig c;
  const std::string n = "planner/";
  p.get(n + "n_candidates", c.n_candidates);
  p.get(n + "p_frontier", c.p_frontier);
  p.get(n + "a_ent", c.a_ent);
  p.get(n + "a_bg", c.a_bg);
  p.get(n + "a_obj", c.a_obj);
  p.get(n + "v_max_mps", c.v_max_mps);
  p.get(n + "omega_max_radps", c.omega_max_radps);
  p.get(n + "mav_radius_m", c.mav_radius_m);
  p.get(n + "clearance_margin_m", c.clearance_margin_m);
  p.get(n + "raycast_width", c.raycast_width);
  p.get(n + "raycast_height", c.raycast_height);
  p.get(n + "time_budget_s", c.time_budget_s);
  p.get(n + "time_limit_s", c.time_limit_s);
  p.get(n + "max_failed_iterations", c.max_failed_iterations);
  p.get(n + "object_observed_fraction", c.object_observed_fraction);
  p.get(n + "object_standoff_factor", c.object_standoff_factor);
  p.get(n + "object_view_samples", c.object_view_samples);
  p.get(n + "min_path_time_s", c.min_path_time_s);
  p.get(n + "cost_threshold_factor", c.cost_threshold_factor);
  p.get(n + "simplify_time_s", c.simplify_time_s);
  p.get(n + "convergence_solutions", c.convergence_solutions);
  p.get(n + "convergence_epsilon", c.convergence_epsilon);
  p.get(n + "planning_threads", c.planning_threads);
  p.get(n + "stall_iterations", c.stall_iterations);
  p.get(n + "stall_volume_m3", c.stall_volume_m3);
  p.get(n + "ompl_termination", c.ompl_termination);
  p.get(n + "ompl_iterations", c.ompl_iterations);
  p.get(n + "lazy_planning", c.lazy_planning);
  p.get(n + "room_search_radius_m", c.room_search_radius_m);
  int seed = static_cast<int>(c.seed);
  p.get(n + "seed", seed);
  if (seed < 0) throw ConfigError(n + "seed", "must be >= 0");
  c.seed = static_cast<std::uint32_t>(seed);
  c.validate(n);
  return c;
}

PlannerNodeConfig loadPlannerNode(const ParamReader& p) {
  PlannerNodeConfig c;
  p.getPositiveAtMost("planner/service_timeout_s", c.service_timeout_s, 3600, "s");
  p.getPositiveAtMost("planner/retry_period_s", c.retry_period_s, 3600, "s");
  p.getAtLeast("planner/goal_timeout_factor", c.goal_timeout_factor, 1.0, "(a factor)");
  return c;
}

semexp::TrajectoryConfig loadTrajectory(const ParamReader& p) {
  semexp::TrajectoryConfig c;
  p.get("planner/a_max_mps2", c.a_max_mps2);
  p.get("planner/alpha_max_radps2", c.alpha_max_radps2);
  p.get("planner/trajectory_sample_period_s", c.trajectory_sample_period_s);
  c.validate("planner/");
  return c;
}

semexp::TerminationConfig loadTermination(const ParamReader& p) {
  semexp::TerminationConfig c;
  const std::string n = "termination/";
  p.get(n + "max_active_frontiers", c.max_active_frontiers);
  p.get(n + "background_observed_share", c.background_observed_share);
  p.get(n + "stall_share", c.stall_share);
  c.validate(n);
  return c;
}

semexp::FrontierRetirementConfig loadFrontierRetirement(const ParamReader& p) {
  semexp::FrontierRetirementConfig c;
  const std::string n = "frontier_retirement/";
  p.get(n + "enabled", c.enabled);
  p.get(n + "cluster_size_m", c.cluster_size_m);
  p.get(n + "max_failed_views", c.max_failed_views);
  p.get(n + "shrink_fraction", c.shrink_fraction);
  p.get(n + "view_range_m", c.view_range_m);
  p.get(n + "min_view_distance_m", c.min_view_distance_m);
  p.get(n + "fov_margin_rad", c.fov_margin_rad);
  p.get(n + "recheck_iterations", c.recheck_iterations);
  p.get(n + "max_evidence_returns", c.max_evidence_returns);
  c.validate(n);
  return c;
}

semexp::ObjectRetirementConfig loadObjectRetirement(const ParamReader& p) {
  semexp::ObjectRetirementConfig c;
  const std::string n = "object_retirement/";
  p.get(n + "enabled", c.enabled);
  p.get(n + "max_failed_views", c.max_failed_views);
  p.get(n + "min_share_change", c.min_share_change);
  c.validate(n);
  return c;
}

SetpointStreamerConfig loadSetpointStreamer(const ParamReader& p) {
  SetpointStreamerConfig c;
  const std::string n = "setpoint_streamer/";
  p.getPositiveAtMost(n + "rate_hz", c.rate_hz, 1000, "Hz");
  p.getPositiveAtMost(n + "pose_timeout_s", c.pose_timeout_s, 3600, "s");
  p.getPositiveAtMost(n + "max_start_offset_m", c.max_start_offset_m, 1000, "m");
  p.getPositiveAtMost(n + "goal_tolerance_m", c.goal_tolerance_m, 1000, "m");
  p.getPositiveAtMost(n + "goal_yaw_tolerance_rad", c.goal_yaw_tolerance_rad, 4, "rad");
  return c;
}

std::vector<std::pair<std::string, std::function<void(const ParamReader&)>>> allLoaders() {
  return {
      {"loadCamera", [](const ParamReader& p) { loadCamera(p); }},
      {"loadBounds", [](const ParamReader& p) { loadBounds(p); }},
      {"loadClasses", [](const ParamReader& p) { loadClasses(p); }},
      {"loadExploration", [](const ParamReader& p) { loadExploration(p); }},
      {"loadBackgroundMap", [](const ParamReader& p) { loadBackgroundMap(p); }},
      {"loadObjectMap", [](const ParamReader& p) { loadObjectMap(p); }},
      {"loadMatching", [](const ParamReader& p) { loadMatching(p); }},
      {"loadDepthHistory", [](const ParamReader& p) { loadDepthHistory(p); }},
      {"loadPlanner", [](const ParamReader& p) { loadPlanner(p); }},
      {"loadDetector", [](const ParamReader& p) { loadDetector(p, semexp::ClassTable()); }},
      {"loadFrames", [](const ParamReader& p) { loadFrames(p); }},
      {"loadTf", [](const ParamReader& p) { loadTf(p); }},
      {"loadPlannerNode", [](const ParamReader& p) { loadPlannerNode(p); }},
      {"loadTermination", [](const ParamReader& p) { loadTermination(p); }},
      {"loadFrontierRetirement", [](const ParamReader& p) { loadFrontierRetirement(p); }},
      {"loadObjectRetirement", [](const ParamReader& p) { loadObjectRetirement(p); }},
      {"loadBackgroundMapNode", [](const ParamReader& p) { loadBackgroundMapNode(p); }},
      {"loadDepthHistoryNode",
       [](const ParamReader& p) { loadDepthHistoryNode(p, semexp::DepthHistoryConfig()); }},
      {"loadImageSync", [](const ParamReader& p) { loadImageSync(p); }},
      {"loadFrontierEvidence", [](const ParamReader& p) { loadFrontierEvidence(p); }},
      {"loadTrajectory", [](const ParamReader& p) { loadTrajectory(p); }},
      {"loadSetpointStreamer", [](const ParamReader& p) { loadSetpointStreamer(p); }},
      {"loadDisplayCut", [](const ParamReader& p) { loadDisplayCut(p); }},
  };
}

}  // namespace semexp_ros

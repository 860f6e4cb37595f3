#include "semantic_exploration/core/planning/exploration_planner.hpp"

#include <chrono>
#include <cstdio>
#include <stdexcept>

namespace semexp {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::string fmt(const char* f, double a, double b = 0.0, double c = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), f, a, b, c);
  return buf;
}

}  // namespace

ExplorationPlanner::ExplorationPlanner(const PlannerConfig& planner, const ExplorationConfig& exploration,
                                       const Bounds& bounds, const PinholeCamera& camera, double map_resolution_m)
    : planner_(planner),
      exploration_(exploration),
      bounds_(bounds),
      camera_(camera),
      map_resolution_m_(map_resolution_m),
      sampler_(planner, exploration, bounds),
      window_columns_(semexp::window_columns(camera.hfov_rad(), planner.raycast_width)) {
  camera_.validate();
  if (!(std::isfinite(map_resolution_m_) && map_resolution_m_ > 0))
    throw std::invalid_argument("ExplorationPlanner: map_resolution_m must be > 0");
}

bool ExplorationPlanner::fail(IterationResult& r, const std::string& why) {
  ++failed_iterations_;
  r.message = why + " (" + std::to_string(failed_iterations_) + " of " +
              std::to_string(planner_.max_failed_iterations) + " iterations without a reachable candidate)";
  if (failed_iterations_ >= planner_.max_failed_iterations) {
    r.finished = true;
    r.termination_reason = "no_reachable_candidate";
  }
  return false;
}

IterationResult ExplorationPlanner::plan(const ExplorationInputs& in, const ExplorationProviders& prov) {
  const auto t_start = Clock::now();
  IterationResult r;
  auto finish = [&]() -> IterationResult& {
    r.total_s = seconds_since(t_start);
    return r;
  };

  // Termination (DESIGN Section 5 step 6).
  if (planner_.time_limit_s > 0 && in.elapsed_s >= planner_.time_limit_s) {
    r.finished = true;
    r.termination_reason = "time_limit";
    r.message = fmt("time limit of %.0f s reached", planner_.time_limit_s);
    return finish();
  }
  bool objects_done = true;
  for (const auto& o : in.objects) objects_done = objects_done && !sampler_.needs_observation(o);
  if (in.frontiers_W.empty() && objects_done && in.background_observed) {
    r.finished = true;
    r.termination_reason = "explored";
    r.message = "no frontier left and all objects observed from <= d_obj";
    return finish();
  }
  if (in.explored_volume_m3 >= 0 && planner_.stall_iterations > 0) {
    explored_volumes_m3_.push_back(in.explored_volume_m3);
    const std::size_t k = static_cast<std::size_t>(planner_.stall_iterations);
    if (explored_volumes_m3_.size() > k) {
      const double grown = explored_volumes_m3_.back() - explored_volumes_m3_[explored_volumes_m3_.size() - 1 - k];
      if (grown < planner_.stall_volume_m3) {
        r.finished = true;
        r.termination_reason = "no_progress";
        r.message = fmt("explored volume grew %.3f m^3 (< %.3f) over the last %.0f iterations", grown,
                        planner_.stall_volume_m3, static_cast<double>(k));
        return finish();
      }
    }
  }
  if (!prov.is_free || !prov.gains) throw std::invalid_argument("ExplorationPlanner: is_free and gains are required");

  // 1. Sampling.
  auto t0 = Clock::now();
  const std::vector<CandidateSample> samples = sampler_.sample(in.frontiers_W, in.objects, prov.is_free);
  r.sampling_s = seconds_since(t0);
  if (samples.empty()) {
    fail(r, "nothing to sample (no frontiers and no object left to observe)");
    return finish();
  }

  // 2. Paths, in parallel.
  t0 = Clock::now();
  const PathPlanner paths(planner_, bounds_, map_resolution_m_, prov.is_free, prov.not_occupied);
  std::vector<Eigen::Vector3d> goals;
  for (const auto& s : samples) goals.push_back(s.position_W);
  std::vector<PlannedPath> planned = paths.plan_all(in.position_W, goals);
  r.path_planning_s = seconds_since(t0);

  r.candidates.resize(samples.size());
  std::vector<Eigen::Vector3d> view_positions;
  std::vector<std::size_t> reachable_idx;
  bool start_invalid = false;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    EvaluatedCandidate& c = r.candidates[i];
    c.sample = samples[i];
    c.plan = std::move(planned[i]);
    c.reachable = c.plan.ok();
    c.position_W = c.reachable ? c.plan.path_W.back() : c.sample.position_W;
    start_invalid = start_invalid || c.plan.status == PlannedPath::Status::kStartInvalid;
    if (c.reachable) {
      reachable_idx.push_back(i);
      view_positions.push_back(c.position_W);
    }
  }
  r.candidates_reachable = static_cast<int>(reachable_idx.size());
  if (reachable_idx.empty()) {
    fail(r, start_invalid ? "the current position is not in free space and no escape was found"
                          : "no candidate reachable");
    return finish();
  }

  // 3-5. Gains (one batched call each), Eq. 2, sliding window, utility.
  t0 = Clock::now();
  std::vector<GainSet> gains;
  std::vector<std::vector<std::uint8_t>> masks;
  try {
    gains = prov.gains(view_positions);
    if (prov.history) masks = prov.history(view_positions);
    if (gains.size() != view_positions.size())
      throw std::runtime_error("gain provider returned " + std::to_string(gains.size()) + " results for " +
                               std::to_string(view_positions.size()) + " positions");
    if (!masks.empty() && masks.size() != view_positions.size())
      throw std::runtime_error("history provider returned a wrong number of masks");
  } catch (const std::exception& e) {
    r.provider_error = true;
    r.message = std::string("gain evaluation failed: ") + e.what();
    r.gains_s = seconds_since(t0);
    return finish();
  }
  const GainWeights weights{planner_.a_ent, planner_.a_bg, planner_.a_obj};
  const int w = planner_.raycast_width, h = planner_.raycast_height;
  std::vector<GainImage> combined(reachable_idx.size());
  double best_utility = 0.0;
  try {
    for (std::size_t k = 0; k < reachable_idx.size(); ++k) {
      EvaluatedCandidate& c = r.candidates[reachable_idx[k]];
      combined[k] = combine_gains(weights, gains[k], masks.empty() ? std::vector<std::uint8_t>{} : masks[k], w, h);
      const YawWindow win = best_yaw(combined[k], window_columns_);
      c.yaw_rad = win.yaw_rad;
      c.gain = win.gain;
      c.gain_entropy = window_mean(gains[k].entropy, win.first_column, win.columns);
      c.gain_bg = window_mean(gains[k].background, win.first_column, win.columns);
      c.gain_obj = window_mean(gains[k].object, win.first_column, win.columns);
      c.path_time_s = path_time_s(c.plan.path_W, in.yaw_rad, c.yaw_rad, planner_.v_max_mps, planner_.omega_max_radps);
      c.utility = utility(c.gain, c.path_time_s, planner_.min_path_time_s);
      if (c.utility > best_utility) {
        best_utility = c.utility;
        r.winner = static_cast<int>(reachable_idx[k]);
        r.winner_gains = gains[k];
        r.winner_combined = combined[k];
      }
    }
  } catch (const std::exception& e) {
    r.provider_error = true;
    r.winner = -1;
    r.message = std::string("bad gain images: ") + e.what();
    r.gains_s = seconds_since(t0);
    return finish();
  }
  r.gains_s = seconds_since(t0);
  if (r.winner < 0) {
    fail(r, std::to_string(reachable_idx.size()) + " candidates reachable, none with a positive gain");
    return finish();
  }

  // Yaw of the winner's path vertices: first keeps the current yaw, last the
  // candidate's, intermediate ones their own best yaw (one batched call).
  t0 = Clock::now();
  const EvaluatedCandidate& win = r.candidates[static_cast<std::size_t>(r.winner)];
  r.path_W = win.plan.path_W;
  r.path_yaw_rad.assign(r.path_W.size(), win.yaw_rad);
  r.path_yaw_rad.front() = in.yaw_rad;
  if (r.path_W.size() > 2) {
    const std::vector<Eigen::Vector3d> mid(r.path_W.begin() + 1, r.path_W.end() - 1);
    try {
      const auto mid_gains = prov.gains(mid);
      const auto mid_masks = prov.history ? prov.history(mid) : std::vector<std::vector<std::uint8_t>>{};
      for (std::size_t k = 0; k < mid.size() && k < mid_gains.size(); ++k) {
        const GainImage g =
            combine_gains(weights, mid_gains[k], k < mid_masks.size() ? mid_masks[k] : std::vector<std::uint8_t>{}, w, h);
        const YawWindow yw = best_yaw(g, window_columns_);
        // A vertex with nothing to see keeps turning towards the final yaw.
        r.path_yaw_rad[k + 1] = yw.gain > 0 ? yw.yaw_rad : win.yaw_rad;
      }
    } catch (const std::exception& e) {
      // The path itself is fine; intermediate vertices keep the final yaw.
      r.message = std::string("intermediate yaw evaluation failed: ") + e.what() + "; ";
    }
  }
  r.yaw_s = seconds_since(t0);

  failed_iterations_ = 0;
  r.message += fmt("winner %.0f: utility %.3f 1/s, gain %.3f", r.winner, win.utility, win.gain) +
               fmt(", path %.2f m ", path_length_m(r.path_W)) + PlannedPath::name(win.plan.status) +
               fmt("; %.0f of %.0f candidates reachable", r.candidates_reachable,
                   static_cast<double>(r.candidates.size()));
  return finish();
}

}  // namespace semexp

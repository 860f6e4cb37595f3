#include "semantic_exploration/core/planning/exploration_planner.hpp"
#include "semantic_exploration/core/planning/room_search.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace semexp {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::string fmt(const char* f, double a, double b = 0.0, double c = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), f, a, b, c);
  return buf;
}

/// One view position's gain images, G (Eq. 2) and best yaw window.
struct ViewGains {
  GainSet gains;
  GainImage combined;
  YawWindow window;
};

/// Gains at `ps` (one batched call to each provider), combined and windowed.
/// On a provider failure or bad images: reports it in r, returns false.
bool evaluateViews(const std::vector<Eigen::Vector3d>& ps, const ExplorationProviders& prov,
                    const PlannerConfig& cfg, int window_columns, std::vector<ViewGains>& out, IterationResult& r) {
  std::vector<GainSet> gains;
  std::vector<std::vector<std::uint8_t>> masks;
  try {
    gains = prov.gains(ps);
    if (prov.history) masks = prov.history(ps);
    if (gains.size() != ps.size())
      throw std::runtime_error("gain provider returned " + std::to_string(gains.size()) + " results for " +
                               std::to_string(ps.size()) + " positions");
    if (!masks.empty() && masks.size() != ps.size())
      throw std::runtime_error("history provider returned a wrong number of masks");
  } catch (const std::exception& e) {
    r.provider_error = true;
    r.message += std::string("gain evaluation failed: ") + e.what();
    return false;
  }
  const GainWeights weights{cfg.a_ent, cfg.a_bg, cfg.a_obj};
  out.assign(ps.size(), ViewGains());
  try {
    for (std::size_t k = 0; k < ps.size(); ++k) {
      out[k].combined = combineGains(weights, gains[k], masks.empty() ? std::vector<std::uint8_t>{} : masks[k],
                                      cfg.raycast_width, cfg.raycast_height);
      out[k].window = bestYaw(out[k].combined, window_columns);
      out[k].gains = std::move(gains[k]);
    }
  } catch (const std::exception& e) {
    r.provider_error = true;
    r.message += std::string("bad gain images: ") + e.what();
    return false;
  }
  return true;
}

void setGains(EvaluatedCandidate& c, const ViewGains& g) {
  const YawWindow& w = g.window;
  c.yaw_rad = w.yaw_rad;
  c.gain = w.gain;
  c.gain_entropy = windowMean(g.gains.entropy, w.first_column, w.columns);
  c.gain_bg = windowMean(g.gains.background, w.first_column, w.columns);
  c.gain_obj = windowMean(g.gains.object, w.first_column, w.columns);
}

}  // namespace

ExplorationPlanner::ExplorationPlanner(const PlannerConfig& planner, const ExplorationConfig& exploration,
                                       const Bounds& bounds, const PinholeCamera& camera, double map_resolution_m,
                                       const TerminationConfig& termination,
                                       const FrontierRetirementConfig& retirement,
                                       const ObjectRetirementConfig& object_retirement)
    : planner_(planner),
      exploration_(exploration),
      bounds_(bounds),
      camera_(camera),
      map_resolution_m_(map_resolution_m),
      sampler_(planner, exploration, bounds),
      window_columns_(semexp::windowColumns(camera.hfov_rad(), planner.raycast_width)),
      termination_(termination, planner),
      retirement_(retirement, camera, bounds, planner.clearance_radius_m(), map_resolution_m),
      object_retirement_(object_retirement, planner.object_observed_fraction) {
  camera_.validate();
  if (!(std::isfinite(map_resolution_m_) && map_resolution_m_ > 0))
    throw std::invalid_argument("ExplorationPlanner: map_resolution_m must be > 0");
}

bool ExplorationPlanner::chooseObjectViews(std::vector<CandidateSample>& samples,
                                           const std::vector<ObjectSummary>& objects,
                                           const ExplorationProviders& prov, IterationResult& r) {
  const auto t0 = Clock::now();
  std::vector<Eigen::Vector3d> views;
  std::vector<std::pair<std::size_t, std::size_t>> range(samples.size(), {0, 0});  // per sample: [first, last)
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (samples[i].source != CandidateSource::kObject) continue;
    const auto o = std::find_if(objects.begin(), objects.end(),
                                [&](const ObjectSummary& x) { return x.id == samples[i].object_id; });
    if (o == objects.end()) continue;
    const std::vector<Eigen::Vector3d> ring = sampler_.objectViewRing(*o, prov.is_free);
    range[i] = {views.size(), views.size() + ring.size()};
    views.insert(views.end(), ring.begin(), ring.end());
  }
  bool ok = true;
  if (!views.empty()) {
    std::vector<ViewGains> g;
    ok = evaluateViews(views, prov, planner_, window_columns_, g, r);
    for (std::size_t i = 0; ok && i < samples.size(); ++i) {
      // The object gain this view's yaw window takes in first, then G; ties keep the first; a ring with no positive
      // gain leaves the sample where it was drawn.
      std::pair<double, double> best{0.0, 0.0};
      for (std::size_t k = range[i].first; k < range[i].second; ++k) {
        const YawWindow& w = g[k].window;
        const std::pair<double, double> key{windowMean(g[k].gains.object, w.first_column, w.columns), w.gain};
        if (key > best) {
          best = key;
          samples[i].position_W = views[k];
        }
      }
    }
  }
  r.object_views = views.size();
  r.gains_s += secondsSince(t0);
  return ok;
}

void ExplorationPlanner::recordUnseeableFrontiers(IterationResult& r, const CollisionQuery& not_occupied,
                                                  const LineQuery& line) {
  // No view the sampler drew has anything to see: by the gains the planner
  // decides with, each frontier candidate's cluster was looked at and nothing
  // came of it. Counted as a view of the cluster (no path was flown, so no
  // pose sees anything else), K of them retire it by evidence: otherwise a
  // cluster whose views all lie in the invalid depth history's mask (for
  // example at a window) or that slips between the raycasts ends the mission
  // no_reachable_candidate with that cluster still open. Lazy and exhaustive
  // planning decide this alike: any_gain is judged at the view positions.
  std::vector<Eigen::Vector3d> targets;
  for (const EvaluatedCandidate& c : r.candidates)
    if (c.sample.source == CandidateSource::kFrontier) targets.push_back(c.sample.position_W);
  if (targets.empty()) return;
  retirement_.recordViews({}, not_occupied, targets, line);
  r.message += fmt("; %.0f frontier candidates with nothing to see: a view of their clusters for retirement",
                   static_cast<double>(targets.size()));
}

bool ExplorationPlanner::fail(IterationResult& r, const std::string& why) {
  ++failed_iterations_;
  r.message += why + " (" + std::to_string(failed_iterations_) + " of " +
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
    r.total_s = secondsSince(t_start);
    return r;
  };

  if (!prov.is_free || !prov.gains) throw std::invalid_argument("ExplorationPlanner: is_free and gains are required");
  // Without an occupancy query every line of sight counts as clear.
  const CollisionQuery not_occupied =
      prov.not_occupied ? prov.not_occupied : CollisionQuery([](const Eigen::Vector3d&, double) { return true; });
  const LineQuery line_not_occupied = prov.not_occupied ? prov.line_not_occupied : LineQuery();

  // Frontiers no reachable view can observe do not hold the exploration open.
  auto t0 = Clock::now();
  FrontierRetirement::Split split = retirement_.update(in.frontiers_W, not_occupied, line_not_occupied);
  r.retirement_s = secondsSince(t0);
  r.active_frontiers = split.active_W.size();
  r.retired_frontiers_W = std::move(split.retired_W);
  r.frontier_clusters = split.clusters;
  r.retired_clusters_geometry = split.retired_by_geometry;
  r.retired_clusters_evidence = split.retired_by_evidence;
  // Objects the last flights aimed at without moving their share (object_retirement.hpp).
  for (const ObjectRetirementChange& c : object_retirement_.update(in.objects)) {
    if (c.retired)
      r.object_retirement_events += fmt("object %.0f retired: %.0f flights aimed at it left its share seen from <= d_obj at %.3f; ",
                                        c.id, object_retirement_.config().max_failed_views, c.share);
    else
      r.object_retirement_events += fmt("object %.0f back: its share seen from <= d_obj moved to %.3f; ", c.id, c.share);
  }
  r.retired_object_ids = object_retirement_.retiredIds();
  r.message = r.object_retirement_events;
  const std::vector<ObjectSummary> active_objects = object_retirement_.active(in.objects);

  // Termination (termination.hpp).
  TerminationInputs ti;
  ti.elapsed_s = in.elapsed_s;
  ti.active_frontiers = split.active_W.size();
  ti.background_share = in.background_observed_share;
  ti.objects = in.objects;
  ti.retired_object_ids = r.retired_object_ids;
  ti.explored_volume_m3 = in.explored_volume_m3;
  ti.frontier_clusters_retired = retirement_.evidenceRetirements();
  r.termination = termination_.check(ti);
  if (r.termination.finished) {
    r.finished = true;
    r.termination_reason = r.termination.reason;
    r.message += r.termination.message;
    return finish();
  }

  // 1. Sampling.
  t0 = Clock::now();
  const std::uint64_t iteration = sampling_iterations_++;
  std::vector<CandidateSample> samples = sampler_.sample(split.active_W, active_objects, prov.is_free);
  // Frontiers and objects done but background seen from too far: the paper
  // samples nothing else, so view points in known free space, chosen by
  // their background gain like any other candidate, close the gap.
  if (samples.empty() && !r.termination.background_done) samples = sampler_.sampleFreeSpace(prov.is_free);
  r.sampling_s = secondsSince(t0);
  if (planner_.object_view_samples > 1 && !chooseObjectViews(samples, in.objects, prov, r)) return finish();
  if (samples.empty()) {
    fail(r, "nothing to sample (no active frontiers, no object left to observe, no free view point)");
    return finish();
  }
  const std::size_t n = samples.size();
  r.candidates.resize(n);
  for (std::size_t i = 0; i < n; ++i) r.candidates[i].sample = samples[i];

  // 2. View positions: where each path ends if it reaches its goal (a
  // frontier goal moves to free space next to it), known before planning.
  t0 = Clock::now();
  const PathPlanner paths(planner_, bounds_, map_resolution_m_, prov.is_free, prov.not_occupied);
  const PlanningStart from = paths.planningStart(in.position_W);
  if (!from.ok) {
    for (EvaluatedCandidate& c : r.candidates) {
      c.position_W = c.sample.position_W;
      c.plan.status = PlannedPath::Status::kStartInvalid;
    }
    r.path_planning_s = secondsSince(t0);
    fail(r, "the current position is not in free space and no escape was found");
    return finish();
  }
  std::vector<Eigen::Vector3d> views;
  for (const CandidateSample& s : samples) views.push_back(s.position_W);
  const std::vector<ResolvedGoal> goals = paths.resolveGoals(from, views);
  for (std::size_t i = 0; i < n; ++i) {
    views[i] = goals[i].goal_W;
    r.candidates[i].position_W = r.candidates[i].view_W = views[i];
  }
  r.path_planning_s = secondsSince(t0);

  // 3. Gains at the view positions (one batched call), Eq. 2, sliding
  // window, and each candidate's utility bound.
  t0 = Clock::now();
  std::vector<ViewGains> view_gains;
  const bool gains_ok = evaluateViews(views, prov, planner_, window_columns_, view_gains, r);
  r.gains_s += secondsSince(t0);
  if (!gains_ok) return finish();
  for (std::size_t i = 0; i < n; ++i) {
    EvaluatedCandidate& c = r.candidates[i];
    setGains(c, view_gains[i]);
    // No path is shorter than the straight line, and path_time_s of the
    // straight path {start, view} is exactly this time.
    const double t_min_s = std::max((views[i] - in.position_W).norm() / planner_.v_max_mps,
                                    yawDifference_rad(in.yaw_rad, c.yaw_rad) / planner_.omega_max_radps);
    c.utility_bound = utility(c.gain, t_min_s, planner_.min_path_time_s);
  }

  // 4. Paths, best bound first. Exhaustive: all at once. Lazy: a batch of
  // `threads` at a time, until no unplanned candidate can beat the best:
  // utilities never exceed their bounds, and ties go to the lower index, as
  // in the exhaustive scan.
  const bool lazy = planner_.lazy_planning;
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < n; ++i)
    if (!lazy || r.candidates[i].gain > 0) order.push_back(i);
  std::sort(order.begin(), order.end(), [&r](std::size_t a, std::size_t b) {
    const double ua = r.candidates[a].utility_bound, ub = r.candidates[b].utility_bound;
    return ua > ub || (ua == ub && a < b);
  });
  const auto beats = [&r](std::size_t a, double utility_a, std::size_t b) {
    const double ub = r.candidates[b].utility;
    return utility_a > ub || (utility_a == ub && a < b);
  };
  const std::size_t batch = lazy ? static_cast<std::size_t>(paths.threads()) : std::max<std::size_t>(1, n);
  std::vector<ViewGains> end_gains(n);  // for paths that end away from their view position
  constexpr int kProviderFailed = -2;  // planPaths: a gain provider failed (reported in r)
  const auto planPaths = [&](const PlanningStart& start) -> int {
    for (EvaluatedCandidate& c : r.candidates) {  // a second pass starts afresh
      if (!c.planned) continue;
      c.plan = PlannedPath();
      c.planned = c.reachable = false;
      c.path_time_s = c.utility = 0.0;
    }
    for (std::size_t i = 0; i < n; ++i)
      if (r.candidates[i].position_W != views[i]) {
        r.candidates[i].position_W = views[i];
        setGains(r.candidates[i], view_gains[i]);
      }
    r.candidates_planned = r.candidates_reachable = 0;
    int best = -1;
    for (std::size_t k = 0; k < order.size();) {
      if (lazy && best >= 0 && !beats(order[k], r.candidates[order[k]].utility_bound, static_cast<std::size_t>(best)))
        break;
      const std::vector<std::size_t> ids(order.begin() + static_cast<std::ptrdiff_t>(k),
                                         order.begin() + static_cast<std::ptrdiff_t>(std::min(order.size(), k + batch)));
      k += ids.size();
      t0 = Clock::now();
      std::vector<ResolvedGoal> batch_goals;
      std::vector<std::uint32_t> seeds;
      for (std::size_t i : ids) {
        batch_goals.push_back(goals[i]);
        seeds.push_back(pathSeed(planner_.seed, iteration, i));
      }
      std::vector<PlannedPath> planned = paths.planAll(start, batch_goals, seeds);
      r.path_planning_s += secondsSince(t0);
      std::vector<std::size_t> moved;
      std::vector<Eigen::Vector3d> ends;
      for (std::size_t j = 0; j < ids.size(); ++j) {
        EvaluatedCandidate& c = r.candidates[ids[j]];
        c.plan = std::move(planned[j]);
        c.planned = true;
        c.reachable = c.plan.ok();
        ++r.candidates_planned;
        r.candidates_reachable += c.reachable ? 1 : 0;
        if (c.reachable && c.plan.path_W.back() != views[ids[j]]) {
          // Approximate: the view is taken where the path ends.
          moved.push_back(ids[j]);
          ends.push_back(c.plan.path_W.back());
        }
      }
      if (!moved.empty()) {
        t0 = Clock::now();
        std::vector<ViewGains> g;
        const bool ok = evaluateViews(ends, prov, planner_, window_columns_, g, r);
        r.gains_s += secondsSince(t0);
        if (!ok) return kProviderFailed;
        for (std::size_t j = 0; j < moved.size(); ++j) {
          end_gains[moved[j]] = std::move(g[j]);
          r.candidates[moved[j]].position_W = ends[j];
          setGains(r.candidates[moved[j]], end_gains[moved[j]]);
        }
      }
      for (std::size_t i : ids) {
        EvaluatedCandidate& c = r.candidates[i];
        if (!c.reachable) continue;
        c.path_time_s = pathTime_s(c.plan.path_W, in.yaw_rad, c.yaw_rad, planner_.v_max_mps, planner_.omega_max_radps);
        // Capped at the bound: equal to the uncapped value whenever the path
        // reaches its view (up to rounding); an approximate path is never
        // worth more than reaching its view could have been.
        c.utility = std::min(utility(c.gain, c.path_time_s, planner_.min_path_time_s), c.utility_bound);
        if (c.utility > 0 && (best < 0 || beats(i, c.utility, static_cast<std::size_t>(best))))
          best = static_cast<int>(i);
      }
    }
    return best;
  };
  // At the view positions, before any path moved a candidate's view: the same in both modes.
  const bool any_gain = std::any_of(r.candidates.begin(), r.candidates.end(),
                                    [](const EvaluatedCandidate& c) { return c.gain > 0; });
  r.winner = planPaths(from);
  // No winner from a cramped start, though some candidate has a gain: perhaps
  // a pocket whose way out RRT* does not sample (room_search.hpp). Before the
  // iteration counts as failed, plan again from the nearest point with room.
  // An iteration with a winner is left as the paper plans it.
  // Decided on what lazy and exhaustive planning share (the winner and the
  // gains), not on the candidates each mode planned. A start that needed an
  // escape is not searched: the escape has just moved it.
  RoomSearchSettings room;
  room.room_radius_m = 2.0 * planner_.clearance_radius_m();
  room.search_radius_m = planner_.room_search_radius_m;
  room.step_m = 2.0 * map_resolution_m_;
  if (r.winner == -1 && room.search_radius_m > 0 && any_gain && !from.escaped &&
      !prov.is_free(from.from_W, room.room_radius_m)) {
    t0 = Clock::now();
    const std::vector<Eigen::Vector3d> route = findRoom(paths, prov.is_free, from.from_W, room);
    r.path_planning_s += secondsSince(t0);
    if (!route.empty()) {
      r.way_out = fmt("no winner from (%.2f, %.2f, %.2f), which has no room; ", from.from_W.x(), from.from_W.y(),
                      from.from_W.z()) +
                  fmt("planned again from (%.2f, %.2f, %.2f), ", route.back().x(), route.back().y(), route.back().z()) +
                  fmt("the nearest point with room, %.2f m along a way out of %.0f segments", pathLength_m(route),
                      static_cast<double>(route.size() - 1));
      r.winner = planPaths(startAfterRoute(route));
      if (r.winner == -1) r.way_out += ": no winner from there either";
      r.way_out += "; ";
      r.message += r.way_out;
    }
  }
  if (r.winner == kProviderFailed) {
    r.winner = -1;
    return finish();
  }

  // 5. The winner.
  if (r.winner < 0) {
    if (r.candidates_planned == 0)
      fail(r, "none of " + std::to_string(n) + " candidates has a positive gain at its view position");
    else if (r.candidates_reachable == 0)
      fail(r, "no candidate reachable");
    else
      fail(r, std::to_string(r.candidates_reachable) + " candidates reachable, none with a positive gain");
    if (!any_gain) recordUnseeableFrontiers(r, not_occupied, line_not_occupied);
    return finish();
  }
  const std::size_t wi = static_cast<std::size_t>(r.winner);
  const ViewGains& wg = r.candidates[wi].position_W == views[wi] ? view_gains[wi] : end_gains[wi];
  r.winner_gains = wg.gains;
  r.winner_combined = wg.combined;
  const GainWeights weights{planner_.a_ent, planner_.a_bg, planner_.a_obj};
  const int w = planner_.raycast_width, h = planner_.raycast_height;

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
            combineGains(weights, mid_gains[k], k < mid_masks.size() ? mid_masks[k] : std::vector<std::uint8_t>{}, w, h);
        const YawWindow yw = bestYaw(g, window_columns_);
        // A vertex with nothing to see keeps turning towards the final yaw.
        r.path_yaw_rad[k + 1] = yw.gain > 0 ? yw.yaw_rad : win.yaw_rad;
      }
    } catch (const std::exception& e) {
      // The path itself is fine; intermediate vertices keep the final yaw.
      r.message += std::string("intermediate yaw evaluation failed: ") + e.what() + "; ";
    }
  }
  r.yaw_s = secondsSince(t0);

  // The camera looks along the whole path, turning from each vertex's yaw to
  // the next: poses every 0.5 m are evidence for frontier retirement.
  std::vector<ViewPose> poses;
  for (std::size_t i = 1; i < r.path_W.size(); ++i) {
    const Eigen::Vector3d d = r.path_W[i] - r.path_W[i - 1];
    const int steps = std::max(1, static_cast<int>(std::ceil(d.norm() / 0.5)));
    const double dyaw = std::remainder(r.path_yaw_rad[i] - r.path_yaw_rad[i - 1], 2.0 * M_PI);
    for (int k = 1; k <= steps; ++k) {
      const double f = static_cast<double>(k) / steps;
      poses.push_back({r.path_W[i - 1] + f * d, r.path_yaw_rad[i - 1] + f * dyaw});
    }
  }
  std::vector<Eigen::Vector3d> targets;
  if (win.sample.source == CandidateSource::kFrontier) targets.push_back(win.sample.position_W);
  t0 = Clock::now();
  retirement_.recordViews(poses, not_occupied, targets, line_not_occupied);
  r.retirement_s += secondsSince(t0);
  if (win.sample.source == CandidateSource::kObject)
    for (const ObjectSummary& o : in.objects)
      if (o.id == win.sample.object_id) object_retirement_.recordView(o.id, o.observed_fraction);

  failed_iterations_ = 0;
  const std::string source = win.sample.source == CandidateSource::kObject
                                 ? "object " + std::to_string(win.sample.object_id)
                                 : candidateSourceName(win.sample.source);
  r.message += fmt("winner %.0f (", r.winner) + source +
               fmt("): utility %.3f 1/s, gain %.3f (object gain %.3f)", win.utility, win.gain, win.gain_obj) +
               fmt(", path %.2f m ", pathLength_m(r.path_W)) + PlannedPath::name(win.plan.status) +
               fmt("; %.0f of %.0f candidates planned, %.0f reachable", r.candidates_planned,
                   static_cast<double>(r.candidates.size()), r.candidates_reachable);
  if (r.object_views > 0) r.message += fmt("; %.0f object ring views", static_cast<double>(r.object_views));
  return finish();
}

}  // namespace semexp

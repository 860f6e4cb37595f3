#include "semantic_exploration/core/planning/termination.hpp"

#include <algorithm>
#include <cstdio>

namespace semexp {

namespace {

std::string fmt(const char* f, double a, double b = 0.0, double c = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), f, a, b, c);
  return buf;
}

}  // namespace

TerminationCheck::TerminationCheck(const TerminationConfig& config, const PlannerConfig& planner)
    : config_(config), planner_(planner) {
  config_.validate();
  planner_.validate();
}

bool TerminationCheck::progressed(const Sample& old, const Sample& now, std::string& what) const {
  const double grown = now.volume_m3 - old.volume_m3;
  if (grown >= planner_.stall_volume_m3) return true;
  what = fmt("explored volume grew %.3f m^3 (< %.3f)", grown, planner_.stall_volume_m3);
  if (now.active_frontiers < old.active_frontiers) return true;
  what += fmt(", active frontier voxels went from %.0f to %.0f", static_cast<double>(old.active_frontiers),
              static_cast<double>(now.active_frontiers));
  if (now.frontier_clusters_retired > old.frontier_clusters_retired) return true;
  what += ", no frontier cluster was retired by evidence for the first time";
  if (pursuesBackground() && old.background_share >= 0 && now.background_share >= 0) {
    const double d = now.background_share - old.background_share;
    if (d >= config_.stall_share) return true;
    what += fmt(", background share seen from <= d_bg grew %.3f (< %.3f)", d, config_.stall_share);
  }
  if (pursuesObjects()) {
    for (const auto& kv : now.object_shares) {
      const auto before = old.object_shares.find(kv.first);
      if (before == old.object_shares.end()) return true;  // a new object
      if (kv.second - before->second >= config_.stall_share) return true;
    }
    what += fmt(", no object appeared or had its share seen from <= d_obj grow by %.3f", config_.stall_share);
  }
  return false;
}

TerminationDecision TerminationCheck::check(const TerminationInputs& in) {
  TerminationDecision d;
  ++checks_;
  if (planner_.time_limit_s > 0 && in.elapsed_s >= planner_.time_limit_s) {
    d.finished = true;
    d.reason = "time_limit";
    d.message = fmt("time limit of %.0f s reached", planner_.time_limit_s);
    return d;
  }

  // The three conditions of "explored".
  d.frontiers_done = in.active_frontiers <= static_cast<std::size_t>(config_.max_active_frontiers);
  d.background_done = !pursuesBackground() ||
                      (in.background_share >= 0 && in.background_share >= config_.background_observed_share);
  std::size_t objects_below = 0;
  double min_share = 1.0;
  for (const auto& o : in.objects) {
    min_share = std::min(min_share, o.observed_fraction);
    if (o.observed_fraction >= planner_.object_observed_fraction) continue;
    const bool retired = std::find(in.retired_object_ids.begin(), in.retired_object_ids.end(), o.id) !=
                         in.retired_object_ids.end();
    ++(retired ? d.objects_retired : objects_below);
  }
  d.objects_done = !pursuesObjects() || objects_below == 0;
  const std::pair<const char*, bool> conds[3] = {
      {"frontiers", d.frontiers_done}, {"background", d.background_done}, {"objects", d.objects_done}};
  for (const auto& c : conds) {
    auto it = held_since_.find(c.first);
    if (!c.second)
      held_since_[c.first] = -1;
    else if (it == held_since_.end() || it->second < 0)
      held_since_[c.first] = checks_;
  }
  if (d.frontiers_done && d.background_done && d.objects_done) {
    long latest = -1;
    for (const auto& c : conds)
      if (held_since_[c.first] > latest) latest = held_since_[c.first], d.last_condition = c.first;
    d.finished = true;
    d.reason = "explored";
    d.message = fmt("%.0f active frontier voxels (<= %.0f)", static_cast<double>(in.active_frontiers),
                    config_.max_active_frontiers);
    if (pursuesBackground())
      d.message += fmt(", background seen from <= d_bg: %.3f (>= %.3f)", in.background_share,
                       config_.background_observed_share);
    if (pursuesObjects() && d.objects_retired == 0)
      d.message += fmt(", %.0f objects, each seen from <= d_obj at >= %.2f (lowest %.3f)",
                       static_cast<double>(in.objects.size()), planner_.object_observed_fraction,
                       in.objects.empty() ? 1.0 : min_share);
    else if (pursuesObjects())
      d.message += fmt(", %.0f objects: %.0f seen from <= d_obj at >= %.2f", static_cast<double>(in.objects.size()),
                       static_cast<double>(in.objects.size() - d.objects_retired), planner_.object_observed_fraction) +
                   fmt(", %.0f retired below it (flights aimed at them did not move it; lowest %.3f)",
                       static_cast<double>(d.objects_retired), min_share);
    d.message += "; the last condition to hold: " + d.last_condition;
    return d;
  }

  // no_progress: a window of stall_iterations checks in which nothing pursued improved.
  if (planner_.stall_iterations <= 0 || in.explored_volume_m3 < 0) return d;
  Sample now{in.explored_volume_m3, in.active_frontiers, in.frontier_clusters_retired, in.background_share, {}};
  for (const auto& o : in.objects) now.object_shares[o.id] = o.observed_fraction;
  history_.push_back(now);
  const std::size_t k = static_cast<std::size_t>(planner_.stall_iterations);
  while (history_.size() > k + 1) history_.pop_front();
  if (history_.size() <= k) return d;
  std::string what;
  if (progressed(history_.front(), history_.back(), what)) return d;
  d.finished = true;
  d.reason = "no_progress";
  d.message = what + fmt(" over the last %.0f iterations", static_cast<double>(k));
  return d;
}

}  // namespace semexp

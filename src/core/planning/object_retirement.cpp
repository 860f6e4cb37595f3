#include "semantic_exploration/core/planning/object_retirement.hpp"

#include <cmath>
#include <set>

namespace semexp {

ObjectRetirement::ObjectRetirement(const ObjectRetirementConfig& config, double done_share)
    : config_(config), done_share_(done_share) {
  config_.validate();
  require(std::isfinite(done_share) && done_share >= 0 && done_share <= 1, "planner/object_observed_fraction",
          "must be in [0, 1]");
}

std::vector<ObjectRetirementChange> ObjectRetirement::update(const std::vector<ObjectSummary>& objects) {
  std::vector<ObjectRetirementChange> changes;
  std::set<std::uint32_t> present;
  for (const ObjectSummary& o : objects) {
    present.insert(o.id);
    auto it = state_.find(o.id);
    if (it == state_.end()) continue;
    State& s = it->second;
    if (s.retired && (std::abs(o.observed_fraction - s.share_at_retirement) >= config_.min_share_change ||
                      o.observed_fraction >= done_share_)) {
      s = State();
      changes.push_back({o.id, false, o.observed_fraction});
    }
  }
  for (auto it = state_.begin(); it != state_.end();) it = present.count(it->first) ? std::next(it) : state_.erase(it);

  if (!pending_) return changes;
  pending_ = false;
  if (!config_.enabled) return changes;
  for (const ObjectSummary& o : objects) {
    if (o.id != pending_id_) continue;
    State& s = state_[o.id];
    if (s.retired) return changes;
    if (std::abs(o.observed_fraction - pending_share_) >= config_.min_share_change ||
        o.observed_fraction >= done_share_) {
      s.failed_views = 0;
      return changes;
    }
    if (++s.failed_views >= config_.max_failed_views) {
      s.retired = true;
      s.share_at_retirement = o.observed_fraction;
      changes.push_back({o.id, true, o.observed_fraction});
    }
    return changes;
  }
  return changes;
}

void ObjectRetirement::recordView(std::uint32_t id, double share_now) {
  pending_ = true;
  pending_id_ = id;
  pending_share_ = share_now;
}

bool ObjectRetirement::retired(std::uint32_t id) const {
  const auto it = state_.find(id);
  return it != state_.end() && it->second.retired;
}

std::vector<std::uint32_t> ObjectRetirement::retiredIds() const {
  std::vector<std::uint32_t> ids;
  for (const auto& kv : state_)
    if (kv.second.retired) ids.push_back(kv.first);
  return ids;
}

std::vector<ObjectSummary> ObjectRetirement::active(const std::vector<ObjectSummary>& objects) const {
  std::vector<ObjectSummary> out;
  for (const ObjectSummary& o : objects)
    if (!retired(o.id)) out.push_back(o);
  return out;
}

}  // namespace semexp

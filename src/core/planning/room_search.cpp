#include "semantic_exploration/core/planning/room_search.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <unordered_map>

#include "semantic_exploration/core/int_math.hpp"

namespace semexp {

namespace {

std::uint64_t latticeKey(const Eigen::Vector3i& k) { return cellKey21(k.x(), k.y(), k.z()); }

}  // namespace

std::vector<Eigen::Vector3d> findRoom(const PathPlanner& paths, const CollisionQuery& is_free,
                                      const Eigen::Vector3d& start_W, const RoomSearchSettings& s) {
  if (!is_free || !(s.step_m > 0) || !paths.valid(start_W) || is_free(start_W, s.room_radius_m)) return {};
  if (!(s.search_radius_m > 0)) return {};
  const int reach = std::max(1, static_cast<int>(std::floor(s.search_radius_m / s.step_m)));
  const auto at = [&](const Eigen::Vector3i& k) -> Eigen::Vector3d { return start_W + s.step_m * k.cast<double>(); };
  // parent of each entered lattice point (the start is its own parent)
  std::unordered_map<std::uint64_t, Eigen::Vector3i> parent;
  // Points judged invalid are never entered: each is tested once, so the
  // work is bounded by max_points entered points x 26 segment tests.
  std::unordered_map<std::uint64_t, bool> point_valid;
  std::deque<Eigen::Vector3i> queue{Eigen::Vector3i::Zero()};
  parent.emplace(latticeKey(Eigen::Vector3i::Zero()), Eigen::Vector3i::Zero());
  bool found = false;
  Eigen::Vector3i room = Eigen::Vector3i::Zero();
  while (!queue.empty() && !found) {
    const Eigen::Vector3i k = queue.front();
    queue.pop_front();
    for (int dz = -1; dz <= 1 && !found; ++dz)
      for (int dy = -1; dy <= 1 && !found; ++dy)
        for (int dx = -1; dx <= 1 && !found; ++dx) {
          const Eigen::Vector3i n = k + Eigen::Vector3i(dx, dy, dz);
          if (n == k || n.squaredNorm() > reach * reach || parent.size() >= s.max_points) continue;
          const std::uint64_t key = latticeKey(n);
          if (parent.count(key)) continue;  // entered already
          auto pv = point_valid.find(key);
          if (pv == point_valid.end()) pv = point_valid.emplace(key, paths.valid(at(n))).first;
          if (!pv->second || !paths.segmentValid(at(k), at(n))) continue;  // perhaps from another neighbour
          parent.emplace(key, k);
          if (is_free(at(n), s.room_radius_m)) {
            found = true;
            room = n;
          } else {
            queue.push_back(n);
          }
        }
  }
  if (!found) return {};
  std::vector<Eigen::Vector3d> chain;
  for (Eigen::Vector3i k = room;; k = parent.at(latticeKey(k))) {
    chain.push_back(at(k));
    if (k == Eigen::Vector3i::Zero()) break;
  }
  std::vector<Eigen::Vector3d> route{start_W};
  // Greedy shortcut, from the start: the farthest chain point a valid segment reaches.
  for (std::size_t i = chain.size() - 1; i > 0;) {
    std::size_t j = 0;
    while (j + 1 < i && !paths.segmentValid(chain[i], chain[j])) ++j;
    route.push_back(chain[j]);
    i = j;
  }
  return route;
}

PlanningStart startAfterRoute(const std::vector<Eigen::Vector3d>& route_W) {
  PlanningStart out;
  if (route_W.empty()) return out;
  out.start_W = route_W.front();
  out.from_W = route_W.back();
  out.lead_W.assign(route_W.begin(), route_W.end() - 1);
  out.ok = true;
  return out;
}

}  // namespace semexp

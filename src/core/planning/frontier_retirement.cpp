#include "semantic_exploration/core/planning/frontier_retirement.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "semantic_exploration/core/int_math.hpp"

namespace semexp {

namespace {

constexpr double kHeightStepM = 0.3;   // between the view heights tried
constexpr int kHeights = 5;            // the nearest reachable height, then +-1 and +-2 steps
constexpr double kRadiusStepM = 0.5;   // between the horizontal distances tried
constexpr int kAzimuths = 12;

double wrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

}  // namespace

FrontierRetirement::FrontierRetirement(const FrontierRetirementConfig& config, const PinholeCamera& camera,
                                       const Bounds& bounds, double clearance_radius_m, double map_resolution_m)
    : config_(config),
      camera_(camera),
      bounds_(bounds),
      clearance_radius_m_(clearance_radius_m),
      resolution_m_(map_resolution_m) {
  config_.validate();
  camera_.validate();
  bounds_.validate();
  require(std::isfinite(resolution_m_) && resolution_m_ > 0, "background_map/resolution_m", "must be > 0 m");
  require(config_.fov_margin_rad < 0.5 * camera_.vfov_rad(), "frontier_retirement/fov_margin_rad",
          "must be < half the camera's vertical field of view");
  require(bounds_.max_m.z() - bounds_.min_m.z() >= 2.0 * clearance_radius_m_, "bounds/max_m",
          "leaves no camera height: the box must be at least 2 x (R + clearance margin) tall");
}

std::uint64_t FrontierRetirement::key(const Eigen::Vector3d& p) const {
  return pointCellKey21(p.x(), p.y(), p.z(), config_.cluster_size_m);
}

bool FrontierRetirement::lineOfSight(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double short_m,
                                     const CollisionQuery& not_occupied, const LineQuery& line) const {
  const Eigen::Vector3d d = to - from;
  const double len = d.norm() - short_m;
  if (len <= 0) return true;
  const Eigen::Vector3d u = d / d.norm();
  if (line) return line(from, u, len, resolution_m_);
  for (double t = 0.0; t <= len; t += resolution_m_)
    if (!not_occupied(from + t * u, 0.0)) return false;
  return true;
}

bool FrontierRetirement::sees(const ViewPose& pose, const Eigen::Vector3d& p, const CollisionQuery& not_occupied,
                              const LineQuery& line) const {
  const Eigen::Vector3d d = p - pose.position_W;
  const double dist = d.norm();
  if (dist > config_.view_range_m || dist < 1e-6) return false;
  const double horizontal = std::hypot(d.x(), d.y());
  if (std::abs(std::atan2(d.z(), horizontal)) > 0.5 * camera_.vfov_rad()) return false;
  if (std::abs(wrapAngle(std::atan2(d.y(), d.x()) - pose.yaw_rad)) > 0.5 * camera_.hfov_rad()) return false;
  // A view reaches the cluster when nothing occupied lies between the camera
  // and the cluster's cube: the surface a frontier borders is allowed to
  // hide the frontier voxel itself (that is what the evidence is about).
  return lineOfSight(pose.position_W, p, 0.5 * config_.cluster_size_m, not_occupied, line);
}

std::vector<Eigen::Vector3d> FrontierRetirement::viewPointPositions(const Eigen::Vector3d& c) const {
  std::vector<Eigen::Vector3d> out;
  const double half = 0.5 * camera_.vfov_rad() - config_.fov_margin_rad;
  const double z_lo = bounds_.min_m.z() + clearance_radius_m_, z_hi = bounds_.max_m.z() - clearance_radius_m_;
  if (half <= 0 || z_lo > z_hi) return out;
  const double z0 = std::clamp(c.z(), z_lo, z_hi);
  const double range = config_.view_range_m;
  for (int k = 0; k < kHeights; ++k) {
    const int step = (k + 1) / 2 * (k % 2 == 1 ? -1 : 1);  // 0, -1, +1, -2, +2
    const double zc = z0 + step * kHeightStepM;
    if (zc < z_lo - 1e-9 || zc > z_hi + 1e-9) continue;
    const double dz = std::abs(c.z() - zc);
    if (dz >= range) continue;
    const double h_min = std::max(config_.min_view_distance_m, dz / std::tan(half));
    const double h_max = std::sqrt(range * range - dz * dz);
    for (double h = h_min; h <= h_max + 1e-9; h += kRadiusStepM)
      for (int a = 0; a < kAzimuths; ++a) {
        const double az = 2.0 * M_PI * a / kAzimuths;
        out.emplace_back(c.x() + h * std::cos(az), c.y() + h * std::sin(az), zc);
      }
  }
  return out;
}

bool FrontierRetirement::possibleViewPoint(const Eigen::Vector3d& p, const Eigen::Vector3d& c,
                                           const CollisionQuery& not_occupied, const LineQuery& line) const {
  // Two voxels short: a grazing line meets the voxels of the surface the frontier borders next to it.
  return bounds_.contains(p) && not_occupied(p, clearance_radius_m_) &&
         lineOfSight(p, c, 2.0 * resolution_m_, not_occupied, line);
}

int FrontierRetirement::viewPoints(const Eigen::Vector3d& c, const CollisionQuery& not_occupied, int stop_at,
                                   const LineQuery& line) const {
  int n = 0;
  for (const Eigen::Vector3d& p : viewPointPositions(c))
    if (possibleViewPoint(p, c, not_occupied, line) && ++n == stop_at) return n;
  return n;
}

std::vector<bool> FrontierRetirement::possibleViewPoints(const Eigen::Vector3d& c, const CollisionQuery& not_occupied,
                                                         const LineQuery& line) const {
  const std::vector<Eigen::Vector3d> ps = viewPointPositions(c);
  std::vector<bool> out(ps.size());
  for (std::size_t i = 0; i < ps.size(); ++i) out[i] = possibleViewPoint(ps[i], c, not_occupied, line);
  return out;
}

FrontierRetirement::Recount FrontierRetirement::recount(const Eigen::Vector3d& c, const std::vector<bool>& before,
                                                        const CollisionQuery& not_occupied, const LineQuery& line) const {
  // Now = kept + gained, where kept counts the view points possible before
  // that still are, gained those impossible before that are now. More than
  // before (k) <=> gained > k - kept <=> lost = k - kept < gained. The
  // impossible ones are judged first (usually fewer and quicker: a blocked
  // line of sight stops early), then the possible ones only until the
  // comparison is settled.
  const std::vector<Eigen::Vector3d> ps = viewPointPositions(c);
  int gained = 0, k = 0;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    if (before[i])
      ++k;
    else
      gained += possibleViewPoint(ps[i], c, not_occupied, line);
  }
  Recount out;
  if (gained > k) {
    out.any = out.more = true;
    return out;
  }
  int kept = 0, lost = 0;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    if (!before[i]) continue;
    if (possibleViewPoint(ps[i], c, not_occupied, line)) {
      ++kept;
      out.any = true;
      if (gained > k - kept) {  // already more than before
        out.more = true;
        return out;
      }
      if (gained == 0) return out;  // none gained: never more; one kept: some
    } else if (++lost >= gained && gained > 0) {
      out.any = true;  // at most k - gained kept: never more, and `gained` > 0 are possible
      return out;
    }
  }
  out.any = out.any || gained > 0;
  return out;
}

FrontierRetirement::Split FrontierRetirement::update(const std::vector<Eigen::Vector3d>& frontiers_W,
                                                     const CollisionQuery& not_occupied, const LineQuery& line) {
  ++iteration_;
  Split out;
  if (!config_.enabled) {
    out.active_W = frontiers_W;
    return out;
  }
  // Members of each cluster now.
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> members;
  for (std::size_t i = 0; i < frontiers_W.size(); ++i) members[key(frontiers_W[i])].push_back(i);
  for (auto it = clusters_.begin(); it != clusters_.end();) {
    // A cluster without frontiers keeps its state only while retired by evidence.
    if (!members.count(it->first) && !it->second.by_evidence) {
      it = clusters_.erase(it);
      continue;
    }
    it->second.voxels = 0;
    ++it;
  }
  for (const auto& m : members) {
    Cluster& c = clusters_[m.first];
    c.voxels = static_cast<int>(m.second.size());
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (std::size_t i : m.second) sum += frontiers_W[i];
    c.centre_W = sum / static_cast<double>(m.second.size());
  }
  // Evidence: the views recorded last iteration.
  for (auto& kv : clusters_) {
    Cluster& c = kv.second;
    if (c.voxels_at_view < 0) continue;
    if (c.voxels_at_first_view < 0) c.voxels_at_first_view = c.voxels_at_view;
    const bool shrank = c.voxels <= c.voxels_at_first_view * (1.0 - config_.shrink_fraction);
    c.failed_views = shrank ? 0 : c.failed_views + 1;
    if (shrank) c.voxels_at_first_view = -1;  // progress: the next view starts a new run from its own count
    c.voxels_at_view = -1;
    if (!c.by_evidence && c.failed_views >= config_.max_failed_views) {
      c.by_evidence = true;
      ever_retired_by_evidence_.insert(kv.first);
      c.possible_at_retirement = possibleViewPoints(c.centre_W, not_occupied, line);
      c.viewpoints_at_retirement =
          static_cast<int>(std::count(c.possible_at_retirement.begin(), c.possible_at_retirement.end(), true));
      c.centre_at_retirement_W = c.centre_W;
      c.judged_at = iteration_;
    }
  }
  // Geometry: new clusters now, every cluster again each recheck_iterations
  // (surface found since can hide a cluster, free space found can reveal it).
  for (const auto& m : members) {
    Cluster& c = clusters_[m.first];
    if (c.judged_at >= 0 && iteration_ - c.judged_at < config_.recheck_iterations) continue;
    c.judged_at = iteration_;
    if (!c.by_evidence) {
      c.by_geometry = viewPoints(c.centre_W, not_occupied, 1, line) == 0;
      continue;
    }
    // Retired by evidence: are more view points possible than at retirement?
    // Where the centre has not moved, the view points are the same ones and
    // those possible at retirement settle it without judging them all.
    Recount now;
    if (c.centre_W == c.centre_at_retirement_W) {
      now = recount(c.centre_W, c.possible_at_retirement, not_occupied, line);
    } else {
      const int n = viewPoints(c.centre_W, not_occupied, 0, line);
      now.any = n > 0;
      now.more = n > c.viewpoints_at_retirement;
    }
    c.by_geometry = !now.any;
    if (now.more && takeEvidenceReturn(m.first)) {
      c.by_evidence = false;  // new free space around it: worth another look
      c.failed_views = 0;
      c.voxels_at_first_view = -1;
      c.possible_at_retirement.clear();
    }
  }
  out.active_W.reserve(frontiers_W.size());
  for (const auto& m : members) {
    const Cluster& c = clusters_[m.first];
    ++out.clusters;
    const bool retired = c.by_geometry || c.by_evidence;
    out.retired_by_geometry += c.by_geometry;
    out.retired_by_evidence += !c.by_geometry && c.by_evidence;
    for (std::size_t i : m.second) (retired ? out.retired_W : out.active_W).push_back(frontiers_W[i]);
  }
  return out;
}

bool FrontierRetirement::takeEvidenceReturn(std::uint64_t cube) {
  if (config_.max_evidence_returns < 0) return true;  // no limit: nothing to count
  int& returns = evidence_returns_[cube];
  if (returns >= config_.max_evidence_returns) return false;
  ++returns;
  return true;
}

void FrontierRetirement::discardViews() {
  for (auto& kv : clusters_) kv.second.voxels_at_view = -1;
}

void FrontierRetirement::recordViews(const std::vector<ViewPose>& poses, const CollisionQuery& not_occupied,
                                     const std::vector<Eigen::Vector3d>& targets_W, const LineQuery& line) {
  if (!config_.enabled) return;
  for (const auto& t : targets_W) {
    const auto it = clusters_.find(key(t));
    if (it != clusters_.end() && it->second.voxels > 0) it->second.voxels_at_view = it->second.voxels;
  }
  for (auto& kv : clusters_) {
    Cluster& c = kv.second;
    if (c.voxels == 0 || c.by_geometry || c.by_evidence || c.voxels_at_view >= 0) continue;
    for (const auto& pose : poses)
      if (sees(pose, c.centre_W, not_occupied, line)) {
        c.voxels_at_view = c.voxels;
        break;
      }
  }
}

}  // namespace semexp

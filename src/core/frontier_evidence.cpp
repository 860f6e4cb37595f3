#include "semantic_exploration/core/frontier_evidence.hpp"

#include <algorithm>
#include <cmath>

#include "semantic_exploration/core/occupancy_map.hpp"

namespace semexp {

FrontierEvidence::FrontierEvidence(const FrontierEvidenceConfig& config) : config_(config) { config_.validate(); }

std::uint64_t FrontierEvidence::key(const Eigen::Vector3d& p) const {
  // Leaf centres lie at (i + 0.5) r: floor(p / r) names each finest voxel once (a coarse leaf's centre names
  // one voxel of it).
  const auto c = [this](double v) {
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(v / key_resolution_m_)) + (1 << 20)) &
           0x1FFFFF;
  };
  return c(p.x()) | (c(p.y()) << 21) | (c(p.z()) << 42);
}

bool FrontierEvidence::look(const OccupancyMap& map, const float* depth_m, const PinholeCamera& camera,
                            const Eigen::Isometry3d& T_WC) {
  if (!config_.enabled) return false;
  key_resolution_m_ = map.resolution();
  if (have_last_) {
    const double moved = (T_WC.translation() - last_T_WC_.translation()).norm();
    const double turned = Eigen::AngleAxisd(last_T_WC_.linear().transpose() * T_WC.linear()).angle();
    if (moved < config_.min_look_separation_m && turned < config_.min_look_rotation_rad) return false;
  }
  have_last_ = true;
  last_T_WC_ = T_WC;
  ++counted_frames_;
  const Eigen::Isometry3d T_CW = T_WC.inverse();
  const double r = map.resolution();
  std::unordered_map<std::uint64_t, std::uint8_t> next;
  next.reserve(map.frontierCount());
  retired_ = 0;
  map.forEachFrontier([&](const Eigen::Vector3d& p_W, double size_m) {
    const std::uint64_t k = key(p_W);
    const auto it = looks_.find(k);
    int n = it == looks_.end() ? 0 : it->second;
    const Eigen::Vector3d p_C = T_CW * p_W;
    const double z = p_C.z();
    // The neighbourhood (the leaf and its neighbours, 1.5 leaf edges from the centre) must project inside the
    // image: the unknown neighbour was in the field of view as well.
    const double half = 1.5 * std::max(size_m, r);
    if (n < config_.looks_to_retire && z - half > camera.d_min_m && p_C.norm() <= config_.view_range_m) {
      const double u = camera.fx * p_C.x() / z + camera.cx, v = camera.fy * p_C.y() / z + camera.cy;
      const double mu = camera.fx * half / (z - half), mv = camera.fy * half / (z - half);
      if (u - mu >= 0 && v - mv >= 0 && u + mu <= camera.width - 1 && v + mv <= camera.height - 1) {
        const int iu = static_cast<int>(std::lround(u)), iv = static_cast<int>(std::lround(v));
        const float d = depth_m[static_cast<std::size_t>(iv) * camera.width + iu];
        const bool no_return = !std::isfinite(d) || d <= 0.0f;
        if (no_return || d >= z - config_.occlusion_margin_m) ++n;
      }
    }
    if (n > 0) next.emplace(k, static_cast<std::uint8_t>(n));
    retired_ += n >= config_.looks_to_retire;
  });
  looks_.swap(next);
  return true;
}

int FrontierEvidence::looks(const Eigen::Vector3d& p_W) const {
  if (key_resolution_m_ <= 0) return 0;
  const auto it = looks_.find(key(p_W));
  return it == looks_.end() ? 0 : it->second;
}

bool FrontierEvidence::retired(const Eigen::Vector3d& p_W) const { return looks(p_W) >= config_.looks_to_retire; }

}  // namespace semexp

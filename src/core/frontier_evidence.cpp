#include "semantic_exploration/core/frontier_evidence.hpp"

#include <algorithm>
#include <cmath>

#include "semantic_exploration/core/int_math.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"

namespace semexp {

FrontierEvidence::FrontierEvidence(const FrontierEvidenceConfig& config) : config_(config) { config_.validate(); }

std::uint64_t FrontierEvidence::key(const Eigen::Vector3d& p) const {
  // Leaf centres lie at (i + 0.5) r: floor(p / r) names each finest voxel once (a coarse leaf's centre names
  // one voxel of it).
  return pointCellKey21(p.x(), p.y(), p.z(), key_resolution_m_);
}

std::size_t FrontierEvidence::look(const OccupancyMap& map, const float* depth_m, const PinholeCamera& camera,
                                   const Eigen::Isometry3d& T_WC) {
  if (!config_.enabled) return 0;
  key_resolution_m_ = map.resolution();
  const Eigen::Isometry3d T_CW = T_WC.inverse();
  const Eigen::Vector3d o_W = T_WC.translation();
  const double r = map.resolution();
  const double cos_turn = std::cos(config_.min_look_rotation_rad);
  std::unordered_map<std::uint64_t, Entry> next;
  next.reserve(entries_.size() + 64);
  std::size_t looked = 0;
  retired_ = 0;
  map.forEachFrontier([&](const Eigen::Vector3d& p_W, double size_m) {
    if (size_m > 1.5 * r) return;  // a coarse leaf: its centre names no voxel of its own
    const std::uint64_t k = key(p_W);
    const auto it = entries_.find(k);
    Entry e = it == entries_.end() ? Entry{} : it->second;
    if (e.looks < config_.looks_to_retire && sees(p_W, o_W, T_CW, r, depth_m, camera)) {
      bool fresh = e.looks == 0;
      if (!fresh) {
        const Eigen::Vector3d last = e.camera_W.cast<double>();
        const Eigen::Vector3d a = (p_W - last).normalized(), b = (p_W - o_W).normalized();
        fresh = (o_W - last).norm() >= config_.min_look_separation_m || a.dot(b) <= cos_turn;
      }
      if (fresh) {
        ++e.looks;
        e.camera_W = o_W.cast<float>();
        ++looked;
      }
    }
    if (e.looks > 0) next.emplace(k, e);
    retired_ += e.looks >= config_.looks_to_retire;
  });
  entries_.swap(next);
  return looked;
}

bool FrontierEvidence::sees(const Eigen::Vector3d& p_W, const Eigen::Vector3d& o_W, const Eigen::Isometry3d& T_CW,
                            double r, const float* depth_m, const PinholeCamera& camera) const {
  const Eigen::Vector3d p_C = T_CW * p_W;
  const double z = p_C.z();
  // The neighbourhood (the voxel and its neighbours, 1.5 voxels from the centre) must project inside the
  // image: the unknown neighbour was in the field of view as well.
  const double half = 1.5 * r;
  if (z - half <= camera.d_min_m || (p_W - o_W).norm() > config_.view_range_m) return false;
  Eigen::Vector2f uv;
  if (!camera.project(p_C.cast<float>(), uv)) return false;
  const double u = uv.x(), v = uv.y();
  const double mu = camera.fx * half / (z - half), mv = camera.fy * half / (z - half);
  if (u - mu < 0 || v - mv < 0 || u + mu > camera.width - 1 || v + mv > camera.height - 1) return false;
  const int iu = static_cast<int>(std::lround(u)), iv = static_cast<int>(std::lround(v));
  const float d = depth_m[static_cast<std::size_t>(iv) * camera.width + iu];
  const bool no_return = !std::isfinite(d) || d <= 0.0f;
  return no_return || d >= z - config_.occlusion_margin_m;
}

int FrontierEvidence::looks(const Eigen::Vector3d& p_W) const {
  if (key_resolution_m_ <= 0) return 0;
  const auto it = entries_.find(key(p_W));
  return it == entries_.end() ? 0 : it->second.looks;
}

bool FrontierEvidence::retired(const Eigen::Vector3d& p_W) const { return looks(p_W) >= config_.looks_to_retire; }

}  // namespace semexp

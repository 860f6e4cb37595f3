#include "semantic_exploration/core/planning/path_check.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace semexp {

PathClearance checkPathClearance(const std::vector<Eigen::Vector3d>& path_W, bool escaped, double clearance_radius_m,
                                 double mav_radius_m, double step_m, const CollisionQuery& not_occupied) {
  if (!(step_m > 0) || !(clearance_radius_m > 0) || !(mav_radius_m > 0) || !not_occupied)
    throw std::invalid_argument("checkPathClearance: step and radii must be > 0 and not_occupied set");
  PathClearance out;
  if (path_W.empty()) {
    out.why = "empty path";
    return out;
  }
  for (std::size_t i = 0; i + 1 < path_W.size(); ++i) {
    const double radius = (escaped && i == 0) ? 0.5 * mav_radius_m : clearance_radius_m;
    const Eigen::Vector3d d = path_W[i + 1] - path_W[i];
    const int n = std::max(1, static_cast<int>(std::ceil(d.norm() / step_m)));
    for (int k = 0; k <= n; ++k) {
      const Eigen::Vector3d q = path_W[i] + d * (static_cast<double>(k) / n);
      if (not_occupied(q, radius)) continue;
      char buf[160];
      std::snprintf(buf, sizeof(buf), "occupied voxel within %.3f m of (%.2f, %.2f, %.2f) on segment %zu of %zu",
                    radius, q.x(), q.y(), q.z(), i + 1, path_W.size() - 1);
      out.why = buf;
      return out;
    }
  }
  out.safe = true;
  return out;
}

}  // namespace semexp

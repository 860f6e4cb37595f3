#include "semantic_exploration/core/planning/sampler.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace semexp {

const char* candidateSourceName(CandidateSource s) {
  switch (s) {
    case CandidateSource::kFrontier: return "frontier";
    case CandidateSource::kObject: return "object";
    case CandidateSource::kFreeSpace: return "free_space";
  }
  return "?";
}

CandidateSampler::CandidateSampler(const PlannerConfig& planner, const ExplorationConfig& exploration,
                                   const Bounds& bounds)
    : planner_(planner), exploration_(exploration), bounds_(bounds), rng_(planner.seed) {
  planner_.validate();
  exploration_.validate();
  bounds_.validate();
}

Eigen::Vector3d CandidateSampler::clampToBounds(const Eigen::Vector3d& p) const {
  Eigen::Vector3d out;
  for (int i = 0; i < 3; ++i) {
    double lo = bounds_.min_m[i] + planner_.mav_radius_m, hi = bounds_.max_m[i] - planner_.mav_radius_m;
    if (lo > hi) lo = hi = 0.5 * (bounds_.min_m[i] + bounds_.max_m[i]);
    out[i] = std::clamp(p[i], lo, hi);
  }
  return out;
}

Eigen::Vector3d CandidateSampler::objectViewPoint(const ObjectSummary& o, double yaw) const {
  return objectViewPoint(o, yaw, o.centroid_W.z());
}

Eigen::Vector3d CandidateSampler::objectViewPoint(const ObjectSummary& o, double yaw, double z_W) const {
  const Eigen::Vector3d dir(std::cos(yaw), std::sin(yaw), 0.0);
  // Distance from the centroid to where the horizontal ray leaves the box.
  double t_exit = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 2; ++i) {
    if (std::abs(dir[i]) < 1e-12) continue;
    const double face = dir[i] > 0 ? o.bbox_max_W[i] : o.bbox_min_W[i];
    t_exit = std::min(t_exit, std::max(0.0, (face - o.centroid_W[i]) / dir[i]));
  }
  if (!std::isfinite(t_exit)) t_exit = 0.0;
  const double standoff = planner_.object_standoff_factor * exploration_.d_obj_m;
  Eigen::Vector3d p = o.centroid_W + (t_exit + standoff) * dir;
  p.z() = z_W;
  return clampToBounds(p);
}

std::vector<CandidateSample> CandidateSampler::sample(const std::vector<Eigen::Vector3d>& frontiers_W,
                                                      const std::vector<ObjectSummary>& objects,
                                                      const CollisionQuery& is_free) {
  std::vector<std::size_t> fr, ob;  // remaining indices (swap-and-pop = without replacement)
  if (planner_.p_frontier > 0.0) {
    fr.resize(frontiers_W.size());
    for (std::size_t i = 0; i < fr.size(); ++i) fr[i] = i;
  }
  if (planner_.p_frontier < 1.0)
    for (std::size_t i = 0; i < objects.size(); ++i)
      if (needsObservation(objects[i])) ob.push_back(i);

  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto take = [this](std::vector<std::size_t>& pool) {
    std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
    const std::size_t k = pick(rng_);
    const std::size_t idx = pool[k];
    pool[k] = pool.back();
    pool.pop_back();
    return idx;
  };

  std::vector<CandidateSample> out;
  while (static_cast<int>(out.size()) < planner_.n_candidates && (!fr.empty() || !ob.empty())) {
    // Draw the source first so that P_fr holds per draw while both remain.
    const bool frontier = ob.empty() || (!fr.empty() && unit(rng_) < planner_.p_frontier);
    CandidateSample s;
    if (frontier) {
      s.source = CandidateSource::kFrontier;
      s.position_W = clampToBounds(frontiers_W[take(fr)]);
    } else {
      const ObjectSummary& o = objects[take(ob)];
      s.source = CandidateSource::kObject;
      s.object_id = o.id;
      const double yaw0 = unit(rng_) * 2.0 * M_PI;
      const double z = drawViewHeight(o);
      s.position_W = objectViewPoint(o, yaw0, z);
      if (is_free) {
        for (int k = 0; k < 8; ++k) {
          const Eigen::Vector3d p = objectViewPoint(o, yaw0 + k * M_PI / 4.0, z);
          if (is_free(p, planner_.clearance_radius_m())) {
            s.position_W = p;
            break;
          }
        }
      }
    }
    out.push_back(s);
  }
  return out;
}

double CandidateSampler::drawViewHeight(const ObjectSummary& o) {
  // From two clearance radii above the box bottom (the clearance sphere then stays off the floor the object
  // stands on and its voxels) to the box top (see objectViewPoint).
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double z_lo = std::min(o.centroid_W.z(), o.bbox_min_W.z() + 2.0 * planner_.clearance_radius_m());
  return z_lo + unit(rng_) * std::max(0.0, o.bbox_max_W.z() - z_lo);
}

std::vector<Eigen::Vector3d> CandidateSampler::objectViewRing(const ObjectSummary& o, const CollisionQuery& is_free) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int m = planner_.object_view_samples;
  const double step = 2.0 * M_PI / m;
  const double yaw0 = unit(rng_) * step;
  std::vector<Eigen::Vector3d> out;
  for (int k = 0; k < m; ++k) {
    // Every draw is made whether or not the point is free, so the stream does not depend on the map.
    const Eigen::Vector3d p = objectViewPoint(o, yaw0 + k * step, drawViewHeight(o));
    if (!is_free || is_free(p, planner_.clearance_radius_m())) out.push_back(p);
  }
  return out;
}

std::vector<CandidateSample> CandidateSampler::sampleFreeSpace(const CollisionQuery& is_free) {
  std::vector<CandidateSample> out;
  if (!is_free) return out;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int k = 0; k < 20 * planner_.n_candidates && static_cast<int>(out.size()) < planner_.n_candidates; ++k) {
    Eigen::Vector3d p;
    // Uniform in the box shrunk by R (clamping draws from the full box would pile them on its faces).
    for (int i = 0; i < 3; ++i) {
      const double lo = bounds_.min_m[i] + planner_.mav_radius_m, hi = bounds_.max_m[i] - planner_.mav_radius_m;
      p[i] = lo < hi ? lo + unit(rng_) * (hi - lo) : 0.5 * (bounds_.min_m[i] + bounds_.max_m[i]);
    }
    if (!is_free(p, planner_.clearance_radius_m())) continue;
    CandidateSample s;
    s.source = CandidateSource::kFreeSpace;
    s.position_W = p;
    out.push_back(s);
  }
  return out;
}

}  // namespace semexp

// Background occupancy map: the share of the surface observed from <= d (the
// background half of the paper's termination condition, Section IV-D),
// counted per cell by occupancy/surface_counter.cpp.
#include <cmath>

#include "semantic_exploration/core/occupancy_map.hpp"

namespace semexp {

occupancy::SurfaceRule OccupancyMap::surfaceRule(double d_m) const {
  occupancy::SurfaceRule rule;
  // Distances are stored in whole mm, rounded (see the integrator): compare in mm.
  rule.d_mm = std::floor(d_m * 1000.0 + 0.5);
  // Only a margin wider than the surface's front leaves a gap in front of the surface.
  rule.gap_q_per_m =
      cfg_.free_margin_quadratic_per_m > cfg_.surface_front_quadratic_per_m ? cfg_.free_margin_quadratic_per_m : 0.0;
  return rule;
}

occupancy::SurfaceRule OccupancyMap::surfaceMarkingRule() const {
  return surfaceRule(0.0);  // marking needs the rule's reach only, which does not depend on d
}

namespace {
OccupancyMap::SurfaceObservation observation(const occupancy::SurfaceTotals& t) {
  OccupancyMap::SurfaceObservation out;
  out.occupied_voxels = t.occupied;
  out.within_voxels = t.within;
  return out;
}
}  // namespace

OccupancyMap::SurfaceObservation OccupancyMap::surfaceObservedWithin(double d_m) const {
  return observation(occupancy::countSurfaceAll(store_, surfaceRule(d_m)));
}

OccupancyMap::SurfaceObservation OccupancyMap::trackSurfaceObservedWithin(double d_m) {
  return observation(surface_counter_.update(store_, surfaceRule(d_m)));
}

}  // namespace semexp

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

OccupancyMap::SurfaceObservation OccupancyMap::surfaceObservedWithin(double d_m) const {
  const occupancy::SurfaceRule rule = surfaceRule(d_m);
  SurfaceObservation out;
  for (int cell = 0; cell < static_cast<int>(store_.cellCount()); ++cell) {
    const occupancy::SurfaceCount c = occupancy::countSurface(store_, cell, rule);
    out.occupied_voxels += c.occupied;
    out.within_voxels += c.within;
  }
  return out;
}

OccupancyMap::SurfaceObservation OccupancyMap::trackSurfaceObservedWithin(double d_m) {
  const occupancy::SurfaceTotals t = surface_counter_.update(store_, surfaceRule(d_m));
  SurfaceObservation out;
  out.occupied_voxels = t.occupied;
  out.within_voxels = t.within;
  return out;
}

}  // namespace semexp

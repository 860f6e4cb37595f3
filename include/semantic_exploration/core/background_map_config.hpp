#pragma once
/// @file background_map_config.hpp
/// Settings of the background occupancy map (paper Section IV-A).

#include <cmath>
#include <string>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

struct BackgroundMapConfig {
  double resolution_m = 0.04;      ///< finest voxel edge, m (Table I r)
  int block_size = 8;              ///< voxels per dense block edge (power of two)
  double log_odds_free = -0.4;     ///< log-odds added to voxels in front of the surface
  double log_odds_occupied = 0.85; ///< log-odds added to voxels in the surface band
  double log_odds_min = -2.0;      ///< clamping minimum (free)
  double log_odds_max = 3.5;       ///< clamping maximum (occupied)
  double surface_band_m = 0.02;    ///< occupied band behind the measured depth (besides the voxel holding the endpoint), m
  bool integrate_colour = true;    ///< fuse colour into leaves
  bool integrate_min_distance = true;  ///< keep the minimum distance each leaf was observed from (needed by Eq. 1)
  double surface_front_m = 0.0;    ///< voxels whose centre lies less than this in front of the measured depth count as surface (occupied), not free, m
  double surface_front_quadratic_per_m = 0.0;  ///< noise-aware margin: the surface starts max(surface_front_m, this * d^2) in front of depth d, 1/m (e.g. 2 x the sensor's s of sigma = s d^2)
  /// Free-space carving stops max(surface_front_m, this * d^2) in front of
  /// depth d, 1/m; voxels between there and the surface are left as they are
  /// (neither free nor occupied). With the sensor's sigma = s d^2, 3 s keeps a
  /// depth measured up to three sigma behind a thin wall from carving free
  /// space through it (3 s = 0.006 for the paper's Table I sensor). Without it,
  /// far returns carve free space through 10 cm walls and leave frontiers
  /// and surface outside the house (docs/BENCHMARKS.md "Termination");
  /// surfaceObservedWithin counts a surface across the gap it leaves. Not
  /// above surface_front_quadratic_per_m: no gap; 0: off.
  double free_margin_quadratic_per_m = 0.006;
  double publish_period_s = 1.0;   ///< minimum period between ~occupied point clouds, s
  int integration_threads = 2;     ///< threads that integrate a frame, the caller's included (same map for any count)
  int gain_threads = 2;            ///< threads that compute one gain request's positions, the caller's included (same gains for any count)

  void validate(const std::string& ns = "background_map/") const {
    require(std::isfinite(resolution_m) && resolution_m > 0, ns + "resolution_m", "must be > 0 m");
    require(block_size >= 2 && block_size <= 64 && (block_size & (block_size - 1)) == 0, ns + "block_size",
            "must be a power of two in [2, 64]");
    require(log_odds_free < 0, ns + "log_odds_free", "must be < 0");
    require(log_odds_occupied > 0, ns + "log_odds_occupied", "must be > 0");
    require(log_odds_min < 0, ns + "log_odds_min", "must be < 0");
    require(log_odds_max > 0, ns + "log_odds_max", "must be > 0");
    require(surface_band_m > 0, ns + "surface_band_m", "must be > 0 m");
    require(std::isfinite(surface_front_m) && surface_front_m >= 0, ns + "surface_front_m", "must be >= 0 m");
    require(std::isfinite(surface_front_quadratic_per_m) && surface_front_quadratic_per_m >= 0,
            ns + "surface_front_quadratic_per_m", "must be >= 0 1/m");
    require(std::isfinite(free_margin_quadratic_per_m) && free_margin_quadratic_per_m >= 0,
            ns + "free_margin_quadratic_per_m", "must be >= 0 1/m");
    require(log_odds_min > -30 && log_odds_max < 30 && log_odds_free > -30 && log_odds_occupied < 30,
            ns + "log_odds_min", "log-odds parameters must lie in (-30, 30)");
    require(publish_period_s >= 0, ns + "publish_period_s", "must be >= 0 s");
    require(integration_threads >= 1 && integration_threads <= 64, ns + "integration_threads", "must be in [1, 64]");
    require(gain_threads >= 1 && gain_threads <= 64, ns + "gain_threads", "must be in [1, 64]");
  }
};

}  // namespace semexp

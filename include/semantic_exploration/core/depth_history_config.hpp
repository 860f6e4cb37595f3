#pragma once
/// @file depth_history_config.hpp
/// Settings of the invalid-depth history (paper Section IV-C).

#include <cmath>
#include <string>

#include "semantic_exploration/core/config_error.hpp"
#include "semantic_exploration/core/spherical_grid.hpp"

namespace semexp {

struct DepthHistoryConfig {
  double cell_size_m = 0.5;  ///< grid cell edge, m
  int width = 36;            ///< 360-degree image width (azimuth samples)
  int height = 10;           ///< image height (elevation samples)

  void validate(const std::string& ns = "depth_history/") const {
    require(std::isfinite(cell_size_m) && cell_size_m > 0, ns + "cell_size_m", "must be > 0 m");
    require(width > 0, ns + "width", "must be > 0");
    require(height > 0, ns + "height", "must be > 0");
    require(SphericalGrid::checkRequest(1, width, height).empty(), ns + "width",
            SphericalGrid::checkRequest(1, width, height));
  }
};

}  // namespace semexp

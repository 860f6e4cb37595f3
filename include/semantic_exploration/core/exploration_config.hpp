#pragma once
/// @file exploration_config.hpp
/// Settings shared by the maps and the planner (paper Table I).

#include <cmath>
#include <string>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

struct ExplorationConfig {
  double d_bg_m = 3.0;   ///< desired observation distance of the background, m
  double d_obj_m = 1.0;  ///< desired observation distance of objects, m (< d_bg_m)

  void validate(const std::string& ns = "exploration/") const {
    require(std::isfinite(d_bg_m) && d_bg_m > 0, ns + "d_bg_m", "must be > 0 m");
    require(std::isfinite(d_obj_m) && d_obj_m > 0, ns + "d_obj_m", "must be > 0 m");
    require(d_obj_m < d_bg_m, ns + "d_obj_m", "must be < d_bg_m (objects are observed closer than the background)");
  }
};

}  // namespace semexp

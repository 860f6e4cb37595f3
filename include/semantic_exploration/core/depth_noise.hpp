#pragma once
/// @file depth_noise.hpp
/// Depth noise of the camera (paper Table I: sigma_min, sigma_max, s), the
/// model the simulator draws its noise from: the standard deviation of one
/// depth measurement at depth d is max(sigma_min, min(s d^2, sigma_max)).

#include <algorithm>
#include <cmath>
#include <string>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

struct DepthNoise {
  double sigma_min_m = 0.005;  ///< noise floor, m (Table I)
  double s_per_m = 0.002;      ///< quadratic growth: s d^2, 1/m (Table I s)
  double sigma_max_m = 0.2;    ///< cap, m (Table I)

  /// Standard deviation of a depth measured at d_m, m; sigma_max_m for a
  /// depth that is not finite (no distance recorded).
  double sigma(double d_m) const {
    if (!std::isfinite(d_m)) return sigma_max_m;
    return std::max(sigma_min_m, std::min(s_per_m * d_m * d_m, sigma_max_m));
  }

  /// ns: the parameters' prefix, e.g. "object_map/depth_noise/".
  void validate(const std::string& ns) const {
    require(std::isfinite(sigma_min_m) && sigma_min_m > 0, ns + "sigma_min_m", "must be > 0 m");
    require(std::isfinite(s_per_m) && s_per_m >= 0, ns + "s_per_m", "must be >= 0 1/m");
    require(std::isfinite(sigma_max_m) && sigma_max_m >= sigma_min_m, ns + "sigma_max_m", "must be >= sigma_min_m");
  }
};

}  // namespace semexp

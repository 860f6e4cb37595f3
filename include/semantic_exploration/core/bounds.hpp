#pragma once
/// @file bounds.hpp
/// Axis-aligned box of the world that is mapped and explored.

#include <Eigen/Core>
#include <cmath>
#include <string>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

/// Mapping/exploration bounds in the world frame, m.
struct Bounds {
  Eigen::Vector3d min_m{-10.0, -10.0, -0.5};  ///< lower corner, m
  Eigen::Vector3d max_m{10.0, 10.0, 3.5};     ///< upper corner, m

  void validate(const std::string& ns = "bounds/") const {
    for (int i = 0; i < 3; ++i) {
      require(std::isfinite(min_m[i]), ns + "min_m", "must be finite");
      require(std::isfinite(max_m[i]), ns + "max_m", "must be finite");
      require(max_m[i] > min_m[i], ns + "max_m", "must be > min_m on every axis");
    }
  }

  bool contains(const Eigen::Vector3d& p_W) const {
    return (p_W.array() >= min_m.array()).all() && (p_W.array() <= max_m.array()).all();
  }
  Eigen::Vector3d size_m() const { return max_m - min_m; }
};

}  // namespace semexp

#pragma once
/// @file spherical_grid.hpp
/// The layout of every 360-degree image (gain images, history masks).
///
/// Column u has world azimuth (about +z, from +x) -pi + 2 pi (u + 0.5) / width;
/// row v has elevation vfov/2 - vfov (v + 0.5) / height (row 0 looks up),
/// vfov being the camera's vertical field of view. Rays above or below that
/// band belong to no pixel.

#include <Eigen/Core>
#include <cmath>
#include <string>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

struct SphericalGrid {
  int width = 36;             ///< azimuth samples
  int height = 10;            ///< elevation samples
  double vfov_rad = 0.8575;   ///< vertical extent, rad (camera vfov; 2 atan(120 / 262.5) by default)

  /// Largest batch of 360-degree images a node computes on request
  /// (compute_gains, get_masks). Such a call runs on the node's only thread:
  /// integration waits meanwhile, and the lockstep simulator with it. The
  /// planner asks for n_candidates x raycast_width x raycast_height = 20 x 36
  /// x 10 = 7200 rays (about 10 ms); the ray cap is 36 times that.
  static constexpr long kMaxPixels = 360L * 180L;      ///< width * height of one image, px (1 degree steps)
  static constexpr long kMaxPositions = 1024;          ///< positions per request
  static constexpr long kMaxRays = 1L << 18;           ///< positions * width * height per request (262144)

  /// "" if `positions` images of width x height stay within the limits
  /// above (and width, height > 0), else which limit the request breaks.
  static std::string checkRequest(long positions, long width, long height) {
    if (width <= 0 || height <= 0) return "width and height must be > 0";
    if (width * height > kMaxPixels)
      return std::to_string(width) + " x " + std::to_string(height) + " px per image is over the limit of " +
             std::to_string(kMaxPixels) + " px (SphericalGrid::kMaxPixels)";
    if (positions > kMaxPositions)
      return std::to_string(positions) + " positions are over the limit of " + std::to_string(kMaxPositions) +
             " per request (SphericalGrid::kMaxPositions)";
    if (positions * width * height > kMaxRays)
      return std::to_string(positions) + " positions x " + std::to_string(width * height) + " px = " +
             std::to_string(positions * width * height) + " rays are over the limit of " + std::to_string(kMaxRays) +
             " per request (SphericalGrid::kMaxRays)";
    return "";
  }

  void validate(const std::string& ns) const {
    require(width > 0, ns + "width", "must be > 0");
    require(height > 0, ns + "height", "must be > 0");
    require(vfov_rad > 0 && vfov_rad < M_PI, ns + "vfov_rad", "must be in (0, pi)");
  }

  double azimuth(int u) const { return -M_PI + 2.0 * M_PI * (u + 0.5) / width; }
  double elevation(int v) const { return 0.5 * vfov_rad - vfov_rad * (v + 0.5) / height; }

  /// Unit direction of pixel (u, v) in the world frame.
  Eigen::Vector3d direction(int u, int v) const {
    const double az = azimuth(u), el = elevation(v);
    return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  }

  /// Pixel holding world direction d (any length > 0). False if the
  /// direction's elevation is outside the band.
  bool pixel(const Eigen::Vector3d& d, int& u, int& v) const {
    const double az = std::atan2(d.y(), d.x());
    const double el = std::atan2(d.z(), std::hypot(d.x(), d.y()));
    const double fv = (0.5 * vfov_rad - el) / vfov_rad * height;
    if (fv < 0.0 || fv >= height) return false;
    v = static_cast<int>(fv);
    u = static_cast<int>(std::floor((az + M_PI) / (2.0 * M_PI) * width));
    if (u >= width) u -= width;  // az == pi is az == -pi: column 0
    if (u < 0) u += width;
    return true;
  }
};

}  // namespace semexp

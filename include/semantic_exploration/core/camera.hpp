#pragma once
/// @file camera.hpp
/// Pinhole depth camera model (optical frame: z forward, x right, y down).

#include <Eigen/Core>
#include <cmath>
#include <string>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

/// Intrinsics and valid depth range of the RGB-D camera. Defaults: paper Table I.
struct PinholeCamera {
  int width = 320;         ///< image width, px
  int height = 240;        ///< image height, px
  double fx = 262.5;       ///< focal length x, px
  double fy = 262.5;       ///< focal length y, px
  double cx = 159.5;       ///< principal point x, px
  double cy = 119.5;       ///< principal point y, px
  double d_min_m = 0.1;    ///< nearest valid depth, m
  double d_max_m = 10.0;   ///< farthest valid depth, m

  /// Largest accepted image: nodes allocate per-pixel buffers (rays, empty
  /// instance images) from width x height before any depth frame confirms
  /// it, so a camera_info of 100000 x 100000 px must not get that far.
  static constexpr int kMaxSidePx = 8192;                ///< width and height, px
  static constexpr long kMaxPixels = 4096L * 4096L;      ///< width * height, px (16.8 Mpx)

  /// "" if an image of width x height px (both > 0) is within the caps above, else which cap it breaks.
  static std::string checkSize(long width_px, long height_px) {
    if (width_px > kMaxSidePx || height_px > kMaxSidePx)
      return "must be <= " + std::to_string(kMaxSidePx) + " px a side (PinholeCamera::kMaxSidePx), got " +
             std::to_string(width_px) + " x " + std::to_string(height_px);
    if (width_px * height_px > kMaxPixels)
      return "width x height must be <= " + std::to_string(kMaxPixels) + " px (PinholeCamera::kMaxPixels), got " +
             std::to_string(width_px) + " x " + std::to_string(height_px);
    return "";
  }

  /// Throws ConfigError naming the first bad field (prefixed with `ns`).
  void validate(const std::string& ns = "camera/") const {
    require(width > 0, ns + "width", "must be > 0 (missing intrinsics?)");
    require(height > 0, ns + "height", "must be > 0 (missing intrinsics?)");
    const std::string size = checkSize(width, height);
    require(size.empty(), ns + (width > kMaxSidePx || height <= kMaxSidePx ? "width" : "height"), size);
    require(std::isfinite(fx) && fx > 0, ns + "fx", "must be a finite focal length > 0 px");
    require(std::isfinite(fy) && fy > 0, ns + "fy", "must be a finite focal length > 0 px");
    require(std::isfinite(cx) && cx >= 0 && cx < width, ns + "cx", "must lie inside the image");
    require(std::isfinite(cy) && cy >= 0 && cy < height, ns + "cy", "must lie inside the image");
    require(std::isfinite(d_min_m) && d_min_m >= 0, ns + "d_min_m", "must be >= 0 m");
    require(std::isfinite(d_max_m) && d_max_m > d_min_m, ns + "d_max_m", "must be > d_min_m");
  }

  /// Ray direction (not normalised, z = 1) through pixel centre (u, v).
  Eigen::Vector3f ray_C(float u, float v) const {
    return {static_cast<float>((u - cx) / fx), static_cast<float>((v - cy) / fy), 1.f};
  }

  /// Projects a camera-frame point; returns false if behind the camera.
  bool project(const Eigen::Vector3f& p_C, Eigen::Vector2f& uv) const {
    if (p_C.z() <= 0.f) return false;
    uv = {static_cast<float>(fx * p_C.x() / p_C.z() + cx), static_cast<float>(fy * p_C.y() / p_C.z() + cy)};
    return true;
  }

  /// Vertical field of view, rad.
  double vfov_rad() const { return 2.0 * std::atan(0.5 * height / fy); }
  /// Horizontal field of view, rad.
  double hfov_rad() const { return 2.0 * std::atan(0.5 * width / fx); }
};

}  // namespace semexp

#pragma once
/// @file depth_history.hpp
/// Invalid-depth history (paper Section IV-C, DESIGN Section 4).
///
/// A grid of cubic cells over the bounds; each cell holds a binary 360-degree
/// image in the SphericalGrid layout (1 = valid, 0 = invalid depth was seen in
/// that world direction from inside the cell). Cells start all valid and are
/// allocated only when the first invalid pixel lands in them, so memory grows
/// with the visited cells, not with the bounds.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "semantic_exploration/core/bounds.hpp"
#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/depth_history_config.hpp"
#include "semantic_exploration/core/spherical_grid.hpp"

namespace semexp {

/// True if a depth value (m) is a valid measurement of `camera`: finite and
/// inside [d_min_m, d_max_m]. 0 and negative values are invalid.
inline bool is_valid_depth(float depth_m, const PinholeCamera& camera) {
  return std::isfinite(depth_m) && depth_m > 0.f && depth_m >= camera.d_min_m && depth_m <= camera.d_max_m;
}

class DepthHistory {
 public:
  /// One cell that holds at least one invalid direction (for markers).
  struct InvalidCell {
    Eigen::Vector3d center_W;  ///< cell centre in world, m
    int invalid_pixels = 0;    ///< number of 0 pixels in the cell's image
  };

  /// The image layout is config.width x config.height with the camera's
  /// vertical field of view. Throws ConfigError on bad settings.
  DepthHistory(const DepthHistoryConfig& config, const Bounds& bounds, const PinholeCamera& camera);

  const SphericalGrid& grid() const { return grid_; }
  const DepthHistoryConfig& config() const { return config_; }

  /// Marks the world direction of every invalid pixel of `depth` in the cell
  /// holding the camera position. `depth` is CV_32FC1 in metres or CV_16UC1 in
  /// millimetres, of the camera's size; T_WC is the optical camera frame in
  /// world. Returns the number of invalid pixels seen (0 if the camera is
  /// outside the bounds, in which case nothing is marked). Throws
  /// std::invalid_argument on a wrong type or size.
  std::size_t integrate(const cv::Mat& depth, const Eigen::Isometry3d& T_WC);

  /// Mask (width * height, row-major, 1 = valid) of the cell holding p_W;
  /// all ones outside the bounds or where nothing invalid was seen.
  std::vector<std::uint8_t> mask(const Eigen::Vector3d& p_W) const;
  /// mask() for a batch of positions.
  std::vector<std::vector<std::uint8_t>> masks(const std::vector<Eigen::Vector3d>& positions_W) const;

  /// All cells holding at least one invalid direction.
  std::vector<InvalidCell> invalid_cells() const;

  /// Index of the cell holding p_W; false outside the bounds.
  bool cell_index(const Eigen::Vector3d& p_W, Eigen::Vector3i& index) const;
  /// Centre of cell `index`, m.
  Eigen::Vector3d cell_center(const Eigen::Vector3i& index) const;

 private:
  std::int64_t key(const Eigen::Vector3i& index) const;
  Eigen::Vector3i unkey(std::int64_t key) const;

  DepthHistoryConfig config_;
  Bounds bounds_;
  PinholeCamera camera_;
  SphericalGrid grid_;
  Eigen::Vector3i cells_;                       ///< cells per axis
  std::vector<Eigen::Vector3d> rays_C_;         ///< unit ray per depth pixel, camera frame
  std::unordered_map<std::int64_t, std::vector<std::uint8_t>> images_;  ///< allocated cells only
};

}  // namespace semexp

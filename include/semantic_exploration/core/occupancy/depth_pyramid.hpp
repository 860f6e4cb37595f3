#pragma once
/// @file depth_pyramid.hpp
/// Min/max pyramid of one depth frame (internal to the occupancy map's
/// integrator): bounds the measured depth over any pixel rectangle in a few
/// reads, so the integrator can free or skip whole octree nodes.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace semexp {
namespace occupancy {

class DepthPyramid {
 public:
  /// Validates `depth_m` (W x H row-major, m) and builds the pyramid. A pixel
  /// is valid when d > 0 and d in [d_min_m, d_max_m] (NaN and inf are not).
  /// Per valid pixel the free limit is max(0, d - max(front_m, quad_per_m d^2)):
  /// voxels nearer than it are carved free. Returns the invalid pixel count.
  std::size_t build(const float* depth_m, int W, int H, float d_min_m, float d_max_m, float front_m,
                    float quad_per_m);

  /// Over the pixel rectangle [u0, u1] x [v0, v1] (inclusive, inside the
  /// image): `mn` = min free limit (0 if any pixel is invalid) and `mx` = max
  /// depth (0 if no pixel is valid), m. Reads the finest level where the
  /// rectangle spans at most 4 x 4 nodes, so the bounds may be looser than
  /// the rectangle's own (min lower, max higher), never tighter.
  void query(int u0, int u1, int v0, int v1, float& mn, float& mx) const;

  int width() const { return dims_.empty() ? 0 : dims_[0].x(); }
  int height() const { return dims_.empty() ? 0 : dims_[0].y(); }
  const float* depth() const { return depth_.data(); }      ///< validated depth, 0 = invalid, m
  const float* freeLimit() const { return free_.data(); }   ///< free limit per pixel, 0 = invalid, m
  std::size_t levelCount() const { return dims_.size(); }
  const Eigen::Vector2i& levelDims(std::size_t j) const { return dims_[j]; }
  /// Node (u, v) of level j >= 1: min free limit / max depth of its 2^j x 2^j pixels.
  float levelMin(std::size_t j, int u, int v) const { return min_[j][v * dims_[j].x() + u]; }
  float levelMax(std::size_t j, int u, int v) const { return max_[j][v * dims_[j].x() + u]; }
  std::size_t memoryBytes() const;

 private:
  std::vector<float> depth_, free_;           ///< level 0 (serves both min and max)
  std::vector<std::vector<float>> min_, max_;  ///< levels >= 1 (index 0 unused)
  std::vector<Eigen::Vector2i> dims_;
};

}  // namespace occupancy
}  // namespace semexp

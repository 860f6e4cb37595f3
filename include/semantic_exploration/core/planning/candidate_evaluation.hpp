#pragma once
/// @file candidate_evaluation.hpp
/// Candidate evaluation (paper Section IV-D.4, DESIGN Section 5 steps 4-5):
/// combined gain image (Eq. 2), sliding-window yaw and utility.
///
/// Every image here is width x height, row-major, in the SphericalGrid layout
/// (column u has azimuth -pi + 2 pi (u + 0.5) / width).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "semantic_exploration/core/spherical_grid.hpp"

namespace semexp {

struct ObjectSummary;  // planning/interfaces.hpp (which includes this header)

/// A 360-degree image of floats (gains in [0, 1]). Empty (no values) means
/// "no such gain" and counts as all zeros.
struct GainImage {
  int width = 0;
  int height = 0;
  std::vector<float> values;  ///< width * height, row-major

  GainImage() = default;
  GainImage(int w, int h, float fill = 0.f)
      : width(w), height(h), values(static_cast<std::size_t>(w) * h, fill) {}
  bool empty() const { return values.empty(); }
  float& at(int u, int v) { return values[static_cast<std::size_t>(v) * width + u]; }
  float at(int u, int v) const { return values[static_cast<std::size_t>(v) * width + u]; }
};

/// The three gain images of one position (DESIGN Section 5 step 3).
struct GainSet {
  GainImage entropy;     ///< G_ent
  GainImage background;  ///< G_bg
  GainImage object;      ///< G_obj
};

/// Weights of Eq. 2.
struct GainWeights {
  double a_ent = 0.34;
  double a_bg = 0.33;
  double a_obj = 0.33;
};

/// G = (a_ent G_ent + a_bg G_bg + a_obj G_obj) o H (Eq. 2). Empty gain images
/// count as zeros; an empty mask as all ones; mask values are 0 or non-zero.
/// Throws std::invalid_argument if the non-empty inputs disagree in size or
/// no input gives the size (width, height) when they are all empty.
GainImage combineGains(const GainWeights& weights, const GainSet& gains, const std::vector<std::uint8_t>& mask,
                        int width, int height);

/// Per-ray depth limits (m) for the object raycast from the background map's
/// per-ray hit depths (m, the distance at which each ray enters its first
/// occupied voxel). Objects are in the background map too, and the surface in
/// the hit voxel can lie up to the voxel's diagonal sqrt(3) r behind the entry
/// point: cut at the entry itself, the object ray stops just short of the very
/// object that the background ray hit and every object gain is 0. Each limit is
/// therefore the hit depth plus 2 r (the diagonal plus slack for the object
/// TSDF's interpolated zero crossing); non-finite depths stay as they are.
/// Throws std::invalid_argument if background_resolution_m is not > 0.
std::vector<float> objectOcclusionDepths_m(const std::vector<float>& background_hit_depth_m,
                                             double background_resolution_m);

/// objectOcclusionDepths_m for the rays of one position, also letting a ray
/// through an object's own voxels in the background map: where the limit falls
/// inside an object's bounding box (grown by 2 background voxels), it moves on
/// to where the ray leaves that box, plus the same margin. The object map's
/// first surface on a ray can lie behind the background's (a thin chair part
/// that its TSDF does not hold as foreground: ~14 cm median behind in a
/// generated house), so the first-voxel margin alone hid most of a chair seen
/// from close by. Occluders outside every object box still hide objects.
/// `background_hit_depth_m`: grid.width * grid.height values, row-major.
/// Throws std::invalid_argument on a size mismatch or resolution <= 0.
std::vector<float> objectRayLimits_m(const Eigen::Vector3d& position_W, const SphericalGrid& grid,
                                       const std::vector<float>& background_hit_depth_m,
                                       double background_resolution_m, const std::vector<ObjectSummary>& objects);

/// objectRayLimits_m for a batch of positions, concatenated in position
/// order (the layout of ComputeGains.max_depth_m): the request that chains
/// the object raycast to the background's. `hit_depths_m` holds one image per
/// position. Returns an empty vector (no occlusion limits) if any of them is
/// empty, i.e. the background map did not report hit depths.
/// Throws std::invalid_argument if the counts or image sizes disagree.
std::vector<float> objectRayLimitsBatch(const std::vector<Eigen::Vector3d>& positions_W, const SphericalGrid& grid,
                                        const std::vector<GainImage>& hit_depths_m, double background_resolution_m,
                                        const std::vector<ObjectSummary>& objects);

/// Result of the sliding window over a 360-degree image.
struct YawWindow {
  double yaw_rad = 0.0;  ///< azimuth of the window centre, world frame, (-pi, pi]
  double gain = 0.0;     ///< mean of the image over the window
  int first_column = 0;  ///< leftmost (lowest azimuth) column of the window
  int columns = 1;       ///< window width in columns
};

/// Window width in columns for a horizontal field of view: round(hfov / 2 pi
/// * width), clamped to [1, width].
int windowColumns(double hfov_rad, int width);

/// Slides a window `columns` wide (all rows) around the image, wrapping
/// across the +-pi seam, and returns the one with the highest mean (the
/// lowest first column among equal means). Throws std::invalid_argument on
/// an empty image.
YawWindow bestYaw(const GainImage& image, int columns);

/// Mean of `image` over the window (first_column, columns) with wrap-around;
/// 0 for an empty image. Used to report the component gains at the chosen yaw.
double windowMean(const GainImage& image, int first_column, int columns);

/// Length of a polyline, m.
double pathLength_m(const std::vector<Eigen::Vector3d>& path_W);

/// Smallest absolute angle between two yaws, rad in [0, pi].
double yawDifference_rad(double a_rad, double b_rad);

/// Time to fly `path_W` at v_max_mps while turning from yaw_start_rad to
/// yaw_end_rad at omega_max_radps. Translation and rotation happen at the
/// same time, so t = max(length / v_max, |dyaw| / omega_max).
double pathTime_s(const std::vector<Eigen::Vector3d>& path_W, double yaw_start_rad, double yaw_end_rad,
                   double v_max_mps, double omega_max_radps);

/// u = g / max(t, t_min): the floor keeps a candidate at the current pose
/// from getting an unbounded utility.
double utility(double gain, double time_s, double min_time_s);

}  // namespace semexp

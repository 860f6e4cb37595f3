#pragma once
/// @file mesh_gate.hpp
/// Which voxels of an object TSDF its mesh is extracted over.

#include "semantic_exploration/core/depth_noise.hpp"

namespace semexp {

/// Which voxels a mesh is extracted over (TsdfMapT::extractMesh): every one
/// of a marching cube's 8 voxels must pass, and their mean foreground
/// probability must exceed min_foreground.
struct MeshGate {
  /// The mean foreground probability of a cube's 8 voxels must exceed this,
  /// [0.5, 1). 0.5 is the paper's extraction (the object's surface is where
  /// foreground > 0.5). A higher bound leaves out surface that a detection
  /// lifted only just over 0.5: a mask bled onto a wall or floor seen once
  /// or twice, where the object's own surface is confirmed by many.
  float min_foreground = 0.5f;
  /// Least weight of a voxel, in full-weight observations (more than 0 is
  /// always needed: the voxel was observed).
  float min_weight = 0.f;
  /// Largest standard error of a voxel's fused SDF, m, as estimated from
  /// sigma(d) / sqrt(w): w its weight and sigma(d) the depth noise at the
  /// nearest distance d the voxel was seen from within the truncation band
  /// (the least noisy of its observations, so the estimate is a lower bound
  /// for a voxel also seen from farther; a voxel seen only as free space
  /// beyond the band has no such distance and takes sigma_max). The weight
  /// a voxel needs grows with the square of the noise: a sensor twice as
  /// noisy needs four times the observations for the same error. 0 = off.
  double max_sdf_std_m = 0.0;
  DepthNoise noise;  ///< the camera's depth noise, for max_sdf_std_m

  /// Whether a voxel of this weight and nearest observation distance (m, inf
  /// if none) passes.
  bool passes(float weight, float min_distance_m) const {
    if (!(weight > 0.f) || weight < min_weight) return false;
    if (max_sdf_std_m <= 0.0) return true;
    // w >= (sigma / e)^2, with a relative tolerance: a weight on the bound (one full view of a voxel at the
    // noise floor with e = sigma_min) passes whatever the rounding of the three factors.
    const double s = noise.sigma(min_distance_m), e = max_sdf_std_m;
    return static_cast<double>(weight) * (e * e) >= (s * s) * (1.0 - 1e-9);
  }
};

}  // namespace semexp

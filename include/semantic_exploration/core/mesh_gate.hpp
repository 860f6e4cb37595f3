#pragma once
/// @file mesh_gate.hpp
/// Which voxels of an object TSDF its mesh is extracted over.

#include "semantic_exploration/core/depth_noise.hpp"

namespace semexp {

/// Which voxels a mesh is extracted over (TsdfMapT::extractMesh): every one
/// of a marching cube's 8 voxels must pass.
struct MeshGate {
  /// Least weight of a voxel, in full-weight observations (more than 0 is
  /// always needed: the voxel was observed).
  float min_weight = 0.f;
  /// Largest standard error of a voxel's fused SDF, m: sigma(d) / sqrt(w),
  /// with w its weight and sigma(d) the depth noise at the nearest distance
  /// the voxel was observed from (the least noisy of its observations, so
  /// this under-estimates the error of a voxel also seen from farther). The
  /// weight a voxel needs grows with the square of the noise: a sensor twice
  /// as noisy needs four times the observations for the same error. 0 = off.
  float max_sdf_std_m = 0.f;
  DepthNoise noise;  ///< the camera's depth noise, for max_sdf_std_m

  /// Whether a voxel of this weight and nearest observation distance (m, inf
  /// if none) passes.
  bool passes(float weight, float min_distance_m) const {
    if (!(weight > 0.f) || weight < min_weight) return false;
    if (max_sdf_std_m <= 0.f) return true;
    const double s = noise.sigma(min_distance_m), e = max_sdf_std_m;
    return s * s <= e * e * static_cast<double>(weight);
  }
};

}  // namespace semexp

#pragma once
/// @file frontier_evidence.hpp
/// Frontier voxels that the camera has looked at from close by, several
/// times and from different poses, without resolving them are retired: they
/// border space no ray of this sensor reaches (the inside of a wall behind a
/// surface voxel that depth noise carved free, the space behind a window or
/// mirror, which return no depth). Paper Section III calls it V_unob; a
/// mission that waits for F = {} would wait for it forever.
///
/// A look at a frontier voxel from one depth frame: the voxel's centre lies
/// within view_range_m, in front of the camera beyond d_min, and its whole
/// 3x3x3 neighbourhood projects inside the image (so the unknown neighbour
/// was in the field of view too); the depth at its pixel is either missing
/// (no return: window, mirror, beyond range) or not nearer than the voxel by
/// more than occlusion_margin_m (nothing hid it). Only frames whose camera
/// moved at least min_look_separation_m or turned at least
/// min_look_rotation_rad since the last counted frame count, so the looks
/// come from different poses. looks_to_retire looks retire a voxel. A voxel
/// that stops being a frontier is forgotten.

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <unordered_map>

#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

class OccupancyMap;

struct FrontierEvidenceConfig {
  bool enabled = true;                  ///< false: every frontier stays active
  double view_range_m = 3.0;            ///< farthest look that counts, m (the paper's d_bg: closer than that a ray resolves a voxel)
  int looks_to_retire = 3;              ///< looks from different poses that did not resolve a voxel before it is retired
  double min_look_separation_m = 0.25;  ///< camera travel between frames whose looks count, m
  double min_look_rotation_rad = 0.26;  ///< or camera rotation between them, rad (15 deg)
  double occlusion_margin_m = 0.1;      ///< depth nearer than the voxel by more than this hid it, m

  void validate(const std::string& ns = "frontier_evidence/") const {
    require(std::isfinite(view_range_m) && view_range_m > 0, ns + "view_range_m", "must be > 0 m");
    require(looks_to_retire > 0, ns + "looks_to_retire", "must be > 0");
    require(std::isfinite(min_look_separation_m) && min_look_separation_m >= 0, ns + "min_look_separation_m",
            "must be >= 0 m");
    require(std::isfinite(min_look_rotation_rad) && min_look_rotation_rad >= 0, ns + "min_look_rotation_rad",
            "must be >= 0 rad");
    require(std::isfinite(occlusion_margin_m) && occlusion_margin_m >= 0, ns + "occlusion_margin_m",
            "must be >= 0 m");
  }
};

class FrontierEvidence {
 public:
  /// Throws ConfigError on an invalid config.
  explicit FrontierEvidence(const FrontierEvidenceConfig& config);

  /// Counts the looks of one integrated depth frame (row-major z-depth, m,
  /// camera.width x camera.height; 0 or non-finite = no return) at the map's
  /// current frontiers; call after map.updateFrontiers(). Returns false (and
  /// counts nothing) for a frame too close to the last counted pose.
  bool look(const OccupancyMap& map, const float* depth_m, const PinholeCamera& camera,
            const Eigen::Isometry3d& T_WC);

  /// Whether the frontier leaf centred at p_W (as given by
  /// OccupancyMap::forEachFrontier) is retired.
  bool retired(const Eigen::Vector3d& p_W) const;
  /// Looks counted at the frontier leaf centred at p_W.
  int looks(const Eigen::Vector3d& p_W) const;

  std::size_t retiredCount() const { return retired_; }  ///< retired frontier leaves after the last look()
  std::size_t countedFrames() const { return counted_frames_; }
  const FrontierEvidenceConfig& config() const { return config_; }

 private:
  std::uint64_t key(const Eigen::Vector3d& p_W) const;

  FrontierEvidenceConfig config_;
  double key_resolution_m_ = 0.0;  ///< the map's resolution, set at the first look
  std::unordered_map<std::uint64_t, std::uint8_t> looks_;
  bool have_last_ = false;
  Eigen::Isometry3d last_T_WC_ = Eigen::Isometry3d::Identity();
  std::size_t retired_ = 0;
  std::size_t counted_frames_ = 0;
};

}  // namespace semexp

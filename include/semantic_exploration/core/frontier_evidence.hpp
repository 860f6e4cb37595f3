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
/// more than occlusion_margin_m (nothing hid it). A look counts for a voxel
/// only if the camera centre moved at least min_look_separation_m since that
/// voxel's last counted look, or the ray to the voxel turned by at least
/// min_look_rotation_rad: the looks come from different places, not from
/// one ray seen again. looks_to_retire looks retire a voxel. A voxel that
/// stops being a frontier is forgotten. Coarse frontier leaves (uniform
/// cells larger than a voxel) are never retired: their centre names no
/// voxel of their own. Integration leaves none (free cells next to unknown
/// space stay voxel blocks, OccupancyMap::refreshSummaries); a map loaded
/// from a file saved before that may hold some.

#include <Eigen/Geometry>
#include <cmath>
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
  double min_look_separation_m = 0.25;  ///< camera travel since a voxel's last counted look, m
  double min_look_rotation_rad = 0.26;  ///< or turn of the ray to the voxel since then, rad (15 deg)
  double occlusion_margin_m = 0.1;      ///< depth nearer than the voxel by more than this hid it, m

  void validate(const std::string& ns = "frontier_evidence/") const {
    require(std::isfinite(view_range_m) && view_range_m > 0, ns + "view_range_m", "must be > 0 m");
    require(looks_to_retire > 0 && looks_to_retire <= 255, ns + "looks_to_retire", "must be in [1, 255]");
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
  /// current frontiers and forgets voxels that are no frontier any more; call
  /// after map.updateFrontiers(), with every integrated frame (one hash
  /// lookup per frontier voxel). Returns how many voxels got a look.
  std::size_t look(const OccupancyMap& map, const float* depth_m, const PinholeCamera& camera,
            const Eigen::Isometry3d& T_WC);

  /// Whether the frontier leaf centred at p_W (as given by
  /// OccupancyMap::forEachFrontier) is retired.
  bool retired(const Eigen::Vector3d& p_W) const;
  /// Looks counted at the frontier leaf centred at p_W.
  int looks(const Eigen::Vector3d& p_W) const;

  std::size_t retiredCount() const { return retired_; }  ///< retired frontier voxels at the last look()
  const FrontierEvidenceConfig& config() const { return config_; }

 private:
  std::uint64_t key(const Eigen::Vector3d& p_W) const;
  /// Whether the voxel at p_W is in clear view of the camera at o_W (see the file comment).
  bool sees(const Eigen::Vector3d& p_W, const Eigen::Vector3d& o_W, const Eigen::Isometry3d& T_CW, double r,
            const float* depth_m, const PinholeCamera& camera) const;

  FrontierEvidenceConfig config_;
  double key_resolution_m_ = 0.0;  ///< the map's resolution, set at the first look
  struct Entry {
    std::uint8_t looks = 0;
    Eigen::Vector3f camera_W = Eigen::Vector3f::Zero();  ///< camera centre of the last counted look, m
  };
  std::unordered_map<std::uint64_t, Entry> entries_;
  std::size_t retired_ = 0;
};

}  // namespace semexp

#pragma once
/// @file object_map_config.hpp
/// Settings of the per-object TSDF submaps and instance matching (paper Section IV-B).

#include <cmath>
#include <string>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

struct ObjectMapConfig {
  double truncation_voxels = 4.0;  ///< TSDF truncation distance in voxels of the object's resolution
  double max_weight = 100.0;       ///< TSDF weight cap
  int block_size = 8;              ///< voxels per block edge
  double publish_period_s = 1.0;   ///< minimum period between mesh marker updates, s

  void validate(const std::string& ns = "object_map/") const {
    require(std::isfinite(truncation_voxels) && truncation_voxels >= 1, ns + "truncation_voxels", "must be >= 1");
    require(std::isfinite(max_weight) && max_weight > 0, ns + "max_weight", "must be > 0");
    require(block_size >= 2 && block_size <= 64 && (block_size & (block_size - 1)) == 0, ns + "block_size",
            "must be a power of two in [2, 64]");
    require(publish_period_s >= 0, ns + "publish_period_s", "must be >= 0 s");
  }
};

struct MatchingConfig {
  double iou_threshold = 0.25;  ///< minimum IoU to match a detection to a rendered object
  int min_mask_pixels = 100;    ///< detections with fewer pixels are dropped

  void validate(const std::string& ns = "matching/") const {
    require(std::isfinite(iou_threshold) && iou_threshold > 0 && iou_threshold <= 1, ns + "iou_threshold",
            "must be in (0, 1]");
    require(min_mask_pixels >= 0, ns + "min_mask_pixels", "must be >= 0 px");
  }
};

}  // namespace semexp

#pragma once
/// @file matching_config.hpp
/// Settings of instance matching (paper Section IV-B.1).

#include <cmath>
#include <string>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

struct MatchingConfig {
  double iou_threshold = 0.25;  ///< minimum IoU to match a detection to a rendered object
  int min_mask_pixels = 100;    ///< detections with fewer pixels are dropped
  /// A detection left without a match whose mask lies at least this much
  /// (fraction of its pixels) on rendered objects is a fragment of known
  /// geometry and is matched to the object covering most of it (a detector
  /// split the object, or it competes with a better detection of the same
  /// object). In (0.5, 1].
  double fragment_fraction = 0.8;

  void validate(const std::string& ns = "matching/") const {
    require(std::isfinite(iou_threshold) && iou_threshold > 0 && iou_threshold <= 1, ns + "iou_threshold",
            "must be in (0, 1]");
    require(min_mask_pixels >= 0, ns + "min_mask_pixels", "must be >= 0 px");
    require(std::isfinite(fragment_fraction) && fragment_fraction > 0.5 && fragment_fraction <= 1, ns + "fragment_fraction",
            "must be in (0.5, 1]");
  }
};

}  // namespace semexp

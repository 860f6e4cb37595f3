#pragma once
/// @file instance_matching.hpp
/// Matching of detected instance masks to the known objects rendered from
/// the current pose (paper Section IV-B.1).
///
/// Policy, in this order:
/// 1. Masks with fewer than `min_mask_pixels` pixels are dropped (object id 0,
///    `dropped`); pixels whose instance id is not listed are ignored.
/// 2. IoU of every kept detection with every rendered object.
/// 3. Pairs with IoU >= `iou_threshold` are taken greedily by descending IoU
///    (ties: lower instance id, then lower object id), one detection per
///    object: when two detections compete for one object the higher IoU wins
///    and the other falls back to its next-best free object above the threshold.
/// 4. A detection still unmatched whose mask lies with at least
///    `fragment_fraction` of its pixels on rendered objects is a fragment of
///    known geometry (the detector split the object, it lost the competition
///    for it, or the object is rendered in pieces) and is matched to the
///    object covering most of it (`fragment`), rather than starting a
///    duplicate. Likewise, a known object whose render lies with at least
///    `fragment_fraction` of its pixels inside an unmatched detection (it was
///    seen only in part so far) takes that detection; renders smaller than
///    min_mask_pixels / 4 are too small to tell. Largest overlap wins.
/// 5. Everything else is a new object (object id 0).
/// A detection spanning two objects goes to the one with the higher IoU; the
/// object map then integrates it without the pixels rendered as the other
/// object (ObjectMap::integrateFrame).

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "semantic_exploration/core/matching_config.hpp"

namespace semexp {

/// Outcome for one detection.
struct MatchResult {
  std::uint16_t instance_id = 0;  ///< pixel value of the detection in the instance image
  std::uint32_t object_id = 0;    ///< matched object, 0 = new object (or dropped)
  float iou = 0.f;                ///< IoU with the matched object's rendered mask, 0 when new
  std::uint32_t mask_pixels = 0;  ///< pixels of the detection's mask
  bool dropped = false;           ///< mask smaller than min_mask_pixels
  bool fragment = false;          ///< matched by the fragment rule (policy step 4)
};

struct MatchingOutput {
  std::vector<MatchResult> detections;  ///< one per listed instance id, in input order
  std::uint32_t unlisted_pixels = 0;    ///< pixels with an instance id that is not listed
  std::uint32_t duplicate_ids = 0;      ///< listed instance ids that repeat (or are 0), ignored
};

/// Matches detections to rendered objects.
/// @param instance_image  CV_16UC1 instance id per pixel, 0 = no detection
/// @param instance_ids    the detections' instance ids (as listed in the message)
/// @param object_ids      CV_16UC1 rendered object id per pixel (same size), 0 = none
/// @param cleaned         optional: instance_image with dropped and unlisted pixels set to 0
/// @throws std::invalid_argument if the images differ in size or type
MatchingOutput matchDetections(const cv::Mat& instance_image, const std::vector<std::uint16_t>& instance_ids,
                               const cv::Mat& object_ids, const MatchingConfig& config, cv::Mat* cleaned = nullptr);

}  // namespace semexp

#pragma once
/// @file object_masks.hpp
/// Detection masks made fit for object integration: a mask that bleeds over
/// an object's border onto a surface far behind it (a wall behind a chair)
/// must neither fill the object with that surface nor carve it.

#include <Eigen/Core>
#include <cmath>
#include <opencv2/core.hpp>

#include "semantic_exploration/core/camera.hpp"

namespace semexp {

/// Settings of markDepthEdges.
struct DepthEdgeParams {
  /// A mask pixel whose depth lies more than edge_m + edge_rel * d behind the
  /// nearest depth d of the mask within window_px pixels is behind a depth
  /// edge: the mask bled past the object there. 0 window = off.
  double edge_m = 0.3;     ///< m
  double edge_rel = 0.05;  ///< fraction of the nearer depth
  int window_px = 8;       ///< px, at least the width a mask bleeds by
};

/// Sets the pixels of `mask` (CV_8UC1: 0 outside, any other value inside)
/// that lie behind a depth edge within the mask (see DepthEdgeParams) to
/// `unknown_value`. Depths are compared after a 5 x 5 median of the mask's
/// valid depths, so depth noise alone does not make an edge.
/// @param depth_m CV_32FC1 m, the mask's size; invalid depth (0, NaN,
///        outside [d_min_m, d_max_m]) is never behind an edge
/// @return pixels set to unknown_value
/// @throws std::invalid_argument if the images do not match
int markDepthEdges(cv::Mat& mask, const cv::Mat& depth_m, const PinholeCamera& camera, const DepthEdgeParams& params,
                   std::uint8_t unknown_value);

/// Lowers the foreground evidence of a detection's border, where masks bleed
/// (TsdfMap::integrate's mask values): a pixel of `mask` of value 255 that
/// lies k <= border_px pixels (chessboard distance, 1 = on the border) inside
/// `detected` gets 128 + round(127 k / (border_px + 1)), the foreground
/// evidence 0.5 + 0.5 k / (border_px + 1). Outside the image counts as inside
/// (a mask cut by the image border did not bleed there). 0 px = off.
/// @param detected CV_8UC1, the detection's mask as the detector gave it (non-zero inside)
/// @return pixels changed
/// @throws std::invalid_argument if the images differ in size or type, or border_px is not in [0, 126]
int markMaskBorder(cv::Mat& mask, const cv::Mat& detected, int border_px);

/// How the surfaces two masks see lie apart (camera frame).
struct MaskSeparation {
  /// Along the line joining the centroids of the masks' 3D points, the gap
  /// between the farthest point of a and the nearest of b, m, with the 2% of
  /// each set nearest the other ignored (depth noise, stray pixels). Negative
  /// if they overlap (two parts of one object do); NaN if either mask has
  /// fewer than 20 pixels with valid depth.
  double gap_m = std::nan("");
  Eigen::Vector3f normal_C = Eigen::Vector3f::Zero();  ///< unit, from a's centroid towards b's
  double plane_m = 0.0;  ///< the plane normal_C . p_C = plane_m lies halfway across the gap, m
};

/// Separation of the surfaces of two masks; only pixels of value 255 count.
/// @param depth_m CV_32FC1 m, the masks' size
/// @throws std::invalid_argument if the images do not match
MaskSeparation separateMasks(const cv::Mat& mask_a, const cv::Mat& mask_b, const cv::Mat& depth_m,
                             const PinholeCamera& camera);

}  // namespace semexp

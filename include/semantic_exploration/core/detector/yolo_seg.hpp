#pragma once
/// @file yolo_seg.hpp
/// Pre- and post-processing of a YOLOv8-seg / YOLO11-seg instance
/// segmentation network, independent of how the network is run.
///
/// Pixel convention: pixel (u, v) covers [u, u + 1) x [v, v + 1); its centre
/// is (u + 0.5, v + 0.5). Network input ("input px") and colour image ("image
/// px") are related by the letterbox: x_input = scale_x * x_image + left.

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "semantic_exploration/core/detector/detector_config.hpp"

namespace semexp {

/// Uniform scaling of the colour image into the network input, centred, with
/// grey (114) padding: x_input = scale_x * x_image + left, y_input = scale_y * y_image + top.
struct Letterbox {
  double scale_x = 1.0;  ///< input px per image px along x: scaled.width / image width
  double scale_y = 1.0;  ///< input px per image px along y: scaled.height / image height (= scale_x up to rounding)
  int left = 0;          ///< padding columns left of the scaled image, input px
  int top = 0;           ///< padding rows above the scaled image, input px
  cv::Size scaled;       ///< scaled image size inside the input, input px
  cv::Size input;        ///< network input size, px

  /// scaled = round(s * image) with s = min(input.w / image.w, input.h / image.h);
  /// left/top = half the padding, rounded down.
  static Letterbox fit(cv::Size image, cv::Size input);
};

/// The network's input blob [1, 3, H, W] (float, RGB, 0..1) of a CV_8UC3 RGB
/// image: bilinear resize to lb.scaled, padding with 114.
cv::Mat letterboxBlob(const cv::Mat& rgb, const Letterbox& lb);

/// One decoded instance in the colour image.
struct SegmentedInstance {
  int model_class = 0;       ///< index into DetectorConfig::model_classes
  std::string class_name;    ///< project class name (DetectorConfig::class_map of the model class)
  float confidence = 0.0f;   ///< class score, [0, 1]
  cv::Rect2d box_input;      ///< box in input px (x1, y1, w, h)
  cv::Rect roi;              ///< image pixels whose centres lie inside the box (may be empty)
  cv::Mat mask;              ///< CV_8UC1 of roi's size: 255 = in the mask
};

/// Decodes the two outputs of a YOLOv8-seg export:
///   output0 [1, 4 + nc + nm, N] float: per candidate box centre x, y, width,
///     height (input px), nc class scores, nm mask coefficients;
///   output1 [1, nm, H/4, W/4] float: mask prototypes.
/// Steps: candidates whose best class score is >= conf_threshold and whose
/// class is in class_map; class-wise non-maximum suppression (a candidate is
/// suppressed by a better-scoring kept one of the same class overlapping it by
/// IoU > nms_iou; ties keep the lower index); mask = sigmoid(coefficients .
/// prototypes), sampled bilinearly at each image pixel centre mapped through
/// the letterbox, kept inside the box and > mask_threshold.
/// Returns the instances by descending confidence. Throws std::invalid_argument
/// if the outputs do not have that layout with nc = model_classes.size().
std::vector<SegmentedInstance> decodeYoloSeg(const cv::Mat& output0, const cv::Mat& output1, const Letterbox& lb,
                                             cv::Size image_size, const DetectorConfig& config);

/// One instance of an InstanceImage.
struct InstanceEntry {
  std::uint16_t instance_id = 0;  ///< its pixels' value in InstanceImage::ids (> 0)
  int model_class = 0;            ///< index into DetectorConfig::model_classes
  std::string class_name;         ///< project class name
  float confidence = 0.0f;        ///< [0, 1]
  std::uint32_t pixel_count = 0;  ///< its pixels in ids (> 0)
};

/// Instance segmentation of one frame at the depth image's size.
struct InstanceImage {
  cv::Mat ids;                          ///< CV_16UC1, 0 = no instance
  std::vector<InstanceEntry> entries;   ///< one per id present in `ids`, ids 1..n by descending confidence
};

/// Paints instances (by descending confidence; a pixel keeps the most
/// confident instance covering it) into an image of `image_size`, then
/// resizes it to `out_size` by nearest neighbour (output pixel (u, v) takes
/// image pixel (floor((u + 0.5) * W / W_out), floor((v + 0.5) * H / H_out)))
/// when the sizes differ. Instances left without pixels are dropped; the rest
/// are numbered 1..n.
InstanceImage renderInstances(const std::vector<SegmentedInstance>& instances, cv::Size image_size, cv::Size out_size);

}  // namespace semexp

#pragma once
/// @file instance_segmenter.hpp
/// Runs an ONNX YOLOv8-seg / YOLO11-seg export with OpenCV DNN on colour
/// images and returns instance images (see yolo_seg.hpp for the decoding).

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include <string>
#include <vector>

#include "semantic_exploration/core/detector/detector_config.hpp"
#include "semantic_exploration/core/detector/yolo_seg.hpp"

namespace semexp {

/// Wall time of one frame's stages, ms.
struct DetectorTiming {
  double preprocess_ms = 0.0;  ///< letterbox and blob
  double inference_ms = 0.0;   ///< the network's forward pass
  double decode_ms = 0.0;      ///< filtering, NMS, masks, instance image
};

class InstanceSegmenter {
 public:
  /// Validates `config`, loads the model and runs it once on a blank input to
  /// check its outputs. Throws ConfigError naming the parameter (`ns` +
  /// model_path, input_size, model_classes, backend or target) and the
  /// expected layout if the model is missing, unreadable or shaped otherwise.
  explicit InstanceSegmenter(const DetectorConfig& config, const std::string& ns = "detector/");

  /// Segments a CV_8UC3 RGB image; the instance image has `out_size` (the
  /// depth image's size; resized by nearest neighbour if it differs). Throws
  /// cv::Exception or std::exception if inference fails. `timing` (optional)
  /// receives the stages' wall times.
  InstanceImage segment(const cv::Mat& rgb, cv::Size out_size, DetectorTiming* timing = nullptr);

  const DetectorConfig& config() const { return config_; }
  /// Prototype image size of the model (output1's W/4 x H/4), px.
  cv::Size protoSize() const { return proto_size_; }
  /// Candidate boxes per frame (output0's N).
  int numCandidates() const { return num_candidates_; }

 private:
  void runNetwork(const cv::Mat& blob, cv::Mat& output0, cv::Mat& output1);

  DetectorConfig config_;
  cv::dnn::Net net_;
  std::vector<std::string> out_names_;
  int out0_index_ = 0, out1_index_ = 1;  ///< which forward() output is which (by rank)
  cv::Size proto_size_;
  int num_candidates_ = 0;
};

}  // namespace semexp

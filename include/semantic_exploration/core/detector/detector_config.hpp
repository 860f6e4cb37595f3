#pragma once
/// @file detector_config.hpp
/// Settings of the instance-segmentation detector (an ONNX YOLOv8-seg /
/// YOLO11-seg export run through OpenCV DNN), section `detector/`.

#include <array>
#include <map>
#include <string>
#include <vector>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

/// The 80 COCO class names in the order of the stock YOLOv8-seg / YOLO11-seg
/// models' class indices, with spaces written as underscores ("dining_table")
/// so that each is a valid ROS parameter name.
const std::vector<std::string>& cocoClassNames();

/// The output layout the detector decodes, for error messages.
extern const char* const kYoloSegLayout;

struct DetectorConfig {
  std::string model_path;               ///< ONNX file (required)
  std::array<int, 2> input_size{{640, 640}};  ///< network input [width, height], px: the export's imgsz
  double conf_threshold = 0.25;         ///< a candidate needs a class score of at least this, [0, 1]
  double nms_iou = 0.45;                ///< a box overlapping a better one of its class by more IoU is suppressed
  double mask_threshold = 0.5;          ///< a pixel belongs to the mask if sigmoid(coefficients . prototypes) > this
  /// The model's class names by class index (its output has 4 + this many + 32 rows).
  std::vector<std::string> model_classes = cocoClassNames();
  /// Model class name -> project class name (classes/names); the detector
  /// reports only the model classes listed here.
  std::map<std::string, std::string> class_map{{"chair", "chair"}};
  std::string backend = "opencv";       ///< OpenCV DNN backend: opencv | cuda
  std::string target = "cpu";           ///< OpenCV DNN target: cpu (backend opencv) | cuda | cuda_fp16 (backend cuda)

  /// Throws ConfigError naming the parameter (`ns` + its name). Does not open the model.
  void validate(const std::string& ns = "detector/") const;
};

}  // namespace semexp

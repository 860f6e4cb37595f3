#include "semantic_exploration/core/detector/detector_config.hpp"

#include <cmath>
#include <set>

namespace semexp {

const char* const kYoloSegLayout =
    "a YOLOv8-seg / YOLO11-seg ONNX export: input [1, 3, H, W] (H, W = input_size), output0 [1, 4 + nc + 32, N] "
    "(box cx, cy, w, h in input px, nc class scores, 32 mask coefficients), output1 [1, 32, H/4, W/4] (mask "
    "prototypes), nc = the length of model_classes";

const std::vector<std::string>& cocoClassNames() {
  static const std::vector<std::string> names{
      "person",        "bicycle",      "car",           "motorcycle",    "airplane",     "bus",
      "train",         "truck",        "boat",          "traffic_light", "fire_hydrant", "stop_sign",
      "parking_meter", "bench",        "bird",          "cat",           "dog",          "horse",
      "sheep",         "cow",          "elephant",      "bear",          "zebra",        "giraffe",
      "backpack",      "umbrella",     "handbag",       "tie",           "suitcase",     "frisbee",
      "skis",          "snowboard",    "sports_ball",   "kite",          "baseball_bat", "baseball_glove",
      "skateboard",    "surfboard",    "tennis_racket", "bottle",        "wine_glass",   "cup",
      "fork",          "knife",        "spoon",         "bowl",          "banana",       "apple",
      "sandwich",      "orange",       "broccoli",      "carrot",        "hot_dog",      "pizza",
      "donut",         "cake",         "chair",         "couch",         "potted_plant", "bed",
      "dining_table",  "toilet",       "tv",            "laptop",        "mouse",        "remote",
      "keyboard",      "cell_phone",   "microwave",     "oven",          "toaster",      "sink",
      "refrigerator",  "book",         "clock",         "vase",          "scissors",     "teddy_bear",
      "hair_drier",    "toothbrush"};
  return names;
}

void DetectorConfig::validate(const std::string& ns) const {
  require(!model_path.empty(), ns + "model_path", std::string("is required: the ONNX file of ") + kYoloSegLayout);
  for (int i = 0; i < 2; ++i)
    require(input_size[i] >= 32 && input_size[i] % 32 == 0, ns + "input_size",
            "must be [width, height] in px, each a positive multiple of 32 (the export's imgsz)");
  require(std::isfinite(conf_threshold) && conf_threshold > 0 && conf_threshold <= 1, ns + "conf_threshold",
          "must be in (0, 1]");
  require(std::isfinite(nms_iou) && nms_iou > 0 && nms_iou <= 1, ns + "nms_iou", "must be in (0, 1]");
  require(std::isfinite(mask_threshold) && mask_threshold > 0 && mask_threshold < 1, ns + "mask_threshold",
          "must be in (0, 1)");
  require(!model_classes.empty(), ns + "model_classes", "must list the model's class names by index");
  std::set<std::string> known;
  for (const auto& n : model_classes) {
    require(!n.empty(), ns + "model_classes", "class names must not be empty");
    require(known.insert(n).second, ns + "model_classes", "duplicate class '" + n + "'");
  }
  require(!class_map.empty(), ns + "class_map", "must map at least one model class to a project class");
  for (const auto& kv : class_map) {
    require(known.count(kv.first) > 0, ns + "class_map",
            "'" + kv.first + "' is not one of the model's classes (" + ns + "model_classes)");
    require(!kv.second.empty(), ns + "class_map", "'" + kv.first + "' maps to an empty class name");
  }
  require(backend == "opencv" || backend == "cuda", ns + "backend", "must be opencv or cuda, got '" + backend + "'");
  if (backend == "opencv")
    require(target == "cpu", ns + "target", "must be cpu with backend opencv, got '" + target + "'");
  else
    require(target == "cuda" || target == "cuda_fp16", ns + "target",
            "must be cuda or cuda_fp16 with backend cuda, got '" + target + "'");
}

}  // namespace semexp

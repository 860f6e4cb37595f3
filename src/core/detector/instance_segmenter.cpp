#include "semantic_exploration/core/detector/instance_segmenter.hpp"

#include <opencv2/core/version.hpp>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <stdexcept>

namespace semexp {

namespace {

using Clock = std::chrono::steady_clock;

double msBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

std::string shapeOf(const cv::Mat& m) {
  std::string s = "[";
  for (int i = 0; i < m.dims; ++i) s += (i ? ", " : "") + std::to_string(m.size[i]);
  return s + "]";
}

// OpenCV's messages run over several lines: joined into one, at most 400 characters.
std::string oneLine(const std::string& s) {
  std::string r;
  for (const char ch : s) {
    if (ch == '\n') {
      if (!r.empty() && r.back() != ' ') r += ' ';
    } else {
      r += ch;
    }
  }
  while (!r.empty() && r.back() == ' ') r.pop_back();
  return r.size() > 400 ? r.substr(0, 400) + "..." : r;
}

std::string expected() { return std::string("; expected ") + kYoloSegLayout; }

}  // namespace

InstanceSegmenter::InstanceSegmenter(const DetectorConfig& config, const std::string& ns) : config_(config) {
  config_.validate(ns);
  const std::string& path = config_.model_path;
  const std::string p_model = ns + "model_path", p_input = ns + "input_size";
  if (!std::ifstream(path, std::ios::binary).good())
    throw ConfigError(p_model, "cannot read '" + path + "' (missing or unreadable)" + expected());
  try {
    net_ = cv::dnn::readNetFromONNX(path);
  } catch (const cv::Exception& e) {
    throw ConfigError(p_model, "OpenCV " CV_VERSION " cannot load '" + path + "' as ONNX (" + oneLine(e.what()) +
                                   ")" + expected() + " (export with opset=12)");
  }
  if (net_.empty()) throw ConfigError(p_model, "'" + path + "' holds no network" + expected());

  const int backend = config_.backend == "cuda" ? cv::dnn::DNN_BACKEND_CUDA : cv::dnn::DNN_BACKEND_OPENCV;
  const int target = config_.target == "cuda"        ? cv::dnn::DNN_TARGET_CUDA
                     : config_.target == "cuda_fp16" ? cv::dnn::DNN_TARGET_CUDA_FP16
                                                     : cv::dnn::DNN_TARGET_CPU;
  const auto targets = cv::dnn::getAvailableTargets(static_cast<cv::dnn::Backend>(backend));
  if (std::find(targets.begin(), targets.end(), static_cast<cv::dnn::Target>(target)) == targets.end())
    throw ConfigError(ns + "backend", "this OpenCV (" CV_VERSION ") offers no " + config_.backend +
                                          " backend with target " + config_.target +
                                          " (built without CUDA?); use backend opencv, target cpu");
  net_.setPreferableBackend(backend);
  net_.setPreferableTarget(target);

  out_names_ = net_.getUnconnectedOutLayersNames();
  if (out_names_.size() != 2)
    throw ConfigError(p_model, "'" + path + "' has " + std::to_string(out_names_.size()) + " outputs" + expected());
  // One forward pass on a grey input checks that the model runs at input_size and how its outputs are shaped.
  const int w = config_.input_size[0], h = config_.input_size[1];
  const int blob_shape[] = {1, 3, h, w};
  const cv::Mat blob(4, blob_shape, CV_32F, cv::Scalar(114.0 / 255.0));
  std::vector<cv::Mat> outs;
  try {
    net_.setInput(blob);
    net_.forward(outs, out_names_);
  } catch (const cv::Exception& e) {
    // Either input_size is not the export's imgsz, or the graph broadcasts in a way this OpenCV cannot.
    throw ConfigError(p_model, "OpenCV " CV_VERSION " cannot run '" + path + "' on a " + std::to_string(w) + " x " +
                                   std::to_string(h) + " input (" + oneLine(e.what()) + "): " + p_input +
                                   " must be the export's imgsz, and OpenCV before 4.7 needs the export passed "
                                   "through scripts/onnx_for_opencv.py" + expected());
  }
  if (outs.size() != 2)
    throw ConfigError(p_model, "'" + path + "' gave " + std::to_string(outs.size()) + " outputs" + expected());
  if (outs[0].dims == 4 && outs[1].dims == 3) std::swap(out0_index_, out1_index_);
  const cv::Mat& o0 = outs[static_cast<std::size_t>(out0_index_)];
  const cv::Mat& o1 = outs[static_cast<std::size_t>(out1_index_)];
  if (o0.dims != 3 || o1.dims != 4 || o0.size[0] != 1 || o1.size[0] != 1 || o0.type() != CV_32F ||
      o1.type() != CV_32F)
    throw ConfigError(p_model,
                      "'" + path + "' has outputs " + shapeOf(outs[0]) + " and " + shapeOf(outs[1]) + expected());
  const int nm = o1.size[1];
  const int nc = o0.size[1] - 4 - nm;
  if (o1.size[2] * 4 != h || o1.size[3] * 4 != w)
    throw ConfigError(p_input, "'" + path + "' gives " + shapeOf(o1) + " prototypes for a " + std::to_string(w) +
                                   " x " + std::to_string(h) + " input, not [1, " + std::to_string(nm) + ", " +
                                   std::to_string(h / 4) + ", " + std::to_string(w / 4) +
                                   "]; input_size must be the export's imgsz" + expected());
  if (nm < 1 || nc < 1)
    throw ConfigError(p_model, "'" + path + "' has outputs " + shapeOf(o0) + " and " + shapeOf(o1) +
                                   ": no room for class scores" + expected());
  if (nc != static_cast<int>(config_.model_classes.size()))
    throw ConfigError(ns + "model_classes", "'" + path + "' has " + std::to_string(nc) + " classes (output0 " +
                                                shapeOf(o0) + " = 4 + nc + " + std::to_string(nm) + ") but " + ns +
                                                "model_classes lists " + std::to_string(config_.model_classes.size()));
  proto_size_ = cv::Size(o1.size[3], o1.size[2]);
  num_candidates_ = o0.size[2];
}

void InstanceSegmenter::runNetwork(const cv::Mat& blob, cv::Mat& output0, cv::Mat& output1) {
  std::vector<cv::Mat> outs;
  net_.setInput(blob);
  net_.forward(outs, out_names_);
  if (outs.size() != 2) throw std::runtime_error("the network gave " + std::to_string(outs.size()) + " outputs, not 2");
  output0 = outs[static_cast<std::size_t>(out0_index_)];
  output1 = outs[static_cast<std::size_t>(out1_index_)];
}

InstanceImage InstanceSegmenter::segment(const cv::Mat& rgb, cv::Size out_size, DetectorTiming* timing) {
  if (rgb.empty() || rgb.type() != CV_8UC3)
    throw std::invalid_argument("segment: the colour image must be CV_8UC3 RGB");
  if (out_size.width <= 0 || out_size.height <= 0)
    throw std::invalid_argument("segment: the output size must be positive");
  const auto t0 = Clock::now();
  const Letterbox lb = Letterbox::fit(rgb.size(), cv::Size(config_.input_size[0], config_.input_size[1]));
  const cv::Mat blob = letterboxBlob(rgb, lb);
  const auto t1 = Clock::now();
  cv::Mat out0, out1;
  runNetwork(blob, out0, out1);
  const auto t2 = Clock::now();
  InstanceImage result = renderInstances(decodeYoloSeg(out0, out1, lb, rgb.size(), config_), rgb.size(), out_size);
  const auto t3 = Clock::now();
  if (timing) {
    timing->preprocess_ms = msBetween(t0, t1);
    timing->inference_ms = msBetween(t1, t2);
    timing->decode_ms = msBetween(t2, t3);
  }
  return result;
}

}  // namespace semexp

// Detector benchmark: per-frame wall time of the detector node's work
// (pre-processing, inference, decoding) on 320x240 and 640x480 colour frames.
//
// Without --model it builds, with test/detector/make_seg_model.py, a graph of
// a stock export's size (input 640 x 640, 8400 candidates, 80 classes, 32
// prototypes of 160 x 160) whose outputs are constants: pre-processing and
// decoding are the real work, inference is OpenCV DNN running a trivial graph
// (not a network's compute). Every class is mapped, so decoding handles the
// most candidates it can (about 60 above the threshold per frame).
//   bench_detector [--out FILE] [--model FILE.onnx --input-size W H]
// measures any YOLOv8-seg export instead (COCO classes, all mapped).

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core/version.hpp>

#include "bench_common.hpp"
#include "semantic_exploration/core/detector/instance_segmenter.hpp"

using namespace semexp;
using semexp_bench::median;

// The Python with the onnx package: the venv's where there is one (Ubuntu 20.04 has it only there).
static std::string python() {
  const char* venv = std::getenv("SEMEXP_VENV");
  return venv && *venv ? std::string(venv) + "/bin/python" : std::string(SEMEXP_PYTHON);
}

int main(int argc, char** argv) {
  semexp_bench::Reporter rep(argc, argv);
  DetectorConfig c;
  std::string tag = "synthetic";
  char dir[] = "/tmp/semexp_detector_bench.XXXXXX";
  bool made = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--model") == 0 && i + 1 < argc) {
      c.model_path = argv[++i];
      tag = c.model_path.substr(c.model_path.find_last_of('/') + 1);  // the file name without .onnx
      tag = tag.substr(0, tag.rfind(".onnx"));
    }
    if (std::strcmp(argv[i], "--input-size") == 0 && i + 2 < argc) {
      c.input_size = {{std::atoi(argv[i + 1]), std::atoi(argv[i + 2])}};
      i += 2;
    }
  }
  if (c.model_path.empty()) {
    if (!mkdtemp(dir)) return 1;
    made = true;
    c.model_path = std::string(dir) + "/stock.onnx";
    const std::string cmd = python() + " " + SEMEXP_MAKE_SEG_MODEL + " " + c.model_path +
                            " --variant stock --input 640 640";
    if (std::system(cmd.c_str()) != 0) {
      std::fprintf(stderr, "failed: %s\n", cmd.c_str());
      return 1;
    }
  }
  c.class_map.clear();
  for (const auto& n : c.model_classes) c.class_map[n] = n;
  InstanceSegmenter seg(c);
  std::printf("model %s: input %dx%d, %d candidates, prototypes %dx%d; OpenCV %s, %d threads\n", c.model_path.c_str(),
              c.input_size[0], c.input_size[1], seg.numCandidates(), seg.protoSize().width, seg.protoSize().height,
              CV_VERSION, cv::getNumThreads());
  std::printf("%-10s %10s %10s %10s %10s %10s\n", "frame", "pre ms", "infer ms", "decode ms", "total ms", "instances");

  cv::RNG rng(1);
  const int frames = 20, warmup = 3;
  for (const cv::Size size : {cv::Size(320, 240), cv::Size(640, 480)}) {
    cv::Mat rgb(size, CV_8UC3);
    rng.fill(rgb, cv::RNG::UNIFORM, 0, 256);
    std::vector<double> pre, inf, dec, total;
    std::size_t instances = 0;
    for (int k = 0; k < warmup + frames; ++k) {
      DetectorTiming t;
      instances = seg.segment(rgb, size, &t).entries.size();
      if (k < warmup) continue;
      pre.push_back(t.preprocess_ms);
      inf.push_back(t.inference_ms);
      dec.push_back(t.decode_ms);
      total.push_back(t.preprocess_ms + t.inference_ms + t.decode_ms);
    }
    const std::string name = "detector." + tag + "." + std::to_string(size.width) + "x" + std::to_string(size.height);
    std::printf("%-10s %10.2f %10.2f %10.2f %10.2f %10zu\n",
                (std::to_string(size.width) + "x" + std::to_string(size.height)).c_str(), median(pre), median(inf),
                median(dec), median(total), instances);
    rep.add(name + ".preprocess_ms", median(pre), "ms");
    rep.add(name + ".inference_ms", median(inf), "ms");
    rep.add(name + ".decode_ms", median(dec), "ms");
    rep.add(name + ".total_ms", median(total), "ms");
  }
  if (made) std::system(("rm -rf " + std::string(dir)).c_str());
  return 0;
}

// The detector's decoding and model checks against a hand-computed scene.
//
// test/detector/make_seg_model.py writes an ONNX graph (at test time, with
// python3-onnx) whose outputs encode known candidates: see SCENE there. Input
// 128 x 128, prototypes 32 x 32, model classes {person, chair, couch}, class
// map {chair: chair, couch: sofa}. Candidates (cx, cy, w, h in input px):
//   A   chair 0.9  (40, 48, 32, 32) -> x [24, 56), y [32, 64), prototype 0 (whole box)
//   dup chair 0.8  (42, 48, 32, 32) -> IoU 0.88 with A: suppressed by NMS (0.45)
//   B   couch 0.7  (72, 64, 64, 32) -> x [40, 104), y [48, 80), prototype 1 (+1 left of x = 64, -1 right)
//   A'  couch 0.6  (44, 48, 32, 32) -> x [28, 60), y [32, 64): IoU 0.78 with A but another class: kept
//   person 0.95, and person 0.6 (chair 0.5): not in the class map; chair 0.2: below conf_threshold
//   E   chair 0.4  (8, 12, 16, 24)  -> x [0, 16), y [0, 24): partly in the letterbox padding
// A 256 x 192 colour image is letterboxed with scale 0.5, left 0, top 16, so
// pixel u, v has its centre at x = 0.5 (u + 0.5), y = 0.5 (v + 0.5) + 16: a box
// [x1, x2) x [y1, y2) holds pixels u in [2 x1, 2 x2 - 1], v in [2 (y1 - 16), 2 (y2 - 16) - 1].
// B's mask probability crosses 0.5 at input x = 64 (halfway between prototype
// columns 15 and 16), so its mask holds u <= 127.
#include <gtest/gtest.h>

#include <opencv2/core/version.hpp>
#include <opencv2/dnn.hpp>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>

#include "semantic_exploration/core/detector/instance_segmenter.hpp"
#include "semantic_exploration/core/detector/yolo_seg.hpp"
#include "semexp_test/config_errors.hpp"

using namespace semexp;

namespace {

std::string g_dir;  // temporary directory of this run's models

// The Python with the onnx package: the venv's where there is one (Ubuntu 20.04 has it only there).
std::string python() {
  const char* venv = std::getenv("SEMEXP_VENV");
  return venv && *venv ? std::string(venv) + "/bin/python" : std::string(SEMEXP_PYTHON);
}

std::string makeModel(const std::string& variant) {
  const std::string out = g_dir + "/" + variant + ".onnx";
  if (std::ifstream(out).good()) return out;
  const std::string cmd =
      python() + " " + SEMEXP_MAKE_SEG_MODEL + " " + out + " --variant " + variant;
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  return out;
}

class ModelDir : public ::testing::Environment {
 public:
  void SetUp() override {
    char tmpl[] = "/tmp/semexp_detector_test.XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    g_dir = tmpl;
  }
  void TearDown() override { std::system(("rm -rf " + g_dir).c_str()); }
};
const auto* const g_env = ::testing::AddGlobalTestEnvironment(new ModelDir);

DetectorConfig sceneConfig() {
  DetectorConfig c;
  c.model_path = makeModel("scene");
  c.input_size = {{128, 128}};
  c.model_classes = {"person", "chair", "couch"};
  c.class_map = {{"chair", "chair"}, {"couch", "sofa"}};
  return c;
}

// Paints rectangles (inclusive pixel ranges u0..u1, v0..v1) in order; a pixel keeps its first id.
struct Rect { int u0, u1, v0, v1; };
cv::Mat paint(cv::Size size, const std::vector<Rect>& rects) {
  cv::Mat m = cv::Mat::zeros(size, CV_16UC1);
  for (std::size_t k = 0; k < rects.size(); ++k)
    for (int v = rects[k].v0; v <= rects[k].v1; ++v)
      for (int u = rects[k].u0; u <= rects[k].u1; ++u)
        if (!m.at<std::uint16_t>(v, u)) m.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(k + 1);
  return m;
}

int differing(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size()) return -1;
  cv::Mat ne;
  cv::compare(a, b, ne, cv::CMP_NE);
  return cv::countNonZero(ne);
}

// The network's two outputs for a 256 x 192 frame, through the same readNetFromONNX as the node.
void sceneOutputs(cv::Mat& out0, cv::Mat& out1, Letterbox& lb) {
  cv::dnn::Net net = cv::dnn::readNetFromONNX(makeModel("scene"));
  lb = Letterbox::fit(cv::Size(256, 192), cv::Size(128, 128));
  net.setInput(letterboxBlob(cv::Mat(192, 256, CV_8UC3, cv::Scalar(10, 200, 30)), lb));
  std::vector<cv::Mat> outs;
  net.forward(outs, std::vector<std::string>{"output0", "output1"});
  out0 = outs[0].clone();
  out1 = outs[1].clone();
}

using semexp_test::rejected;

}  // namespace

TEST(Letterbox, FitsNonSquareImages) {
  Letterbox lb = Letterbox::fit(cv::Size(256, 192), cv::Size(128, 128));
  EXPECT_DOUBLE_EQ(lb.scale_x, 0.5);
  EXPECT_DOUBLE_EQ(lb.scale_y, 0.5);
  EXPECT_EQ(lb.scaled, cv::Size(128, 96));
  EXPECT_EQ(lb.left, 0);
  EXPECT_EQ(lb.top, 16);
  lb = Letterbox::fit(cv::Size(192, 256), cv::Size(128, 128));
  EXPECT_EQ(lb.scaled, cv::Size(96, 128));
  EXPECT_EQ(lb.left, 16);
  EXPECT_EQ(lb.top, 0);
  lb = Letterbox::fit(cv::Size(500, 375), cv::Size(640, 640));  // scale 1.28
  EXPECT_EQ(lb.scaled, cv::Size(640, 480));
  EXPECT_EQ(lb.top, 80);
  EXPECT_DOUBLE_EQ(lb.scale_x, 1.28);
  lb = Letterbox::fit(cv::Size(640, 480), cv::Size(640, 480));
  EXPECT_EQ(lb.left, 0);
  EXPECT_EQ(lb.top, 0);
  EXPECT_DOUBLE_EQ(lb.scale_x, 1.0);
}

TEST(Letterbox, BlobHoldsTheRgbImageBetweenGreyPadding) {
  const cv::Mat rgb(2, 4, CV_8UC3, cv::Scalar(255, 0, 51));  // R, G, B
  const Letterbox lb = Letterbox::fit(rgb.size(), cv::Size(4, 4));
  const cv::Mat blob = letterboxBlob(rgb, lb);
  ASSERT_EQ(blob.dims, 4);
  EXPECT_EQ(blob.size[1], 3);
  EXPECT_EQ(blob.size[2], 4);
  EXPECT_EQ(blob.size[3], 4);
  const auto at = [&](int c, int y, int x) { return blob.at<float>(cv::Vec4i(0, c, y, x)); };
  for (int x = 0; x < 4; ++x) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_FLOAT_EQ(at(c, 0, x), 114.0f / 255.0f);  // padding rows 0 and 3
      EXPECT_FLOAT_EQ(at(c, 3, x), 114.0f / 255.0f);
    }
    EXPECT_FLOAT_EQ(at(0, 1, x), 1.0f);
    EXPECT_FLOAT_EQ(at(1, 2, x), 0.0f);
    EXPECT_FLOAT_EQ(at(2, 1, x), 0.2f);
  }
}

TEST(Decode, FiltersSuppressesAndCropsMasksToBoxes) {
  cv::Mat out0, out1;
  Letterbox lb;
  sceneOutputs(out0, out1, lb);
  const DetectorConfig c = sceneConfig();
  const auto inst = decodeYoloSeg(out0, out1, lb, cv::Size(256, 192), c);
  ASSERT_EQ(inst.size(), 4u);  // A, B, A', E: dup suppressed, persons unmapped, 0.2 below threshold
  const std::vector<std::string> names{"chair", "sofa", "sofa", "chair"};
  const std::vector<int> classes{1, 2, 2, 1};
  const std::vector<float> conf{0.9f, 0.7f, 0.6f, 0.4f};
  const std::vector<cv::Rect> rois{{48, 32, 64, 64}, {80, 64, 128, 64}, {56, 32, 64, 64}, {0, 0, 32, 16}};
  for (std::size_t k = 0; k < inst.size(); ++k) {
    EXPECT_EQ(inst[k].class_name, names[k]) << k;
    EXPECT_EQ(inst[k].model_class, classes[k]) << k;
    EXPECT_FLOAT_EQ(inst[k].confidence, conf[k]) << k;
    EXPECT_EQ(inst[k].roi, rois[k]) << k;  // exactly the pixels whose centres lie in the box
    ASSERT_EQ(inst[k].mask.size(), rois[k].size()) << k;
  }
  EXPECT_EQ(cv::countNonZero(inst[0].mask), 64 * 64);
  EXPECT_EQ(cv::countNonZero(inst[2].mask), 64 * 64);
  EXPECT_EQ(cv::countNonZero(inst[3].mask), 32 * 16);
  // B: the mask is the box's columns u <= 127 (roi columns 0..47), all rows.
  EXPECT_EQ(cv::countNonZero(inst[1].mask), 48 * 64);
  EXPECT_EQ(cv::countNonZero(inst[1].mask.colRange(0, 48)), 48 * 64);
  EXPECT_EQ(inst[1].box_input, cv::Rect2d(40, 48, 64, 32));
}

TEST(Decode, NmsAndClassMapAndThresholdAreWhatRemoveCandidates) {
  cv::Mat out0, out1;
  Letterbox lb;
  sceneOutputs(out0, out1, lb);
  DetectorConfig c = sceneConfig();
  c.nms_iou = 0.9;  // above the duplicate's IoU of 0.88
  auto inst = decodeYoloSeg(out0, out1, lb, cv::Size(256, 192), c);
  ASSERT_EQ(inst.size(), 5u);
  EXPECT_FLOAT_EQ(inst[1].confidence, 0.8f);
  c = sceneConfig();
  c.class_map["person"] = "person";
  inst = decodeYoloSeg(out0, out1, lb, cv::Size(256, 192), c);
  ASSERT_EQ(inst.size(), 6u);  // both persons; the second is a person (its best class), not a chair
  EXPECT_EQ(inst[0].class_name, "person");
  EXPECT_FLOAT_EQ(inst[0].confidence, 0.95f);
  EXPECT_EQ(inst[3].class_name, "sofa");
  EXPECT_EQ(inst[4].class_name, "person");
  EXPECT_FLOAT_EQ(inst[4].confidence, 0.6f);
  c = sceneConfig();
  c.conf_threshold = 0.15;
  inst = decodeYoloSeg(out0, out1, lb, cv::Size(256, 192), c);
  ASSERT_EQ(inst.size(), 5u);
  EXPECT_FLOAT_EQ(inst[4].confidence, 0.2f);
  EXPECT_EQ(inst[4].roi, cv::Rect(190, 18, 20, 20));  // x [95, 105) -> u 190..209; y [25, 35) -> v 18..37
}

TEST(Decode, NonFiniteOrHugeBoxesAreSkipped) {
  // Three chair candidates of score 0.9 (1 class, 1 prototype of 2 x 2 = 1): NaN centre, 1e30 width, a good box.
  const int s0[] = {1, 6, 3}, s1[] = {1, 1, 2, 2};
  cv::Mat out0(3, s0, CV_32F, cv::Scalar(0)), out1(4, s1, CV_32F, cv::Scalar(1));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float rows[6][3] = {{nan, 4, 4}, {4, 4, 4}, {2, 1e30f, 4}, {2, 2, 4}, {0.9f, 0.9f, 0.9f}, {10, 10, 10}};
  for (int r = 0; r < 6; ++r)
    for (int j = 0; j < 3; ++j) out0.at<float>(cv::Vec3i(0, r, j)) = rows[r][j];
  DetectorConfig c;
  c.model_classes = {"chair"};
  c.class_map = {{"chair", "chair"}};
  const auto inst = decodeYoloSeg(out0, out1, Letterbox::fit(cv::Size(8, 8), cv::Size(8, 8)), cv::Size(8, 8), c);
  ASSERT_EQ(inst.size(), 1u);
  EXPECT_EQ(inst[0].roi, cv::Rect(2, 2, 4, 4));  // box x, y [2, 6)
  EXPECT_EQ(cv::countNonZero(inst[0].mask), 16);
}

TEST(Segmenter, InstanceImageOfALandscapeFrame) {
  InstanceSegmenter seg(sceneConfig());
  EXPECT_EQ(seg.protoSize(), cv::Size(32, 32));
  EXPECT_EQ(seg.numCandidates(), 8);
  const cv::Mat rgb(192, 256, CV_8UC3, cv::Scalar(90, 60, 30));
  DetectorTiming t;
  const InstanceImage img = seg.segment(rgb, rgb.size(), &t);
  // By confidence A, B, A', E; each keeps the pixels no more confident instance took.
  const cv::Mat want = paint(rgb.size(), {{48, 111, 32, 95}, {80, 127, 64, 127}, {56, 119, 32, 95}, {0, 31, 0, 15}});
  EXPECT_EQ(differing(img.ids, want), 0);
  ASSERT_EQ(img.entries.size(), 4u);
  const std::vector<std::uint32_t> pixels{4096, 3072 - 1024, 512 - 256, 512};
  const std::vector<std::string> names{"chair", "sofa", "sofa", "chair"};
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(img.entries[k].instance_id, k + 1);
    EXPECT_EQ(img.entries[k].class_name, names[k]);
    EXPECT_EQ(img.entries[k].pixel_count, pixels[k]) << k;
  }
  EXPECT_GE(t.inference_ms, 0.0);
}

TEST(Segmenter, PortraitFrameIsPaddedLeftAndRight) {
  // 192 x 256 -> scale 0.5, left 16, top 0: u in [2 (x1 - 16), 2 (x2 - 16) - 1], v in [2 y1, 2 y2 - 1].
  InstanceSegmenter seg(sceneConfig());
  const cv::Mat rgb(256, 192, CV_8UC3, cv::Scalar(0, 0, 0));
  const InstanceImage img = seg.segment(rgb, rgb.size());
  // A u 16..79 v 64..127; B u 48..175 but its mask stops at x = 64: u <= 95, v 96..159; A' u 24..87 v 64..127;
  // E lies in the left padding (x < 16) and has no pixel: it is dropped.
  const cv::Mat want = paint(rgb.size(), {{16, 79, 64, 127}, {48, 95, 96, 159}, {24, 87, 64, 127}});
  EXPECT_EQ(differing(img.ids, want), 0);
  ASSERT_EQ(img.entries.size(), 3u);
  EXPECT_EQ(img.entries[0].pixel_count, 4096u);
  EXPECT_EQ(img.entries[1].pixel_count, 2048u);
  EXPECT_EQ(img.entries[2].pixel_count, 256u);
}

TEST(Segmenter, InstanceImageIsResizedToTheDepthSizeByNearestNeighbour) {
  InstanceSegmenter seg(sceneConfig());
  const cv::Mat rgb(192, 256, CV_8UC3, cv::Scalar(90, 60, 30));
  const InstanceImage full = seg.segment(rgb, rgb.size());
  const InstanceImage half = seg.segment(rgb, cv::Size(128, 96));
  ASSERT_EQ(half.ids.size(), cv::Size(128, 96));
  for (int v = 0; v < 96; ++v)
    for (int u = 0; u < 128; ++u)
      ASSERT_EQ(half.ids.at<std::uint16_t>(v, u), full.ids.at<std::uint16_t>(2 * v + 1, 2 * u + 1)) << u << "," << v;
  ASSERT_EQ(half.entries.size(), 4u);
  EXPECT_EQ(half.entries[0].pixel_count, 1024u);
  EXPECT_EQ(half.entries[1].pixel_count, 512u);
  EXPECT_EQ(half.entries[2].pixel_count, 64u);
  EXPECT_EQ(half.entries[3].pixel_count, 128u);
}

TEST(Segmenter, ABadFrameThrowsAndTheNextOneWorks) {
  InstanceSegmenter seg(sceneConfig());
  EXPECT_ANY_THROW(seg.segment(cv::Mat(192, 256, CV_8UC1, cv::Scalar(0)), cv::Size(256, 192)));
  EXPECT_EQ(seg.segment(cv::Mat(192, 256, CV_8UC3, cv::Scalar(0)), cv::Size(256, 192)).entries.size(), 4u);
}

TEST(Segmenter, ABadModelFailsAtStartupNamingTheParameter) {
  DetectorConfig c = sceneConfig();
  c.model_path = g_dir + "/missing.onnx";
  EXPECT_EQ(rejected([&] { InstanceSegmenter s(c); }), "detector/model_path");
  c.model_path = g_dir + "/not_onnx.onnx";
  std::ofstream(c.model_path) << "not a model\n";
  EXPECT_EQ(rejected([&] { InstanceSegmenter s(c); }), "detector/model_path");
  c.model_path = makeModel("one_output");  // a detection-only export
  EXPECT_EQ(rejected([&] { InstanceSegmenter s(c); }), "detector/model_path");
  try {
    InstanceSegmenter s(c);
  } catch (const ConfigError& e) {  // the message gives the expected layout
    EXPECT_NE(std::string(e.what()).find("output1 [1, 32, H/4, W/4]"), std::string::npos) << e.what();
  }
  c = sceneConfig();
  c.model_classes = {"person", "chair"};  // the model has three
  c.class_map = {{"chair", "chair"}};
  EXPECT_EQ(rejected([&] { InstanceSegmenter s(c); }), "detector/model_classes");
  c = sceneConfig();
  c.input_size = {{256, 256}};  // the graph cannot run at that size
  EXPECT_EQ(rejected([&] { InstanceSegmenter s(c); }), "detector/model_path");
  c = sceneConfig();
  c.backend = "cuda";
  c.target = "cuda";
  if (cv::dnn::getAvailableTargets(cv::dnn::DNN_BACKEND_CUDA).empty()) {
    EXPECT_EQ(rejected([&] { InstanceSegmenter s(c); }), "detector/backend");
  }
}

TEST(Segmenter, AnExportThatBroadcastsRunsAfterOnnxForOpencv) {
  // output0 = boxes [1, 39, 8] x a [1, 8] constant, as a stock export's anchor strides.
  DetectorConfig c = sceneConfig();
  c.model_path = makeModel("broadcast");
  if (CV_VERSION_MAJOR == 4 && CV_VERSION_MINOR < 7) {
    EXPECT_EQ(rejected([&] { InstanceSegmenter s(c); }), "detector/model_path");
  }
  const std::string prepared = g_dir + "/broadcast_prepared.onnx";
  const std::string cmd =
      python() + " " + SEMEXP_ONNX_FOR_OPENCV + " " + c.model_path + " " + prepared;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  c.model_path = prepared;
  InstanceSegmenter seg(c);
  const InstanceImage img = seg.segment(cv::Mat(192, 256, CV_8UC3, cv::Scalar(0)), cv::Size(256, 192));
  ASSERT_EQ(img.entries.size(), 4u);
  EXPECT_EQ(img.entries[0].pixel_count, 4096u);
  EXPECT_EQ(img.entries[1].pixel_count, 2048u);
  EXPECT_EQ(img.entries[2].pixel_count, 256u);
  EXPECT_EQ(img.entries[3].pixel_count, 512u);
}

TEST(DetectorConfig, ValidateNamesTheParameter) {
  DetectorConfig c;
  EXPECT_EQ(rejected([&] { c.validate(); }), "detector/model_path");
  c.model_path = "m.onnx";
  EXPECT_EQ(rejected([&] { c.validate(); }), "");
  EXPECT_EQ(c.model_classes.size(), 80u);
  EXPECT_EQ(c.model_classes[56], "chair");
  EXPECT_EQ(c.model_classes[60], "dining_table");
  const auto bad = [&](auto change) {
    DetectorConfig d = c;
    change(d);
    return rejected([&] { d.validate(); });
  };
  EXPECT_EQ(bad([](DetectorConfig& d) { d.input_size = {{640, 100}}; }), "detector/input_size");
  EXPECT_EQ(bad([](DetectorConfig& d) { d.conf_threshold = 0.0; }), "detector/conf_threshold");
  EXPECT_EQ(bad([](DetectorConfig& d) { d.nms_iou = 1.5; }), "detector/nms_iou");
  EXPECT_EQ(bad([](DetectorConfig& d) { d.mask_threshold = 1.0; }), "detector/mask_threshold");
  EXPECT_EQ(bad([](DetectorConfig& d) { d.class_map = {{"sofa", "sofa"}}; }), "detector/class_map");  // COCO says couch
  EXPECT_EQ(bad([](DetectorConfig& d) { d.class_map.clear(); }), "detector/class_map");
  EXPECT_EQ(bad([](DetectorConfig& d) { d.model_classes.push_back("chair"); }), "detector/model_classes");
  EXPECT_EQ(bad([](DetectorConfig& d) { d.backend = "tensorrt"; }), "detector/backend");
  EXPECT_EQ(bad([](DetectorConfig& d) { d.target = "cuda"; }), "detector/target");
}

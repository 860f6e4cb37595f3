#include "semantic_exploration/core/detector/yolo_seg.hpp"

#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace semexp {

Letterbox Letterbox::fit(cv::Size image, cv::Size input) {
  if (image.width <= 0 || image.height <= 0 || input.width <= 0 || input.height <= 0)
    throw std::invalid_argument("letterbox: image and input sizes must be positive");
  const double s = std::min(static_cast<double>(input.width) / image.width,
                            static_cast<double>(input.height) / image.height);
  Letterbox lb;
  lb.input = input;
  lb.scaled = cv::Size(std::min(input.width, std::max(1, static_cast<int>(std::lround(s * image.width)))),
                       std::min(input.height, std::max(1, static_cast<int>(std::lround(s * image.height)))));
  lb.left = (input.width - lb.scaled.width) / 2;
  lb.top = (input.height - lb.scaled.height) / 2;
  lb.scale_x = static_cast<double>(lb.scaled.width) / image.width;
  lb.scale_y = static_cast<double>(lb.scaled.height) / image.height;
  return lb;
}

cv::Mat letterboxBlob(const cv::Mat& rgb, const Letterbox& lb) {
  if (rgb.type() != CV_8UC3) throw std::invalid_argument("letterbox: the colour image must be CV_8UC3");
  cv::Mat scaled;
  if (rgb.size() == lb.scaled)
    scaled = rgb;
  else
    cv::resize(rgb, scaled, lb.scaled, 0, 0, cv::INTER_LINEAR);
  cv::Mat padded;
  cv::copyMakeBorder(scaled, padded, lb.top, lb.input.height - lb.scaled.height - lb.top, lb.left,
                     lb.input.width - lb.scaled.width - lb.left, cv::BORDER_CONSTANT, cv::Scalar::all(114));
  return cv::dnn::blobFromImage(padded, 1.0 / 255.0);
}

namespace {

struct Candidate {
  int index;   // column of output0
  int cls;     // model class
  float conf;  // its score
  cv::Rect2d box;  // input px
};

double iou(const cv::Rect2d& a, const cv::Rect2d& b) {
  const double inter = (a & b).area();
  const double uni = a.area() + b.area() - inter;
  return uni > 0 ? inter / uni : 0.0;
}

// Columns (or rows) whose pixel centres, mapped to input px, lie in [lo, hi):
// [first, last], empty if last < first. The mapping is increasing in the pixel index.
void pixelRange(double lo, double hi, double scale, int offset, int n, int& first, int& last) {
  const auto centre = [&](int u) { return scale * (u + 0.5) + offset; };
  first = std::max(0, static_cast<int>(std::floor((lo - offset) / scale - 0.5)) - 1);
  while (first < n && centre(first) < lo) ++first;
  last = std::min(n - 1, static_cast<int>(std::ceil((hi - offset) / scale)) + 1);
  while (last >= 0 && !(centre(last) < hi)) --last;
}

// Bilinear sample positions along one axis: for each pixel of [first, last],
// the lower prototype index, the upper one and the weight of the upper.
struct Taps {
  std::vector<int> i0, i1;
  std::vector<float> w1;
};

Taps taps(int first, int last, double scale, int offset, double proto_per_input, int proto_n) {
  Taps t;
  for (int u = first; u <= last; ++u) {
    const double p = (scale * (u + 0.5) + offset) * proto_per_input - 0.5;  // prototype pixel coordinate
    const double f = std::floor(p);
    const int a = static_cast<int>(f);
    t.i0.push_back(std::clamp(a, 0, proto_n - 1));
    t.i1.push_back(std::clamp(a + 1, 0, proto_n - 1));
    t.w1.push_back(static_cast<float>(p - f));
  }
  return t;
}

}  // namespace

std::vector<SegmentedInstance> decodeYoloSeg(const cv::Mat& output0, const cv::Mat& output1, const Letterbox& lb,
                                             cv::Size image_size, const DetectorConfig& config) {
  if (output0.dims != 3 || output1.dims != 4 || output0.type() != CV_32F || output1.type() != CV_32F ||
      output0.size[0] != 1 || output1.size[0] != 1 || !output0.isContinuous() || !output1.isContinuous())
    throw std::invalid_argument(std::string("network outputs are not ") + kYoloSegLayout);
  const int nm = output1.size[1], mh = output1.size[2], mw = output1.size[3];
  const int rows = output0.size[1], n = output0.size[2];
  const int nc = rows - 4 - nm;
  if (nc != static_cast<int>(config.model_classes.size()))
    throw std::invalid_argument("output0 has " + std::to_string(rows) + " rows, output1 " + std::to_string(nm) +
                                " prototypes: " + std::to_string(nc) + " classes, but model_classes lists " +
                                std::to_string(config.model_classes.size()));
  // Project class of each model class, or "" for classes not mapped.
  std::vector<std::string> project(static_cast<std::size_t>(nc));
  for (int c = 0; c < nc; ++c) {
    const auto it = config.class_map.find(config.model_classes[static_cast<std::size_t>(c)]);
    if (it != config.class_map.end()) project[static_cast<std::size_t>(c)] = it->second;
  }
  const float* out = output0.ptr<float>();
  const auto at = [&](int row, int j) { return out[static_cast<std::size_t>(row) * n + j]; };

  // Best class per candidate, row by row (output0 is class-major: a column walk would miss the cache at every read).
  std::vector<float> best_score(out + static_cast<std::size_t>(4) * n, out + static_cast<std::size_t>(5) * n);
  std::vector<int> best_class(static_cast<std::size_t>(n), 0);
  for (int c = 1; c < nc; ++c) {
    const float* row = out + static_cast<std::size_t>(4 + c) * n;
    for (std::size_t j = 0; j < best_score.size(); ++j) {
      if (row[j] > best_score[j]) {
        best_score[j] = row[j];
        best_class[j] = c;
      }
    }
  }
  std::vector<Candidate> cands;
  for (int j = 0; j < n; ++j) {
    const int best = best_class[static_cast<std::size_t>(j)];
    const float score = best_score[static_cast<std::size_t>(j)];
    if (!(score >= config.conf_threshold) || project[static_cast<std::size_t>(best)].empty()) continue;
    const double cx = at(0, j), cy = at(1, j), w = at(2, j), h = at(3, j);
    // A box must be finite and of sane size (a broken model's NaN or 1e30 would overflow pixel indices).
    const double lim = 1e6;
    if (!(w > 0 && h > 0 && w < lim && h < lim && std::abs(cx) < lim && std::abs(cy) < lim)) continue;
    cands.push_back({j, best, score, cv::Rect2d(cx - 0.5 * w, cy - 0.5 * h, w, h)});
  }
  std::stable_sort(cands.begin(), cands.end(), [](const Candidate& a, const Candidate& b) { return a.conf > b.conf; });
  std::vector<Candidate> kept;
  for (const auto& c : cands) {
    const bool suppressed = std::any_of(kept.begin(), kept.end(), [&](const Candidate& k) {
      return k.cls == c.cls && iou(k.box, c.box) > config.nms_iou;
    });
    if (!suppressed) kept.push_back(c);
  }
  if (kept.empty()) return {};

  const float* protos = output1.ptr<float>();
  const std::size_t plane = static_cast<std::size_t>(mh) * mw;
  const double px_per_input_x = static_cast<double>(mw) / lb.input.width;
  const double px_per_input_y = static_cast<double>(mh) / lb.input.height;
  const float thr = static_cast<float>(config.mask_threshold);
  std::vector<SegmentedInstance> result;
  std::vector<float> prob;
  for (const Candidate& c : kept) {
    SegmentedInstance inst;
    inst.model_class = c.cls;
    inst.class_name = project[static_cast<std::size_t>(c.cls)];
    inst.confidence = c.conf;
    inst.box_input = c.box;
    int u0, u1, v0, v1;
    pixelRange(c.box.x, c.box.x + c.box.width, lb.scale_x, lb.left, image_size.width, u0, u1);
    pixelRange(c.box.y, c.box.y + c.box.height, lb.scale_y, lb.top, image_size.height, v0, v1);
    if (u1 >= u0 && v1 >= v0) {
      inst.roi = cv::Rect(u0, v0, u1 - u0 + 1, v1 - v0 + 1);
      inst.mask = cv::Mat::zeros(inst.roi.size(), CV_8UC1);
      Taps tx = taps(u0, u1, lb.scale_x, lb.left, px_per_input_x, mw);
      const Taps ty = taps(v0, v1, lb.scale_y, lb.top, px_per_input_y, mh);
      // Mask probability sigmoid(coefficients . prototypes) on the prototype pixels the box samples only
      // (taps increase along each axis: the first tap's lower and the last tap's upper index bound them).
      const int px0 = tx.i0.front(), px1 = tx.i1.back(), py0 = ty.i0.front(), py1 = ty.i1.back();
      const int rw = px1 - px0 + 1, rh = py1 - py0 + 1;
      prob.assign(static_cast<std::size_t>(rw) * rh, 0.0f);
      for (int m = 0; m < nm; ++m) {
        const float coeff = at(4 + nc + m, c.index);
        if (coeff == 0.0f) continue;
        for (int y = 0; y < rh; ++y) {
          const float* src = protos + m * plane + static_cast<std::size_t>(py0 + y) * mw + px0;
          float* dst = prob.data() + static_cast<std::size_t>(y) * rw;
          for (int x = 0; x < rw; ++x) dst[x] += coeff * src[x];
        }
      }
      for (float& v : prob) v = 1.0f / (1.0f + std::exp(-v));
      for (std::size_t q = 0; q < tx.i0.size(); ++q) tx.i0[q] -= px0, tx.i1[q] -= px0;  // columns of `prob`
      for (int r = 0; r < inst.roi.height; ++r) {
        const float* row0 = prob.data() + static_cast<std::size_t>(ty.i0[r] - py0) * rw;
        const float* row1 = prob.data() + static_cast<std::size_t>(ty.i1[r] - py0) * rw;
        const float wy = ty.w1[r];
        std::uint8_t* dst = inst.mask.ptr<std::uint8_t>(r);
        for (int q = 0; q < inst.roi.width; ++q) {
          const float wx = tx.w1[q];
          const float top = row0[tx.i0[q]] + wx * (row0[tx.i1[q]] - row0[tx.i0[q]]);
          const float bottom = row1[tx.i0[q]] + wx * (row1[tx.i1[q]] - row1[tx.i0[q]]);
          if (top + wy * (bottom - top) > thr) dst[q] = 255;
        }
      }
    }
    result.push_back(std::move(inst));
  }
  return result;
}

InstanceImage renderInstances(const std::vector<SegmentedInstance>& instances, cv::Size image_size, cv::Size out_size) {
  if (instances.size() >= 65535) throw std::invalid_argument("more than 65534 instances do not fit a 16-bit image");
  std::vector<std::size_t> order(instances.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return instances[a].confidence > instances[b].confidence; });
  cv::Mat full = cv::Mat::zeros(image_size, CV_16UC1);
  const cv::Rect whole(cv::Point(0, 0), image_size);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const SegmentedInstance& inst = instances[order[k]];
    const auto id = static_cast<std::uint16_t>(k + 1);
    if (inst.roi.empty() || (inst.roi & whole) != inst.roi || inst.mask.size() != inst.roi.size()) continue;
    for (int r = 0; r < inst.roi.height; ++r) {
      const std::uint8_t* m = inst.mask.ptr<std::uint8_t>(r);
      std::uint16_t* dst = full.ptr<std::uint16_t>(inst.roi.y + r) + inst.roi.x;
      for (int q = 0; q < inst.roi.width; ++q)
        if (m[q] && !dst[q]) dst[q] = id;
    }
  }
  InstanceImage out;
  if (out_size == image_size) {
    out.ids = full;
  } else {  // nearest neighbour, pixel centre to pixel centre
    out.ids.create(out_size, CV_16UC1);
    std::vector<int> col(static_cast<std::size_t>(out_size.width));
    for (int u = 0; u < out_size.width; ++u)
      col[static_cast<std::size_t>(u)] = std::min(
          image_size.width - 1, static_cast<int>(std::floor((u + 0.5) * image_size.width / out_size.width)));
    for (int v = 0; v < out_size.height; ++v) {
      const int sv = std::min(image_size.height - 1,
                              static_cast<int>(std::floor((v + 0.5) * image_size.height / out_size.height)));
      const std::uint16_t* src = full.ptr<std::uint16_t>(sv);
      std::uint16_t* dst = out.ids.ptr<std::uint16_t>(v);
      for (int u = 0; u < out_size.width; ++u) dst[u] = src[col[static_cast<std::size_t>(u)]];
    }
  }
  // Count, then renumber the instances that kept pixels 1..n.
  std::vector<std::uint32_t> count(order.size() + 1, 0);
  for (int v = 0; v < out.ids.rows; ++v) {
    const std::uint16_t* p = out.ids.ptr<std::uint16_t>(v);
    for (int u = 0; u < out.ids.cols; ++u) ++count[p[u]];
  }
  std::vector<std::uint16_t> lut(order.size() + 1, 0);
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (!count[k + 1]) continue;
    const SegmentedInstance& inst = instances[order[k]];
    InstanceEntry e;
    e.instance_id = static_cast<std::uint16_t>(out.entries.size() + 1);
    e.model_class = inst.model_class;
    e.class_name = inst.class_name;
    e.confidence = inst.confidence;
    e.pixel_count = count[k + 1];
    lut[k + 1] = e.instance_id;
    out.entries.push_back(e);
  }
  if (out.entries.size() != order.size()) {
    for (int v = 0; v < out.ids.rows; ++v) {
      std::uint16_t* p = out.ids.ptr<std::uint16_t>(v);
      for (int u = 0; u < out.ids.cols; ++u) p[u] = lut[p[u]];
    }
  }
  return out;
}

}  // namespace semexp

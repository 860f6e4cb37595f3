#include "semantic_exploration/core/object_masks.hpp"

#include <algorithm>
#include <cmath>
#include <vector>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace semexp {

int markDepthEdges(cv::Mat& mask, const cv::Mat& depth_m, const PinholeCamera& camera, const DepthEdgeParams& params,
                   std::uint8_t unknown_value) {
  if (mask.type() != CV_8UC1 || depth_m.type() != CV_32FC1 || mask.size() != depth_m.size())
    throw std::invalid_argument("markDepthEdges: mask (8UC1) and depth (32FC1) must be of one size");
  if (params.window_px <= 0 || mask.empty()) return 0;
  // Work on the mask's box grown by the window (a mask is a small part of the image).
  const cv::Rect box = cv::boundingRect(mask);
  if (box.empty()) return 0;
  const int grow = params.window_px + 2;
  const cv::Rect roi =
      (box + cv::Point(-grow, -grow) + cv::Size(2 * grow, 2 * grow)) & cv::Rect(0, 0, mask.cols, mask.rows);
  const cv::Mat m = mask(roi), d = depth_m(roi);
  // Depth of the mask's valid pixels, a far constant elsewhere (finite: the median sorts it).
  constexpr float kFar = 1e6f;
  cv::Mat near(roi.size(), CV_32FC1, cv::Scalar(kFar));
  for (int v = 0; v < roi.height; ++v) {
    const std::uint8_t* mr = m.ptr<std::uint8_t>(v);
    const float* dr = d.ptr<float>(v);
    float* nr = near.ptr<float>(v);
    for (int u = 0; u < roi.width; ++u) {
      const float z = dr[u];
      if (mr[u] && std::isfinite(z) && z > 0.f && z >= camera.d_min_m && z <= camera.d_max_m) nr[u] = z;
    }
  }
  cv::Mat median, nearest;
  cv::medianBlur(near, median, 5);
  const int k = 2 * params.window_px + 1;
  cv::erode(median, nearest, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)));
  int marked = 0;
  for (int v = 0; v < roi.height; ++v) {
    std::uint8_t* mr = mask.ptr<std::uint8_t>(roi.y + v) + roi.x;
    const float* nr = near.ptr<float>(v);
    const float* md = median.ptr<float>(v);
    const float* ref = nearest.ptr<float>(v);
    for (int u = 0; u < roi.width; ++u) {
      if (!mr[u] || nr[u] >= kFar || ref[u] >= kFar) continue;
      // A pixel whose own neighbourhood is mostly outside the mask keeps its raw depth.
      const float z = md[u] < kFar ? md[u] : nr[u];
      if (z > ref[u] + static_cast<float>(params.edge_m + params.edge_rel * ref[u])) {
        mr[u] = unknown_value;
        ++marked;
      }
    }
  }
  return marked;
}

int markMaskBorder(cv::Mat& mask, const cv::Mat& detected, int border_px) {
  if (mask.type() != CV_8UC1 || detected.type() != CV_8UC1 || mask.size() != detected.size())
    throw std::invalid_argument("markMaskBorder: mask and detected mask must be 8UC1 of one size");
  if (border_px < 0 || border_px > 126) throw std::invalid_argument("markMaskBorder: border_px must be in [0, 126]");
  if (border_px == 0 || mask.empty()) return 0;
  const cv::Rect box = cv::boundingRect(mask == 255);
  if (box.empty()) return 0;
  // The distance to the detected mask's outside, on the mask's box grown by the border (plus one pixel that
  // may be outside); past the image edge the detected mask is continued (replicated).
  const int grow = border_px + 1;
  cv::Mat padded;
  cv::copyMakeBorder(detected, padded, grow, grow, grow, grow, cv::BORDER_REPLICATE);
  const cv::Rect roi(box.x, box.y, box.width + 2 * grow, box.height + 2 * grow);
  cv::Mat inside = padded(roi) != 0, distance;
  cv::distanceTransform(inside, distance, cv::DIST_C, 3);
  int marked = 0;
  for (int v = 0; v < box.height; ++v) {
    std::uint8_t* mr = mask.ptr<std::uint8_t>(box.y + v) + box.x;
    const float* dr = distance.ptr<float>(v + grow) + grow;
    for (int u = 0; u < box.width; ++u) {
      const int k = static_cast<int>(std::lround(dr[u]));
      if (mr[u] != 255 || k > border_px || k < 1) continue;
      mr[u] = static_cast<std::uint8_t>(128 + std::lround(127.0 * k / (border_px + 1)));
      ++marked;
    }
  }
  return marked;
}

namespace {

std::vector<Eigen::Vector3f> maskPoints_C(const cv::Mat& mask, const cv::Mat& depth_m, const PinholeCamera& camera) {
  std::vector<Eigen::Vector3f> points;
  for (int v = 0; v < mask.rows; ++v) {
    const std::uint8_t* mr = mask.ptr<std::uint8_t>(v);
    const float* dr = depth_m.ptr<float>(v);
    for (int u = 0; u < mask.cols; ++u) {
      const float z = dr[u];
      if (mr[u] == 255 && std::isfinite(z) && z > 0.f && z >= camera.d_min_m && z <= camera.d_max_m)
        points.push_back(camera.ray_C(static_cast<float>(u), static_cast<float>(v)) * z);
    }
  }
  return points;
}

// The value with `fraction` of `values` below it.
float quantile(std::vector<float> values, double fraction) {
  const auto k = static_cast<std::ptrdiff_t>(fraction * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[static_cast<size_t>(k)];
}

}  // namespace

MaskSeparation separateMasks(const cv::Mat& mask_a, const cv::Mat& mask_b, const cv::Mat& depth_m,
                             const PinholeCamera& camera) {
  if (mask_a.type() != CV_8UC1 || mask_b.type() != CV_8UC1 || depth_m.type() != CV_32FC1 ||
      mask_a.size() != depth_m.size() || mask_b.size() != depth_m.size())
    throw std::invalid_argument("separateMasks: masks (8UC1) and depth (32FC1) must be of one size");
  MaskSeparation out;
  const std::vector<Eigen::Vector3f> a = maskPoints_C(mask_a, depth_m, camera);
  const std::vector<Eigen::Vector3f> b = maskPoints_C(mask_b, depth_m, camera);
  constexpr size_t kMinPoints = 20;
  if (a.size() < kMinPoints || b.size() < kMinPoints) return out;
  Eigen::Vector3f ca = Eigen::Vector3f::Zero(), cb = Eigen::Vector3f::Zero();
  for (const auto& p : a) ca += p;
  for (const auto& p : b) cb += p;
  ca /= static_cast<float>(a.size());
  cb /= static_cast<float>(b.size());
  if ((cb - ca).norm() < 1e-6f) {  // one centroid: overlapping
    out.gap_m = -1.0;
    return out;
  }
  out.normal_C = (cb - ca).normalized();
  std::vector<float> pa, pb;
  for (const auto& p : a) pa.push_back(p.dot(out.normal_C));
  for (const auto& p : b) pb.push_back(p.dot(out.normal_C));
  constexpr double kTrim = 0.02;
  const float a_far = quantile(pa, 1.0 - kTrim), b_near = quantile(pb, kTrim);
  out.gap_m = static_cast<double>(b_near - a_far);
  out.plane_m = 0.5 * (static_cast<double>(a_far) + b_near);
  return out;
}

}  // namespace semexp

#include "semantic_exploration/core/planning/candidate_evaluation.hpp"

#include "semantic_exploration/core/planning/interfaces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace semexp {

namespace {

void checkSize(const GainImage& img, const char* what, int& w, int& h) {
  if (img.empty()) return;
  if (img.values.size() != static_cast<std::size_t>(img.width) * img.height)
    throw std::invalid_argument(std::string("combineGains: ") + what + " has inconsistent size");
  if (img.width != w || img.height != h)
    throw std::invalid_argument(std::string("combineGains: ") + what + " is " + std::to_string(img.width) + "x" +
                                std::to_string(img.height) + ", expected " + std::to_string(w) + "x" +
                                std::to_string(h));
}

double wrapPi(double a) {
  a = std::remainder(a, 2.0 * M_PI);  // [-pi, pi]
  return a <= -M_PI ? a + 2.0 * M_PI : a;
}

}  // namespace

GainImage combineGains(const GainWeights& wgt, const GainSet& g, const std::vector<std::uint8_t>& mask, int width,
                        int height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("combineGains: width and height must be > 0");
  checkSize(g.entropy, "entropy gain", width, height);
  checkSize(g.background, "background gain", width, height);
  checkSize(g.object, "object gain", width, height);
  const std::size_t n = static_cast<std::size_t>(width) * height;
  if (!mask.empty() && mask.size() != n) throw std::invalid_argument("combineGains: mask size mismatch");
  GainImage out(width, height);
  for (std::size_t i = 0; i < n; ++i) {
    if (!mask.empty() && mask[i] == 0) continue;
    double v = 0.0;
    if (!g.entropy.empty()) v += wgt.a_ent * g.entropy.values[i];
    if (!g.background.empty()) v += wgt.a_bg * g.background.values[i];
    if (!g.object.empty()) v += wgt.a_obj * g.object.values[i];
    out.values[i] = static_cast<float>(v);
  }
  return out;
}

std::vector<float> objectOcclusionDepths_m(const std::vector<float>& background_hit_depth_m,
                                             double background_resolution_m) {
  if (!(std::isfinite(background_resolution_m) && background_resolution_m > 0))
    throw std::invalid_argument("objectOcclusionDepths_m: background_resolution_m must be > 0");
  const float margin_m = static_cast<float>(2.0 * background_resolution_m);
  std::vector<float> out(background_hit_depth_m);
  for (float& d : out)
    if (std::isfinite(d)) d += margin_m;
  return out;
}

std::vector<float> objectRayLimits_m(const Eigen::Vector3d& position_W, const SphericalGrid& grid,
                                       const std::vector<float>& background_hit_depth_m,
                                       double background_resolution_m, const std::vector<ObjectSummary>& objects) {
  const std::size_t n = static_cast<std::size_t>(grid.width) * grid.height;
  if (background_hit_depth_m.size() != n)
    throw std::invalid_argument("objectRayLimits_m: need width * height hit depths");
  std::vector<float> out = objectOcclusionDepths_m(background_hit_depth_m, background_resolution_m);
  const double margin_m = 2.0 * background_resolution_m;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(out[i])) continue;
    const Eigen::Vector3d dir = grid.direction(static_cast<int>(i) % grid.width, static_cast<int>(i) / grid.width);
    // A limit may pass into another object's box after leaving one: repeat (bounded by the object count).
    for (std::size_t pass = 0; pass <= objects.size(); ++pass) {
      const Eigen::Vector3d q = position_W + static_cast<double>(out[i]) * dir;
      double exit_t = -1.0;
      for (const ObjectSummary& o : objects) {
        const Eigen::Vector3d lo = o.bbox_min_W.array() - margin_m, hi = o.bbox_max_W.array() + margin_m;
        if ((q.array() < lo.array()).any() || (q.array() > hi.array()).any()) continue;
        double t_exit = std::numeric_limits<double>::infinity();
        for (int k = 0; k < 3; ++k)
          if (std::abs(dir[k]) > 1e-12) t_exit = std::min(t_exit, ((dir[k] > 0 ? hi[k] : lo[k]) - position_W[k]) / dir[k]);
        exit_t = std::max(exit_t, t_exit);
      }
      if (!(exit_t > out[i])) break;
      out[i] = static_cast<float>(exit_t + margin_m);
    }
  }
  return out;
}

std::vector<float> objectRayLimitsBatch(const std::vector<Eigen::Vector3d>& positions_W, const SphericalGrid& grid,
                                        const std::vector<GainImage>& hit_depths_m, double background_resolution_m,
                                        const std::vector<ObjectSummary>& objects) {
  if (hit_depths_m.size() != positions_W.size())
    throw std::invalid_argument("objectRayLimitsBatch: " + std::to_string(hit_depths_m.size()) +
                                " hit depth images for " + std::to_string(positions_W.size()) + " positions");
  for (const auto& d : hit_depths_m)
    if (d.empty()) return {};
  std::vector<float> out;
  out.reserve(positions_W.size() * static_cast<std::size_t>(grid.width) * grid.height);
  for (std::size_t i = 0; i < positions_W.size(); ++i) {
    const std::vector<float> limits =
        objectRayLimits_m(positions_W[i], grid, hit_depths_m[i].values, background_resolution_m, objects);
    out.insert(out.end(), limits.begin(), limits.end());
  }
  return out;
}

int windowColumns(double hfov_rad, int width) {
  const int k = static_cast<int>(std::lround(hfov_rad / (2.0 * M_PI) * width));
  return std::clamp(k, 1, std::max(1, width));
}

double windowMean(const GainImage& img, int first, int columns) {
  if (img.empty() || columns <= 0) return 0.0;
  double sum = 0.0;
  for (int c = 0; c < columns; ++c) {
    const int u = ((first + c) % img.width + img.width) % img.width;
    for (int v = 0; v < img.height; ++v) sum += img.at(u, v);
  }
  return sum / (static_cast<double>(columns) * img.height);
}

YawWindow bestYaw(const GainImage& img, int columns) {
  if (img.empty() || img.width <= 0 || img.height <= 0) throw std::invalid_argument("bestYaw: empty image");
  columns = std::clamp(columns, 1, img.width);
  // Column sums once, then a circular running sum: O(width * height).
  std::vector<double> col(static_cast<std::size_t>(img.width), 0.0);
  for (int v = 0; v < img.height; ++v)
    for (int u = 0; u < img.width; ++u) col[static_cast<std::size_t>(u)] += img.at(u, v);
  double sum = 0.0;
  for (int c = 0; c < columns; ++c) sum += col[static_cast<std::size_t>(c)];
  double best = sum;
  int best_first = 0;
  for (int s = 1; s < img.width; ++s) {
    sum += col[static_cast<std::size_t>((s + columns - 1) % img.width)] - col[static_cast<std::size_t>(s - 1)];
    if (sum > best + 1e-12) {
      best = sum;
      best_first = s;
    }
  }
  YawWindow w;
  w.first_column = best_first;
  w.columns = columns;
  w.gain = best / (static_cast<double>(columns) * img.height);
  w.yaw_rad = wrapPi(-M_PI + 2.0 * M_PI * (best_first + 0.5 * columns) / img.width);
  return w;
}

double pathLength_m(const std::vector<Eigen::Vector3d>& path) {
  double l = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) l += (path[i] - path[i - 1]).norm();
  return l;
}

double yawDifference_rad(double a, double b) { return std::abs(wrapPi(a - b)); }

double pathTime_s(const std::vector<Eigen::Vector3d>& path, double yaw_start, double yaw_end, double v_max,
                   double omega_max) {
  return std::max(pathLength_m(path) / v_max, yawDifference_rad(yaw_start, yaw_end) / omega_max);
}

double utility(double gain, double time_s, double min_time_s) { return gain / std::max(time_s, min_time_s); }

}  // namespace semexp

#pragma once
/// @file rendering.hpp
/// The one camera loop of the test scenes: exact, noise-free depth images of
/// analytic scenes (z-depth along the optical axis, m; 0 = no return).

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/depth_noise.hpp"
#include "shapes.hpp"

namespace semexp_test {

/// The optical ray (z = 1) through the centre of pixel (u, v), in double
/// precision. PinholeCamera::ray_C rounds it to float, and whether the
/// optimiser keeps that rounding differs between call sites (GCC 12 -O3
/// drops it in some): exact scenes want the same image wherever they are
/// rendered.
inline Eigen::Vector3d pixelRay_C(const semexp::PinholeCamera& cam, int u, int v) {
  return {(u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0};
}

/// Depth image (CV_32FC1) of `cam` whose pixel (u, v) is depth_of(u, v, r_C), r_C
/// the pixel's optical ray (z = 1): a hit at T_WC.translation() + t R_WC r_C
/// lies at z-depth t.
template <class DepthOf>
cv::Mat renderDepthImage(const semexp::PinholeCamera& cam, DepthOf&& depth_of) {
  cv::Mat depth(cam.height, cam.width, CV_32FC1);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) depth.at<float>(v, u) = depth_of(u, v, pixelRay_C(cam, u, v));
  return depth;
}

/// Depth (32FC1, 0 where nothing is hit, whatever d_max) of the nearest of
/// `shapes` seen by `cam` at T_WC, and the index + 1 of the shape seen per
/// pixel (16UC1, 0 = none).
inline void renderShapes(const semexp::PinholeCamera& cam, const Eigen::Isometry3d& T_WC,
                         const std::vector<const Shape*>& shapes, cv::Mat& depth_m, cv::Mat& labels) {
  labels = cv::Mat::zeros(cam.height, cam.width, CV_16UC1);
  depth_m = renderDepthImage(cam, [&](int u, int v, const Eigen::Vector3d& r_C) {
    double s;
    const int k = nearestHit(shapes, T_WC.translation(), T_WC.linear() * r_C, s);
    if (k < 0) return 0.f;
    labels.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(k + 1);
    return static_cast<float>(s);
  });
}

/// Adds depth noise to every return of a z-depth image (CV_32FC1): Gaussian
/// with the standard deviation noise.sigma(d) (the simulator's model; Table I's
/// values by default).
inline void addQuadraticDepthNoise(cv::Mat& depth_m, std::mt19937& rng, const semexp::DepthNoise& noise = {}) {
  for (int v = 0; v < depth_m.rows; ++v)
    for (int u = 0; u < depth_m.cols; ++u) {
      float& d = depth_m.at<float>(v, u);
      if (d <= 0.f) continue;
      d += static_cast<float>(std::normal_distribution<double>(0.0, noise.sigma(d))(rng));
    }
}

}  // namespace semexp_test

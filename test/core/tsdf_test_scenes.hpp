#pragma once
// Analytic test scenes for the object TSDF tests: shapes with an exact signed
// distance and exact ray intersection, depth/mask rendering and camera rings.

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "semantic_exploration/core/camera.hpp"
#include "test_shapes.hpp"

namespace semexp_test {

/// Camera at eye_W looking at target_W (optical frame, world z up).
inline Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye_W, const Eigen::Vector3d& target_W) {
  const Eigen::Vector3d z = (target_W - eye_W).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  T_WC.linear().col(0) = x;
  T_WC.linear().col(1) = y;
  T_WC.linear().col(2) = z;
  T_WC.translation() = eye_W;
  return T_WC;
}

/// n poses on a horizontal circle of `radius` around target at height offset dz, looking at target.
inline std::vector<Eigen::Isometry3d> ring(const Eigen::Vector3d& target, double radius, double dz, int n,
                                           double phase = 0.0) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < n; ++i) {
    const double a = phase + 2.0 * M_PI * i / n;
    poses.push_back(lookAt(target + Eigen::Vector3d(radius * std::cos(a), radius * std::sin(a), dz), target));
  }
  return poses;
}

/// Noise-free depth (32FC1, 0 where nothing is hit) of the nearest of `shapes`,
/// and the index + 1 of the shape seen per pixel (16UC1, 0 = none).
inline void renderShapes(const semexp::PinholeCamera& cam, const Eigen::Isometry3d& T_WC,
                         const std::vector<const Shape*>& shapes, cv::Mat& depth_m, cv::Mat& labels) {
  depth_m = cv::Mat::zeros(cam.height, cam.width, CV_32FC1);
  labels = cv::Mat::zeros(cam.height, cam.width, CV_16UC1);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d d_W = T_WC.linear() * cam.ray_C(static_cast<float>(u), static_cast<float>(v)).cast<double>();
      double best = std::numeric_limits<double>::infinity();
      for (size_t k = 0; k < shapes.size(); ++k) {
        double s;
        if (shapes[k]->intersect(T_WC.translation(), d_W, s) && s < best) {
          best = s;
          labels.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(k + 1);
        }
      }
      if (std::isfinite(best)) depth_m.at<float>(v, u) = static_cast<float>(best);  // ray has z = 1
    }
}

}  // namespace semexp_test

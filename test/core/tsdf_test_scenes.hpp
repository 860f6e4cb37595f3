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

namespace semexp_test {

struct Shape {
  virtual ~Shape() = default;
  /// Exact signed distance (negative inside), m.
  virtual double sdf(const Eigen::Vector3d& p_W) const = 0;
  /// Smallest s > 0 with o + s d on the surface (d need not be unit).
  virtual bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& s) const = 0;
};

struct Sphere : Shape {
  Eigen::Vector3d centre;
  double radius;
  Sphere(const Eigen::Vector3d& c, double r) : centre(c), radius(r) {}
  double sdf(const Eigen::Vector3d& p) const override { return (p - centre).norm() - radius; }
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& s) const override {
    const Eigen::Vector3d oc = o - centre;
    const double a = d.squaredNorm(), b = 2.0 * oc.dot(d), c = oc.squaredNorm() - radius * radius;
    const double disc = b * b - 4 * a * c;
    if (disc < 0) return false;
    s = (-b - std::sqrt(disc)) / (2 * a);
    return s > 0;
  }
};

struct Box : Shape {
  Eigen::Vector3d centre, half;
  Box(const Eigen::Vector3d& c, const Eigen::Vector3d& h) : centre(c), half(h) {}
  double sdf(const Eigen::Vector3d& p) const override {
    const Eigen::Vector3d q = (p - centre).cwiseAbs() - half;
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
  }
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& s) const override {
    double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
      const double lo = centre[i] - half[i], hi = centre[i] + half[i];
      if (std::abs(d[i]) < 1e-12) {
        if (o[i] < lo || o[i] > hi) return false;
        continue;
      }
      double a = (lo - o[i]) / d[i], b = (hi - o[i]) / d[i];
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
    }
    if (t0 > t1 || t0 <= 0) return false;
    s = t0;
    return true;
  }
};

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

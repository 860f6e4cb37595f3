#pragma once
// Analytic box-room scenes for the background map tests: exact depth images
// (z-depth along the optical axis) and exact distances to the true surfaces.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "semantic_exploration/core/camera.hpp"
#include "test_shapes.hpp"

namespace semexp_test {

/// The inside of `room` (walls, floor, ceiling) plus solid boxes in it.
struct BoxRoom {
  Box room;
  std::vector<Box> boxes;

  /// Ray parameter of the first surface hit along o + t d (inf if none).
  double hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
    double best = std::numeric_limits<double>::infinity();
    // leaving the room
    double tr = best;
    for (int i = 0; i < 3; ++i) {
      if (d[i] > 0) tr = std::min(tr, (room.hi[i] - o[i]) / d[i]);
      if (d[i] < 0) tr = std::min(tr, (room.lo[i] - o[i]) / d[i]);
    }
    if (tr > 0) best = tr;
    for (const Box& b : boxes) {
      double t0 = -std::numeric_limits<double>::infinity(), t1 = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 3; ++i) {
        if (d[i] == 0) {
          if (o[i] < b.lo[i] || o[i] > b.hi[i]) t0 = t1 + 1;
          continue;
        }
        double a = (b.lo[i] - o[i]) / d[i], c = (b.hi[i] - o[i]) / d[i];
        if (a > c) std::swap(a, c);
        t0 = std::max(t0, a);
        t1 = std::min(t1, c);
      }
      if (t0 <= t1 && t0 > 0) best = std::min(best, t0);
    }
    return best;
  }

  /// Distance from p to the nearest true surface, m.
  double surfaceDistance(const Eigen::Vector3d& p) const {
    double d = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
      // wall planes (distance to the plane, clamped to the room's other extents is not needed inside)
      d = std::min(d, std::abs(p[i] - room.lo[i]));
      d = std::min(d, std::abs(p[i] - room.hi[i]));
    }
    for (const Box& b : boxes) {
      const Eigen::Vector3d q = (b.lo - p).cwiseMax(p - b.hi);
      const double outside = q.cwiseMax(0.0).norm();
      const double inside = std::min(0.0, q.maxCoeff());
      d = std::min(d, std::abs(outside + inside));
    }
    return d;
  }

  bool insideSolid(const Eigen::Vector3d& p) const {
    if ((p.array() < room.lo.array()).any() || (p.array() > room.hi.array()).any()) return true;
    for (const Box& b : boxes)
      if ((p.array() >= b.lo.array()).all() && (p.array() <= b.hi.array()).all()) return true;
    return false;
  }

  /// z-depth image (metres) seen by `cam` at T_WC; 0 where nothing is within d_max.
  std::vector<float> render(const semexp::PinholeCamera& cam, const Eigen::Isometry3d& T_WC) const {
    std::vector<float> depth(static_cast<std::size_t>(cam.width) * cam.height, 0.f);
    const Eigen::Vector3d o = T_WC.translation();
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u) {
        const Eigen::Vector3d r_C = cam.ray_C(static_cast<float>(u), static_cast<float>(v)).cast<double>();  // z = 1
        const double t = hit(o, T_WC.linear() * r_C);  // = z-depth since r_C.z = 1
        if (std::isfinite(t) && t <= cam.d_max_m) depth[static_cast<std::size_t>(v) * cam.width + u] = static_cast<float>(t);
      }
    return depth;
  }
};

/// Camera (optical frame) at `pos` looking along yaw (about +z from +x), pitched down by `tilt` rad.
inline Eigen::Isometry3d lookPose(const Eigen::Vector3d& pos, double yaw, double tilt) {
  // optical: z forward, x right, y down
  const Eigen::Vector3d fwd(std::cos(yaw) * std::cos(tilt), std::sin(yaw) * std::cos(tilt), -std::sin(tilt));
  const Eigen::Vector3d right = fwd.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = fwd.cross(right);
  Eigen::Matrix3d R;
  R.col(0) = right;
  R.col(1) = down;
  R.col(2) = fwd;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = pos;
  return T;
}

/// A room of 6 x 4.5 x 2.7 m with four boxes; walls deliberately off the voxel grid.
inline BoxRoom standardRoom() {
  BoxRoom s;
  s.room = {{-2.987, -2.013, 0.013}, {3.013, 2.487, 2.713}};
  s.boxes = {{{1.513, 0.613, 0.013}, {2.313, 1.613, 0.913}},
             {{-2.187, -1.613, 0.013}, {-1.287, -0.913, 1.413}},
             {{0.413, -1.887, 0.013}, {1.013, -1.287, 0.513}},
             {{-0.987, 1.213, 0.813}, {-0.487, 1.713, 1.213}}};  // floating shelf
  return s;
}

}  // namespace semexp_test

#pragma once
/// @file box_room.hpp
/// Analytic box-room scenes for the background map tests and benchmarks:
/// exact depth images and exact distances to the true surfaces.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "cameras.hpp"
#include "rendering.hpp"
#include "semantic_exploration/core/bounds.hpp"
#include "shapes.hpp"

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
    double s;
    nearestHit(boxes, o, d, s);
    return std::min(best, s);
  }

  /// Distance from p to the nearest true surface, m.
  double surfaceDistance(const Eigen::Vector3d& p) const {
    double d = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
      // wall planes (distance to the plane, clamped to the room's other extents is not needed inside)
      d = std::min(d, std::abs(p[i] - room.lo[i]));
      d = std::min(d, std::abs(p[i] - room.hi[i]));
    }
    for (const Box& b : boxes) d = std::min(d, std::abs(b.sdf(p)));
    return d;
  }

  /// Map bounds holding the room and `margin_m` more on every side, m.
  semexp::Bounds bounds(double margin_m = 0.0) const {
    semexp::Bounds b;
    b.min_m = room.lo - Eigen::Vector3d::Constant(margin_m);
    b.max_m = room.hi + Eigen::Vector3d::Constant(margin_m);
    return b;
  }

  bool insideSolid(const Eigen::Vector3d& p) const {
    if (!room.contains(p)) return true;
    for (const Box& b : boxes)
      if (b.contains(p)) return true;
    return false;
  }

  /// z-depth image (m, row-major) seen by `cam` at T_WC; 0 where nothing is within d_max.
  std::vector<float> render(const semexp::PinholeCamera& cam, const Eigen::Isometry3d& T_WC) const {
    const cv::Mat depth = renderDepthImage(cam, [&](int, int, const Eigen::Vector3d& r_C) {
      const double t = hit(T_WC.translation(), T_WC.linear() * r_C);  // = z-depth since r_C.z = 1
      return std::isfinite(t) && t <= cam.d_max_m ? static_cast<float>(t) : 0.f;
    });
    return std::vector<float>(depth.begin<float>(), depth.end<float>());
  }
};

/// A wall facing -x at x = 2.013 m (off the voxel grid) inside a generous box.
inline BoxRoom wallScene() {
  BoxRoom s;
  s.room = {{-8.0, -6.0, -4.0}, {2.013, 6.0, 4.0}};
  return s;
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

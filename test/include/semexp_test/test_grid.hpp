#pragma once
/// @file test_grid.hpp
/// A small dense voxel grid (unknown / free / occupied) standing in for the
/// background map in planning tests and benchmarks: sphere queries and a
/// simple 360-degree entropy raycast in the SphericalGrid layout. Also depth
/// images rendered from a grid and the room with a table that the map and
/// planning tests share.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "cameras.hpp"
#include "rendering.hpp"
#include "semantic_exploration/core/bounds.hpp"
#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/planning/candidate_evaluation.hpp"
#include "semantic_exploration/core/spherical_grid.hpp"

namespace semexp_test {

class TestGrid {
 public:
  enum State : std::int8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

  TestGrid(const semexp::Bounds& bounds, double res, State fill)
      : bounds_(bounds), res_(res),
        dims_(((bounds.max_m - bounds.min_m) / res).array().round().cast<int>().matrix()),
        cells_(static_cast<std::size_t>(dims_.prod()), fill) {}

  const semexp::Bounds& bounds() const { return bounds_; }
  double resolution() const { return res_; }

  /// Sets every voxel whose centre lies in [lo, hi].
  void fill_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, State s) {
    // The test is per axis, so each axis's index range is found once (the same
    // arithmetic as center()); a scan of every voxel per box was most of a
    // sanitizer build's test time.
    int first[3], last[3];
    for (int k = 0; k < 3; ++k) {
      first[k] = dims_[k];
      last[k] = -1;
      for (int i = 0; i < dims_[k]; ++i) {
        const double c = centerAxis(k, i);
        if (c >= lo[k] && c <= hi[k]) {
          if (last[k] < 0) first[k] = i;
          last[k] = i;
        }
      }
    }
    for (int z = first[2]; z <= last[2]; ++z)
      for (int y = first[1]; y <= last[1]; ++y)
        for (int x = first[0]; x <= last[0]; ++x) at({x, y, z}) = s;
  }

  Eigen::Vector3d center(const Eigen::Vector3i& i) const {
    return bounds_.min_m + (i.cast<double>().array() + 0.5).matrix() * res_;
  }
  /// Component k of center() for index i along that axis (the same arithmetic).
  double centerAxis(int k, int i) const { return bounds_.min_m[k] + (static_cast<double>(i) + 0.5) * res_; }
  bool index(const Eigen::Vector3d& p, Eigen::Vector3i& i) const {
    const Eigen::Vector3d f = ((p - bounds_.min_m) / res_).array().floor();
    i = f.cast<int>();
    return (i.array() >= 0).all() && (i.array() < dims_.array()).all();
  }
  State state(const Eigen::Vector3d& p) const {
    Eigen::Vector3i i;
    return index(p, i) ? at(i) : kUnknown;
  }

  /// Every voxel whose box meets the sphere has state `want` (or, with
  /// allow_unknown, is not occupied); space outside the grid is unknown.
  bool sphere_all(const Eigen::Vector3d& p, double r, bool allow_unknown) const {
    Eigen::Vector3i lo, hi;
    const bool in_lo = index(p - Eigen::Vector3d::Constant(r), lo);
    const bool in_hi = index(p + Eigen::Vector3d::Constant(r), hi);
    if ((!in_lo || !in_hi) && !allow_unknown) return false;
    lo = lo.cwiseMax(0);
    hi = hi.cwiseMin(dims_ - Eigen::Vector3i::Ones());
    const double h = 0.5 * res_;
    // Per axis, the distance from p to the voxel's box: hoisted out of the inner
    // loops (the same values as ((p - c).cwiseAbs() - h).cwiseMax(0) per voxel).
    // A slab whose own axis's term exceeds r^2 is skipped whole: a sum of
    // non-negative terms rounds to no less than any one of them.
    const auto gap = [&](int k, int i) { return std::max(std::abs(p[k] - centerAxis(k, i)) - h, 0.0); };
    const double r2 = r * r;
    std::vector<double> dx(static_cast<std::size_t>(std::max(0, hi.x() - lo.x() + 1)));
    for (int x = lo.x(); x <= hi.x(); ++x) dx[static_cast<std::size_t>(x - lo.x())] = gap(0, x);
    for (int z = lo.z(); z <= hi.z(); ++z) {
      const double dz = gap(2, z);
      if (dz * dz > r2) continue;
      for (int y = lo.y(); y <= hi.y(); ++y) {
        const double dy = gap(1, y);
        if (dy * dy > r2) continue;
        for (int x = lo.x(); x <= hi.x(); ++x) {
          if (Eigen::Vector3d(dx[static_cast<std::size_t>(x - lo.x())], dy, dz).squaredNorm() > r2) continue;
          const State s = at({x, y, z});
          if (s == kOccupied || (s == kUnknown && !allow_unknown)) return false;
        }
      }
    }
    return true;
  }
  bool sphereFree(const Eigen::Vector3d& p, double r) const { return sphere_all(p, r, false); }
  bool sphereNotOccupied(const Eigen::Vector3d& p, double r) const { return sphere_all(p, r, true); }

  /// Entropy gain image: per ray, the unknown voxels (entropy 1, known 0)
  /// passed until an occupied voxel or d_max, divided by (d_max - d_min) / res.
  semexp::GainImage entropy_gain(const Eigen::Vector3d& p, const semexp::SphericalGrid& g, double d_min,
                                 double d_max) const {
    semexp::GainImage img(g.width, g.height);
    const double norm = (d_max - d_min) / res_;
    for (int v = 0; v < g.height; ++v)
      for (int u = 0; u < g.width; ++u) {
        const Eigen::Vector3d dir = g.direction(u, v);
        double sum = 0.0;
        for (double t = d_min; t <= d_max; t += res_) {
          Eigen::Vector3i i;
          if (!index(p + t * dir, i)) break;
          const State s = at(i);
          if (s == kOccupied) break;
          if (s == kUnknown) sum += 1.0;
        }
        img.at(u, v) = static_cast<float>(std::min(1.0, sum / norm));
      }
    return img;
  }

  /// Distance along unit `dir` from `origin` to where the ray enters the
  /// first occupied voxel (exact voxel traversal); infinity if none within
  /// max_range_m or before leaving the grid.
  double first_hit(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_range_m) const {
    Eigen::Vector3i i;
    if (!index(origin, i)) return std::numeric_limits<double>::infinity();
    if (at(i) == kOccupied) return 0.0;
    Eigen::Vector3i step;
    Eigen::Vector3d t_max, t_delta;
    for (int k = 0; k < 3; ++k) {
      const double lo = bounds_.min_m[k] + i[k] * res_;
      if (dir[k] > 0) {
        step[k] = 1;
        t_max[k] = (lo + res_ - origin[k]) / dir[k];
        t_delta[k] = res_ / dir[k];
      } else if (dir[k] < 0) {
        step[k] = -1;
        t_max[k] = (lo - origin[k]) / dir[k];
        t_delta[k] = -res_ / dir[k];
      } else {
        step[k] = 0;
        t_max[k] = t_delta[k] = std::numeric_limits<double>::infinity();
      }
    }
    while (true) {
      int k = 0;
      if (t_max[1] < t_max[k]) k = 1;
      if (t_max[2] < t_max[k]) k = 2;
      const double t = t_max[k];
      if (t > max_range_m) return std::numeric_limits<double>::infinity();
      i[k] += step[k];
      if (i[k] < 0 || i[k] >= dims_[k]) return std::numeric_limits<double>::infinity();
      if (at(i) == kOccupied) return t;
      t_max[k] += t_delta[k];
    }
  }

  /// Centres of free voxels with an unknown 6-neighbour (inside the grid).
  std::vector<Eigen::Vector3d> frontiers() const {
    std::vector<Eigen::Vector3d> out;
    const Eigen::Vector3i n6[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int z = 0; z < dims_.z(); ++z)
      for (int y = 0; y < dims_.y(); ++y)
        for (int x = 0; x < dims_.x(); ++x) {
          const Eigen::Vector3i i(x, y, z);
          if (at(i) != kFree) continue;
          for (const auto& d : n6) {
            const Eigen::Vector3i j = i + d;
            if ((j.array() >= 0).all() && (j.array() < dims_.array()).all() && at(j) == kUnknown) {
              out.push_back(center(i));
              break;
            }
          }
        }
    return out;
  }

 private:
  State& at(const Eigen::Vector3i& i) {
    return cells_[(static_cast<std::size_t>(i.z()) * dims_.y() + i.y()) * dims_.x() + i.x()];
  }
  State at(const Eigen::Vector3i& i) const {
    return cells_[(static_cast<std::size_t>(i.z()) * dims_.y() + i.y()) * dims_.x() + i.x()];
  }

  semexp::Bounds bounds_;
  double res_;
  Eigen::Vector3i dims_;
  std::vector<State> cells_;
};

// ------------------------------------------------------------ scene fixtures

/// z-depth image (CV_32FC1, m) of `grid` seen by `cam` at T_WC: exact voxel
/// traversal to the first occupied voxel; 0 where there is none within d_max.
inline cv::Mat renderDepth(const TestGrid& grid, const semexp::PinholeCamera& cam, const Eigen::Isometry3d& T_WC) {
  return renderDepthImage(cam, [&](int, int, const Eigen::Vector3d& r_C) {
    const double n = r_C.norm();
    const double t = grid.first_hit(T_WC.translation(), T_WC.linear() * (r_C / n), cam.d_max_m * n);
    return std::isfinite(t) ? static_cast<float>(t / n) : 0.f;
  });
}

/// Bounds of tableRoom(): [0, 5] x [0, 4] x [0, 2.4] m.
inline semexp::Bounds tableRoomBounds() {
  semexp::Bounds b;
  b.min_m = {0.0, 0.0, 0.0};
  b.max_m = {5.0, 4.0, 2.4};
  return b;
}

/// A room at 4 cm: free inside [0.2, 4.8] x [0.2, 3.8] x [0.1, 2.3] m, occupied
/// around it (walls, floor, ceiling), and a table, the box [2.0, 2.6] x [1.0, 1.6] x [0.1, 0.9] m.
inline TestGrid tableRoom() {
  TestGrid room(tableRoomBounds(), 0.04, TestGrid::kOccupied);
  room.fill_box({0.2, 0.2, 0.1}, {4.8, 3.8, 2.3}, TestGrid::kFree);
  room.fill_box({2.0, 1.0, 0.1}, {2.6, 1.6, 0.9}, TestGrid::kOccupied);
  return room;
}

/// Integrates `frames` exact depth views of tableRoom() into `map` (an OccupancyMap, or anything with its
/// integrate(depth, colour, camera, T_WC)): the half-size camera, level, at (1.2 + step_m k, 2.0, 1.2) m with
/// yaw yaw_step_rad k for k = 0 .. frames - 1. The map holds free space (mostly uniform blocks), walls, the
/// table and unknown space beyond.
template <class Map>
void integrateTableRoomViews(Map& map, int frames, double step_m, double yaw_step_rad) {
  const TestGrid room = tableRoom();
  const semexp::PinholeCamera cam = halfSizeCamera();
  for (int k = 0; k < frames; ++k) {
    const Eigen::Isometry3d T = levelCameraPose({1.2 + step_m * k, 2.0, 1.2}, yaw_step_rad * k);
    map.integrate(renderDepth(room, cam, T), cv::Mat(), cam, T);
  }
}

}  // namespace semexp_test

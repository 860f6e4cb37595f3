#pragma once
/// @file shapes.hpp
/// Solids with an exact signed distance and an exact ray intersection: the
/// one definition of each that the scene helpers and tests share (the box
/// slab test here is also what BoxRoom uses for its furniture).

#include <Eigen/Core>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <vector>

namespace semexp_test {

struct Shape {
  virtual ~Shape() = default;
  /// Exact signed distance (negative inside), m.
  virtual double sdf(const Eigen::Vector3d& p_W) const = 0;
  /// Smallest s > 0 with o + s d on the surface (d need not be unit); false if none
  /// (also when o is inside the solid).
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

/// Solid axis-aligned box between the corners lo and hi, m.
struct Box : Shape {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero();
  Eigen::Vector3d hi = Eigen::Vector3d::Zero();

  Box() = default;
  Box(const Eigen::Vector3d& lo_, const Eigen::Vector3d& hi_) : lo(lo_), hi(hi_) {}
  /// The box reaching `half` from `centre` along each axis.
  static Box around(const Eigen::Vector3d& centre, const Eigen::Vector3d& half) {
    return Box(centre - half, centre + half);
  }
  Eigen::Vector3d centre() const { return 0.5 * (lo + hi); }
  Eigen::Vector3d half() const { return 0.5 * (hi - lo); }
  /// p in the closed box.
  bool contains(const Eigen::Vector3d& p) const {
    return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
  }

  double sdf(const Eigen::Vector3d& p) const override {
    const Eigen::Vector3d q = (p - centre()).cwiseAbs() - half();
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
  }
  /// Slab test: where o + s d (s >= 0) lies within all three slabs of the
  /// box, [t0, t1] (empty if t0 > t1); false if d runs parallel to an axis
  /// outside the box's slab on that axis.
  bool slabs(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& t0, double& t1) const {
    t0 = 0.0;
    t1 = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
      if (std::abs(d[i]) < 1e-12) {
        if (o[i] < lo[i] || o[i] > hi[i]) return false;
        continue;
      }
      double a = (lo[i] - o[i]) / d[i], b = (hi[i] - o[i]) / d[i];
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
    }
    return true;
  }
  /// Entry parameter of the ray into the box.
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& s) const override {
    double t0, t1;
    if (!slabs(o, d, t0, t1) || t0 > t1 || t0 <= 0) return false;
    s = t0;
    return true;
  }
};

namespace detail {
inline const Shape& shapeRef(const Shape& s) { return s; }
inline const Shape& shapeRef(const Shape* s) { return *s; }
}  // namespace detail

/// Index of the first of `shapes` (shapes or pointers to them) hit along
/// o + s d, with its entry parameter in s; -1 (s = inf) if none is hit.
template <class Shapes>
int nearestHit(const Shapes& shapes, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& s) {
  int best = -1;
  s = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    double t;
    if (detail::shapeRef(shapes[k]).intersect(o, d, t) && t < s) {
      s = t;
      best = static_cast<int>(k);
    }
  }
  return best;
}

/// Union of boxes: a chair, a table. The signed distance is exact outside and
/// on the surface (what mesh accuracy measures).
class BoxUnion : public Shape {
 public:
  /// Adds a part (lo <= hi on every axis: the bounds test below relies on
  /// it); the union's bounds grow to hold it.
  void add(const Box& part) {
    assert((part.lo.array() <= part.hi.array()).all());
    if (parts_.empty()) {
      bounds_ = part;
    } else {
      bounds_.lo = bounds_.lo.cwiseMin(part.lo);
      bounds_.hi = bounds_.hi.cwiseMax(part.hi);
    }
    parts_.push_back(part);
  }
  const std::vector<Box>& parts() const { return parts_; }
  /// The smallest box holding every part (meaningless while there is none).
  const Box& bounds() const { return bounds_; }

  double sdf(const Eigen::Vector3d& p) const override {
    double d = std::numeric_limits<double>::infinity();
    for (const Box& b : parts_) d = std::min(d, b.sdf(p));
    return d;
  }
  /// Most rays of a rendered frame miss the union: one slab test against its
  /// bounds spares the test of every part (a third of the time of the
  /// sanitized test that renders a chair most). It never rejects a ray that
  /// hits a part: the bounds' slabs hold each part's, computed the same way,
  /// and IEEE arithmetic is monotonic.
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& s) const override {
    double t0, t1;
    if (parts_.empty() || !bounds_.slabs(o, d, t0, t1) || t0 > t1) {
      s = std::numeric_limits<double>::infinity();  // as nearestHit leaves it on a miss
      return false;
    }
    return nearestHit(parts_, o, d, s) >= 0;
  }

 private:
  std::vector<Box> parts_;
  Box bounds_;
};

}  // namespace semexp_test

#pragma once
/// @file object_scenes.hpp
/// Scenes for the object-map tests on constructed frames: a chair made of
/// boxes, one frame run as the nodes run it (render the map from the pose,
/// match the detections to the render, integrate), and mesh accuracy.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <vector>

#include "cameras.hpp"
#include "rendering.hpp"
#include "semantic_exploration/core/instance_matching.hpp"
#include "semantic_exploration/core/object_map.hpp"
#include "shapes.hpp"

namespace semexp_test {

/// An object TSDF as the tests integrate it: 2 cm voxels (config's chair resolution), 8 cm truncation, 4 cm
/// carved behind the surface.
inline semexp::TsdfParams objectTsdfParams() {
  semexp::TsdfParams p;
  p.resolution_m = 0.02;
  p.truncation_m = 0.08;
  p.behind_surface_m = 0.04;
  return p;
}

/// The object map with the foreground prior measured in docs/BENCHMARKS.md (0.3 with the weight of 2
/// observations; off by default).
inline semexp::ObjectMapConfig objectMapConfigWithPrior() {
  semexp::ObjectMapConfig c;
  c.foreground_prior = 0.3;
  c.foreground_prior_weight = 2.0;
  return c;
}

/// A chair 0.44 m wide standing on z = 0 at (x, y), facing -x: a seat 0.45 m
/// high, a back up to 0.95 m on its +x side and four 4 cm legs.
inline BoxUnion chair(double x, double y) {
  BoxUnion c;
  const double h = 0.22;  // half width and depth of the seat
  c.add(Box(Eigen::Vector3d(x - h, y - h, 0.42), Eigen::Vector3d(x + h, y + h, 0.47)));
  c.add(Box(Eigen::Vector3d(x + h - 0.04, y - h, 0.47), Eigen::Vector3d(x + h, y + h, 0.95)));
  for (const double sx : {-1.0, 1.0})
    for (const double sy : {-1.0, 1.0}) {
      const Eigen::Vector3d corner(x + sx * (h - 0.02), y + sy * (h - 0.02), 0.0);
      c.add(Box::around(corner + Eigen::Vector3d(0, 0, 0.21), Eigen::Vector3d(0.02, 0.02, 0.21)));
    }
  return c;
}

/// One frame as instance_matching and object_map run it: the map is rendered
/// from T_WC occluded by the depth, the detections (instance ids of class
/// `class_id` in `instances`) are matched to the render and integrated with it.
inline semexp::FrameIntegration runFrame(semexp::ObjectMap& map, const semexp::PinholeCamera& cam,
                                         const Eigen::Isometry3d& T_WC, const cv::Mat& depth_m,
                                         const cv::Mat& instances, const std::vector<std::uint16_t>& ids,
                                         int class_id, const semexp::MatchingConfig& matching = {}) {
  cv::Mat rendered, cleaned;
  map.render(cam, T_WC, depth_m, rendered);
  const semexp::MatchingOutput out = semexp::matchDetections(instances, ids, rendered, matching, &cleaned);
  std::vector<semexp::ObjectDetection> detections;
  for (const semexp::MatchResult& r : out.detections)
    if (!r.dropped) detections.push_back({r.instance_id, r.object_id, class_id});
  return map.integrateFrame(cam, T_WC, depth_m, cv::Mat(), cleaned, detections, &rendered);
}

/// The tiny camera at the origin looking along +x at a wall whose face lies distance_m (default 1 m) ahead.
struct WallAhead {
  semexp::PinholeCamera cam = tinyCamera();
  Eigen::Isometry3d T_WC = lookAlong(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  cv::Mat depth;
  explicit WallAhead(double distance_m = 1.0) {
    const Box wall(Eigen::Vector3d(distance_m, -3.0, -3.0), Eigen::Vector3d(distance_m + 0.5, 3.0, 3.0));
    cv::Mat labels;
    renderShapes(cam, T_WC, {&wall}, depth, labels);
  }
  /// Integrates the view with every pixel's mask value `mask` (255 inside, 0 outside, 129-254 at a border).
  template <class Map>
  void into(Map& map, std::uint8_t mask, bool detected) const {
    map.integrate(cam, T_WC, depth, cv::Mat(), cv::Mat(depth.size(), CV_8U, cv::Scalar(mask)), detected);
  }
};

/// Root mean square of shape.sdf over the vertices, m (inf if none).
inline double rmse(const std::vector<Eigen::Vector3f>& vertices_W, const Shape& shape) {
  if (vertices_W.empty()) return std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (const auto& v : vertices_W) {
    const double d = shape.sdf(v.cast<double>());
    sum += d * d;
  }
  return std::sqrt(sum / static_cast<double>(vertices_W.size()));
}

}  // namespace semexp_test

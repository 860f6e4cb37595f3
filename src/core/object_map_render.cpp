// ObjectMap's ray casts through all objects: the object-id image a camera would see (render) and the object
// gain images of candidate positions (computeGains, Eq. 1 with d_obj).

#include "semantic_exploration/core/object_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace semexp {

double objectDistanceGain(double d_node_m, double d_exp_m, double d_desired_m, double d_max_m) {
  d_node_m = std::min(d_node_m, d_max_m);  // "never observed closer than range" counts as d_max
  if (d_node_m <= d_desired_m || d_node_m <= d_exp_m) return 0.0;
  return std::clamp((d_node_m - std::max(d_exp_m, d_desired_m)) / d_max_m, 0.0, 1.0);
}

void ObjectMap::render(const PinholeCamera& camera, const Eigen::Isometry3d& T_WC, const cv::Mat& depth_m,
                       cv::Mat& object_ids, cv::Mat* depth_out) const {
  const bool occlude = !depth_m.empty();
  if (occlude && (depth_m.type() != CV_32FC1 || depth_m.cols != camera.width || depth_m.rows != camera.height))
    throw std::invalid_argument("ObjectMap::render: depth must be 32FC1 of the camera's size");
  object_ids = cv::Mat::zeros(camera.height, camera.width, CV_16UC1);
  const float inf = std::numeric_limits<float>::infinity();
  cv::Mat t_best(camera.height, camera.width, CV_32FC1, cv::Scalar(inf));  // along the unit ray, m
  const Eigen::Isometry3f T_WCf = T_WC.cast<float>();
  const Eigen::Isometry3f T_CWf = T_WCf.inverse();
  const Eigen::Vector3f o_W = T_WCf.translation();
  const float tol = static_cast<float>(config_.render_depth_tolerance_m);
  const float tol_rel = static_cast<float>(config_.render_depth_tolerance_rel);
  const float d_max = static_cast<float>(camera.d_max_m);

  for (const auto& kv : objects_) {
    Eigen::AlignedBox3f box;
    if (!kv.second->tsdf.allocatedBox(box)) continue;
    // Image footprint of the object's box (whole image if the box reaches behind the camera).
    int u0 = 0, u1 = camera.width - 1, v0 = 0, v1 = camera.height - 1;
    bool behind = false, any_front = false;
    float umin = inf, umax = -inf, vmin = inf, vmax = -inf;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3f p_C = T_CWf * box.corner(static_cast<Eigen::AlignedBox3f::CornerType>(c));
      if (p_C.z() <= 1e-3f) {
        behind = true;
        continue;
      }
      any_front = true;
      Eigen::Vector2f uv(0.f, 0.f);
      camera.project(p_C, uv);
      umin = std::min(umin, uv.x());
      umax = std::max(umax, uv.x());
      vmin = std::min(vmin, uv.y());
      vmax = std::max(vmax, uv.y());
    }
    if (!any_front) continue;
    if (!behind) {
      u0 = std::max(u0, static_cast<int>(std::floor(umin)));
      u1 = std::min(u1, static_cast<int>(std::ceil(umax)));
      v0 = std::max(v0, static_cast<int>(std::floor(vmin)));
      v1 = std::min(v1, static_cast<int>(std::ceil(vmax)));
    }
    if (u0 > u1 || v0 > v1) continue;  // the box projects beside the image
    const auto id = static_cast<std::uint16_t>(kv.first);
    const float front_margin = static_cast<float>(kv.second->tsdf.params().truncation_m) + 4.f * tol;
    // Ray range of pixel (u, v) and its unit direction in world.
    const auto range = [&](int u, int v, float& t_min, float& t_max, Eigen::Vector3f& dir_W) {
      const Eigen::Vector3f ray = camera.ray_C(static_cast<float>(u), static_cast<float>(v));
      const float n = ray.norm();
      dir_W = T_WCf.linear() * (ray / n);
      t_max = std::min(t_best.at<float>(v, u), d_max * n);
      t_min = 0.f;
      if (occlude) {
        const float d = depth_m.at<float>(v, u);
        if (std::isfinite(d) && d > 0.f && d >= camera.d_min_m && d <= camera.d_max_m) {
          t_max = std::min(t_max, d * n * (1.f + tol_rel) + tol);
          // A surface well in front of the measured one would have been measured instead.
          t_min = std::max(0.f, d * n * (1.f - tol_rel) - front_margin);
        }
      }
    };
    const auto cast = [&](int u, int v) {
      float t_min, t_max;
      Eigen::Vector3f dir_W;
      range(u, v, t_min, t_max, dir_W);
      TsdfRayHit hit;
      return kv.second->tsdf.castRay(o_W, dir_W, t_min, t_max, hit) ? hit.distance_m : inf;
    };
    const auto write = [&](int u, int v, float t) {
      if (!std::isfinite(t)) return;
      t_best.at<float>(v, u) = t;
      object_ids.at<std::uint16_t>(v, u) = id;
    };
    // Adaptive subsampling: rays on every second row and column; a pixel
    // between four samples that all missed is a miss, between four hits it
    // takes their interpolated distance if that passes its own depth test;
    // anything else gets its own ray. Masks under min_mask_pixels are dropped
    // anyway, so 1-px slivers between samples do not matter.
    std::vector<int> us, vs;
    for (int u = u0; u <= u1; u += 2) us.push_back(u);
    if (us.back() != u1) us.push_back(u1);
    for (int v = v0; v <= v1; v += 2) vs.push_back(v);
    if (vs.back() != v1) vs.push_back(v1);
    std::vector<float> sample(us.size() * vs.size());
    for (size_t j = 0; j < vs.size(); ++j)
      for (size_t i = 0; i < us.size(); ++i) sample[j * us.size() + i] = cast(us[i], vs[j]);
    for (size_t j = 0; j < vs.size(); ++j)
      for (size_t i = 0; i < us.size(); ++i) write(us[i], vs[j], sample[j * us.size() + i]);
    for (size_t j = 0; j + 1 < vs.size(); ++j)
      for (size_t i = 0; i + 1 < us.size(); ++i) {
        const float c00 = sample[j * us.size() + i], c10 = sample[j * us.size() + i + 1];
        const float c01 = sample[(j + 1) * us.size() + i], c11 = sample[(j + 1) * us.size() + i + 1];
        const int n_hit = std::isfinite(c00) + std::isfinite(c10) + std::isfinite(c01) + std::isfinite(c11);
        if (n_hit == 0) continue;
        const int ua = us[i], ub = us[i + 1], va = vs[j], vb = vs[j + 1];
        for (int v = va; v <= vb; ++v)
          for (int u = ua; u <= ub; ++u) {
            if ((u == ua || u == ub) && (v == va || v == vb)) continue;  // a sample
            if ((v == vb && j + 2 < vs.size()) || (u == ub && i + 2 < us.size())) continue;  // next cell's
            if (n_hit == 4) {
              const float fu = ub > ua ? static_cast<float>(u - ua) / (ub - ua) : 0.f;
              const float fv = vb > va ? static_cast<float>(v - va) / (vb - va) : 0.f;
              const float t = (1 - fv) * ((1 - fu) * c00 + fu * c10) + fv * ((1 - fu) * c01 + fu * c11);
              float t_min, t_max;
              Eigen::Vector3f dir_W;
              range(u, v, t_min, t_max, dir_W);
              if (t >= t_min && t <= t_max) {
                write(u, v, t);
                continue;
              }
            }
            write(u, v, cast(u, v));
          }
      }
  }
  if (depth_out) {
    *depth_out = cv::Mat::zeros(camera.height, camera.width, CV_32FC1);
    for (int v = 0; v < camera.height; ++v)
      for (int u = 0; u < camera.width; ++u) {
        const float t = t_best.at<float>(v, u);
        if (std::isfinite(t))
          depth_out->at<float>(v, u) = t / camera.ray_C(static_cast<float>(u), static_cast<float>(v)).norm();
      }
  }
}

void ObjectMap::computeGains(const std::vector<Eigen::Vector3d>& positions_W, const SphericalGrid& grid,
                             const std::vector<float>& max_depth_m, double d_obj_m, double d_max_m,
                             std::vector<cv::Mat>& gains, std::vector<cv::Mat>& hit_depth_m) const {
  if (const std::string why = SphericalGrid::checkRequest(static_cast<long>(positions_W.size()), grid.width,
                                                         grid.height); !why.empty())
    throw std::invalid_argument("ObjectMap::computeGains: " + why);
  const size_t per_position = static_cast<size_t>(grid.width) * grid.height;
  if (!max_depth_m.empty() && max_depth_m.size() != per_position * positions_W.size())
    throw std::invalid_argument("ObjectMap::computeGains: max_depth_m must hold width * height values per position");
  std::vector<Eigen::Vector3f> dirs(per_position);
  for (int v = 0; v < grid.height; ++v)
    for (int u = 0; u < grid.width; ++u) dirs[v * grid.width + u] = grid.direction(u, v).cast<float>();
  gains.assign(positions_W.size(), cv::Mat());
  hit_depth_m.assign(positions_W.size(), cv::Mat());
  for (size_t i = 0; i < positions_W.size(); ++i) {
    gains[i] = cv::Mat::zeros(grid.height, grid.width, CV_32FC1);
    hit_depth_m[i] = cv::Mat(grid.height, grid.width, CV_32FC1, cv::Scalar(d_max_m));
    const Eigen::Vector3f o = positions_W[i].cast<float>();
    for (size_t r = 0; r < per_position; ++r) {
      float t_max = static_cast<float>(d_max_m);
      if (!max_depth_m.empty()) {
        const float m = max_depth_m[i * per_position + r];
        if (!std::isnan(m)) t_max = std::min(t_max, m);
      }
      if (!(t_max > 0.f)) continue;
      bool found = false;
      TsdfRayHit best;
      for (const auto& kv : objects_) {
        TsdfRayHit hit;
        if (kv.second->tsdf.castRay(o, dirs[r], 0.f, t_max, hit)) {
          t_max = hit.distance_m;
          best = hit;
          found = true;
        }
      }
      if (!found) continue;
      const int v = static_cast<int>(r) / grid.width, u = static_cast<int>(r) % grid.width;
      hit_depth_m[i].at<float>(v, u) = best.distance_m;
      gains[i].at<float>(v, u) =
          static_cast<float>(objectDistanceGain(best.min_distance_m, best.distance_m, d_obj_m, d_max_m));
    }
  }
}

}  // namespace semexp

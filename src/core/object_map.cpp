#include "semantic_exploration/core/object_map.hpp"

#include "semantic_exploration/core/object_masks.hpp"

#include <algorithm>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace semexp {

namespace {
/// A new object's detection may have at most this share of its pixels beyond the integrated depth (noise at the
/// boundary), else it waits for a nearer view.
constexpr double kMaxNewObjectShareBeyondRange = 0.05;
}  // namespace

double objectDistanceGain(double d_node_m, double d_exp_m, double d_desired_m, double d_max_m) {
  d_node_m = std::min(d_node_m, d_max_m);  // "never observed closer than range" counts as d_max
  if (d_node_m <= d_desired_m || d_node_m <= d_exp_m) return 0.0;
  return std::clamp((d_node_m - std::max(d_exp_m, d_desired_m)) / d_max_m, 0.0, 1.0);
}

ObjectMap::ObjectMap(const ObjectMapConfig& config, const ClassTable& classes) : config_(config), classes_(classes) {
  config_.validate();
  classes_.validate();
}

TsdfParams ObjectMap::tsdfParams(int class_id) const {
  TsdfParams p;
  p.resolution_m = classes_.resolution(class_id);
  p.truncation_m = config_.truncation_voxels * p.resolution_m;
  p.behind_surface_m = config_.behind_surface_voxels * p.resolution_m;
  p.behind_surface_quadratic_per_m = config_.behind_surface_quadratic_per_m;
  p.full_weight_depth_m = config_.full_weight_depth_m;
  p.foreground_prior = config_.foreground_prior;
  p.foreground_prior_weight = config_.foreground_prior_weight;
  p.block_size = config_.block_size;
  p.max_weight = config_.max_weight;
  return p;
}

std::string ObjectMap::checkIntegratedDepth(double d_bg_m) const {
  for (const std::string& name : classes_.of_interest) {
    const TsdfParams p = tsdfParams(classes_.id(name));
    if (p.maxIntegratedDepth_m() < d_bg_m)
      return "the " + name + " map (" + std::to_string(p.resolution_m) + " m voxels, truncation " +
             std::to_string(p.truncation_m) + " m) integrates depths only up to " +
             std::to_string(p.maxIntegratedDepth_m()) + " m, less than exploration/d_bg_m = " + std::to_string(d_bg_m) +
             " m, so objects seen from d_bg would never be made; lower it or raise object_map/truncation_voxels";
  }
  return "";
}

std::string ObjectMap::checkBounds(const Bounds& bounds, double range_m) const {
  const double extent_m = std::max(bounds.min_m.cwiseAbs().maxCoeff(), bounds.max_m.cwiseAbs().maxCoeff()) + range_m;
  for (const std::string& name : classes_.of_interest) {
    const TsdfParams p = tsdfParams(classes_.id(name));
    if (extent_m >= p.maxCoordinate_m())
      return "the bounds reach " + std::to_string(extent_m) + " m from the origin (with " + std::to_string(range_m) +
             " m of sensor range); the " + name + " map at " + std::to_string(p.resolution_m) +
             " m holds at most " + std::to_string(p.maxCoordinate_m()) + " m (TsdfParams::kMaxVoxelIndex)";
  }
  return "";
}

std::uint32_t ObjectMap::createObject(int class_id) {
  const std::string name = classes_.name(class_id);
  if (name.empty()) return 0;
  const std::uint32_t id = ids_.acquire(version_);
  if (id == 0) return 0;
  objects_.emplace(id, std::make_unique<MappedObject>(id, class_id, name, tsdfParams(class_id)));
  return id;
}

const MappedObject* ObjectMap::object(std::uint32_t id) const {
  const auto it = objects_.find(id);
  return it == objects_.end() ? nullptr : it->second.get();
}

std::vector<std::uint32_t> ObjectMap::visibleIds(const cv::Mat& object_ids) {
  // Runs of one id along a row are collected once; no pass over all 65535 possible ids per call.
  std::vector<std::uint32_t> ids;
  for (int v = 0; v < object_ids.rows; ++v) {
    const std::uint16_t* row = object_ids.ptr<std::uint16_t>(v);
    for (int u = 0; u < object_ids.cols; ++u)
      if (row[u] && (ids.empty() || ids.back() != row[u])) ids.push_back(row[u]);
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

FrameIntegration ObjectMap::integrateFrame(const PinholeCamera& camera, const Eigen::Isometry3d& T_WC,
                                           const cv::Mat& depth_m, const cv::Mat& rgb, const cv::Mat& instance_image,
                                           const std::vector<ObjectDetection>& detections,
                                           const cv::Mat* rendered_before) {
  if (instance_image.type() != CV_16UC1 || instance_image.size() != depth_m.size())
    throw std::invalid_argument("ObjectMap::integrateFrame: instance image must be 16UC1 of the depth image's size");
  if (rendered_before && (rendered_before->type() != CV_16UC1 || rendered_before->size() != depth_m.size()))
    throw std::invalid_argument("ObjectMap::integrateFrame: rendered ids must be 16UC1 of the depth image's size");
  FrameIntegration result;
  ++version_;
  cv::Mat rendered;
  if (rendered_before)
    rendered = *rendered_before;
  else
    render(camera, T_WC, depth_m, rendered);

  // Union of the masks of the detections of each object.
  std::map<std::uint32_t, cv::Mat> masks;
  // Object split off -> the object the map had, and the plane between them (normal towards the split-off one).
  struct SplitFrom {
    std::uint32_t id;
    Eigen::Vector3f normal_W;
    float offset_m;
  };
  std::map<std::uint32_t, SplitFrom> split_from;
  // separateMasks(a, b) with the rims of each bled onto surfaces behind left out (they would join the two).
  const auto separation = [&](const cv::Mat& a, const cv::Mat& b) {
    cv::Mat ea = a.clone(), eb = b.clone();
    markDepthEdges(ea, depth_m, camera, config_.depthEdgeParams(), TsdfMap::kMaskUnknown);
    markDepthEdges(eb, depth_m, camera, config_.depthEdgeParams(), TsdfMap::kMaskUnknown);
    return separateMasks(ea, eb, depth_m, camera);
  };
  const auto apart = [&](const cv::Mat& a, const cv::Mat& b, Eigen::Vector3f& normal_W, float& offset_m) {
    const MaskSeparation s = separation(b, a);  // normal towards the new detection
    normal_W = T_WC.linear().cast<float>() * s.normal_C;
    offset_m = static_cast<float>(s.plane_m + normal_W.cast<double>().dot(T_WC.translation()));
    return s.gap_m >= config_.split_gap_m;  // false for NaN (too few points to tell)
  };
  for (const ObjectDetection& d : detections) {
    if (classes_.name(d.class_id).empty()) {
      ++result.dropped_unknown_class;
      continue;
    }
    if (!classes_.isOfInterest(d.class_id)) {
      ++result.dropped_not_of_interest;
      continue;
    }
    std::uint32_t id = d.object_id;
    if (id == 0) {
      id = createObject(d.class_id);
      if (id == 0) {
        ++result.dropped_full;
        continue;
      }
      result.created.push_back(id);
    } else if (!object(id)) {
      ++result.dropped_unknown_object;
      continue;
    }
    cv::Mat mask = instance_image == d.instance_id;
    auto it = masks.find(id);
    Eigen::Vector3f normal_W;
    float offset_m = 0.f;
    if (it != masks.end() && config_.split_gap_m > 0 && apart(mask, it->second, normal_W, offset_m)) {
      // Two detections of one known object in a frame whose surfaces lie apart: two objects the map took
      // for one (a mask bled over both). This one starts an object of its own; the part of the map's object
      // on its side of the gap is its, not the other's.
      // The original forgets that side only once the new object is kept (below).
      const std::uint32_t split = createObject(d.class_id);
      if (split == 0) {
        ++result.dropped_full;
        continue;
      }
      result.created.push_back(split);
      split_from[split] = {id, normal_W, offset_m};
      id = split;
      it = masks.end();
    }
    if (it == masks.end())
      masks.emplace(id, mask);
    else
      it->second |= mask;
  }
  // Merge visible undetected objects whose render lies mostly inside a
  // detection of the same class: they are pieces of the detected object.
  std::map<std::uint32_t, std::uint32_t> merged_into;
  {
    // Summaries walk all of an object's blocks: once per object, surface and frame (nothing merges before the
    // end). tracked: the tracked surface; else the object as published (ObjectMap::summarize).
    std::map<std::pair<std::uint32_t, bool>, TsdfSummary> summaries;
    const auto summary = [this, &summaries](std::uint32_t id, bool tracked) -> const TsdfSummary& {
      auto it = summaries.find({id, tracked});
      if (it == summaries.end()) {
        const MappedObject& o = *objects_.at(id);
        it = summaries.emplace(std::make_pair(id, tracked), tracked ? o.tsdf.summarize(0.0, true) : summarize(o, 0.0))
                 .first;
      }
      return it->second;
    };
    // y's tracked surface lies mostly inside the box of x's reconstructed surface in 3D (boxes padded by 2
    // voxels; x's tracked surface while it has no reconstructed one, as published). Surface a bled mask added
    // to x in a few detections is tracked but not reconstructed (under the foreground prior): it must not widen
    // x's box over a neighbour. `smaller` compares the tracked surfaces.
    const auto inside_box = [this, &summary](std::uint32_t y, std::uint32_t x, bool smaller) {
      const TsdfSummary &sy = summary(y, true), &sx_tracked = summary(x, true), &sx = summary(x, false);
      if (sx.voxel_count == 0 || sy.voxel_count == 0 || (smaller && sy.voxel_count >= sx_tracked.voxel_count))
        return false;
      const Eigen::Vector3d pad = Eigen::Vector3d::Constant(2.0 * objects_.at(x)->resolution_m);
      const Eigen::AlignedBox3d bx(sx.bbox_min_W - pad, sx.bbox_max_W + pad);
      const Eigen::AlignedBox3d by(sy.bbox_min_W - pad, sy.bbox_max_W + pad);
      // Eigen's intersection of disjoint boxes is empty but its volume() is the product of the (negative)
      // sizes: positive when two of them are negative.
      const Eigen::AlignedBox3d both = bx.intersection(by);
      return !both.isEmpty() && both.volume() >= config_.merge_fraction * by.volume();
    };
    // One of y and x is a piece of the other that reaches past its box (the top of a chair's back first
    // detected alone, whose rendered pixels would otherwise keep the chair's object from growing there): within
    // x's mask their surfaces lie closer than split_gap_m (separateMasks, the split rule's measure, mirrored),
    // and one holds at most piece_max_share of the other's tracked surface voxels. Neighbouring objects of a
    // class touch too, but are of a size (traced in docs/BENCHMARKS.md).
    const auto piece = [&](std::uint32_t y, std::uint32_t x, const cv::Mat& mask) {
      if (config_.split_gap_m <= 0 || config_.piece_max_share <= 0) return false;
      const double ny = static_cast<double>(summary(y, true).voxel_count);
      const double nx = static_cast<double>(summary(x, true).voxel_count);
      if (ny == 0 || nx == 0 || std::min(ny, nx) > config_.piece_max_share * std::max(ny, nx)) return false;
      return separation(mask & (rendered == static_cast<int>(y)), mask & (rendered == static_cast<int>(x))).gap_m <
             config_.split_gap_m;  // false for NaN
    };
    std::map<std::uint32_t, int> rendered_pixels;
    for (int v = 0; v < rendered.rows; ++v) {
      const std::uint16_t* row = rendered.ptr<std::uint16_t>(v);
      for (int u = 0; u < rendered.cols; ++u)
        if (row[u]) ++rendered_pixels[row[u]];
    }
    for (const auto& rp : rendered_pixels) {
      const std::uint32_t y = rp.first;
      if (masks.count(y) || !objects_.count(y)) continue;
      const MappedObject& oy = *objects_.at(y);
      for (const auto& kv : masks) {
        const MappedObject& ox = *objects_.at(kv.first);
        if (ox.class_id != oy.class_id || ox.resolution_m != oy.resolution_m) continue;
        const int inside = cv::countNonZero((rendered == static_cast<int>(y)) & kv.second);
        if (inside < config_.merge_fraction * rp.second) continue;
        // A detector may also merge two neighbouring objects into one mask: only merge if y's surface also lies
        // mostly inside x's box in 3D, or one of the two is a piece of the other.
        if (!inside_box(y, kv.first, false) && !piece(y, kv.first, kv.second)) continue;
        merged_into[y] = kv.first;
        break;
      }
    }
    // A piece made from one detection and not rendered (too small or thin for the raycast to hit) is never
    // matched, updated or merged by the rule above: it would stay a ghost object that the planner keeps
    // visiting. It joins a larger detected object of its class whose box holds it.
    for (const auto& kv_y : objects_) {
      const std::uint32_t y = kv_y.first;
      const MappedObject& oy = *kv_y.second;
      if (masks.count(y) || rendered_pixels.count(y) || oy.detection_count > 1) continue;
      for (const auto& kv : masks) {
        const MappedObject& ox = *objects_.at(kv.first);
        if (ox.class_id != oy.class_id || ox.resolution_m != oy.resolution_m || !inside_box(y, kv.first, true)) continue;
        merged_into[y] = kv.first;
        break;
      }
    }
    for (const auto& m : merged_into) {
      MappedObject& into = *objects_.at(m.second);
      const MappedObject& from = *objects_.at(m.first);
      into.tsdf.mergeFrom(from.tsdf);
      into.detection_count += from.detection_count;
      into.undetected_count += from.undetected_count;
      objects_.erase(m.first);
      ids_.release(m.first, version_);
      result.merged.emplace_back(m.first, m.second);
    }
  }
  for (auto& kv : masks) {
    // Pixels where another known object is rendered belong to that object
    // (a detection spanning two objects only feeds the one it was matched to).
    // Grown by 2 px: rendered silhouettes are good to about that (a voxel spans several pixels up close).
    cv::Mat other = (rendered != 0) & (rendered != static_cast<int>(kv.first));
    for (const auto& m : merged_into)
      if (m.second == kv.first) other.setTo(0, rendered == static_cast<int>(m.first));
    // A split-off object is rendered as the one it was part of until that one forgets it.
    if (const auto sp = split_from.find(kv.first); sp != split_from.end())
      other.setTo(0, rendered == static_cast<int>(sp->second.id));
    cv::dilate(other, other, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5)));
    const cv::Mat detected = kv.second.clone();
    // Edges first: the pixels of the other object are the near side of the edges its bled rim lies behind.
    markDepthEdges(kv.second, depth_m, camera, config_.depthEdgeParams(), TsdfMap::kMaskUnknown);
    kv.second.setTo(0, other);
    markMaskBorder(kv.second, detected, config_.foreground_border_px);
    MappedObject& obj = *objects_.at(kv.first);
    const bool is_new = std::find(result.created.begin(), result.created.end(), kv.first) != result.created.end();
    int new_pixels = 0, beyond_range = 0;
    if (is_new) {
      const float max_depth = static_cast<float>(obj.tsdf.params().maxIntegratedDepth_m());
      for (int v = 0; v < depth_m.rows; ++v) {
        const float* d = depth_m.ptr<float>(v);
        const std::uint8_t* m = kv.second.ptr<std::uint8_t>(v);
        for (int u = 0; u < depth_m.cols; ++u) {
          const bool valid = m[u] && m[u] != TsdfMap::kMaskUnknown && d[u] > 0.f && d[u] >= camera.d_min_m &&
                             d[u] <= camera.d_max_m;
          new_pixels += valid;
          beyond_range += valid && d[u] > max_depth;
        }
      }
    }
    // A detection reaching past the depth the TSDF integrates (its noise band would pass the truncation) would
    // make an object of its near part only, which later whole views no longer match: it waits for a nearer view.
    const bool whole = beyond_range <= kMaxNewObjectShareBeyondRange * new_pixels;
    if (!is_new || (new_pixels >= config_.min_new_object_pixels && whole))
      obj.tsdf.integrate(camera, T_WC, depth_m, rgb, kv.second, true);
    if (is_new && (new_pixels < config_.min_new_object_pixels || !whole || !obj.tsdf.hasSurface())) {
      // Too little of the detection was left (a rim round known objects, or no depth), part of it lay beyond the
      // integrated depth, or not enough to hold one surface voxel: no object (such a piece would never be
      // rendered, updated or merged again).
      objects_.erase(kv.first);
      ids_.releaseUnpublished(kv.first);  // created and erased in this frame: nobody saw the id
      result.created.erase(std::find(result.created.begin(), result.created.end(), kv.first));
      ++result.dropped_empty;
      continue;
    }
    ++obj.detection_count;
    result.detected.push_back(kv.first);
    if (const auto sp = split_from.find(kv.first); sp != split_from.end() && objects_.count(sp->second.id)) {
      objects_.at(sp->second.id)->tsdf.dropForegroundBeyond(sp->second.normal_W, sp->second.offset_m);
      result.split.emplace_back(kv.first, sp->second.id);
    }
  }
  for (const std::uint32_t id : visibleIds(rendered)) {
    if (masks.count(id)) continue;
    const auto it = objects_.find(id);
    if (it == objects_.end()) continue;
    it->second->tsdf.integrate(camera, T_WC, depth_m, rgb, rendered == static_cast<int>(id), false);
    ++it->second->undetected_count;
    result.undetected.push_back(id);
  }
  return result;
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

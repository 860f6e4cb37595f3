#include "semantic_exploration/core/object_map.hpp"

#include "semantic_exploration/core/object_masks.hpp"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace semexp {

namespace {
/// A new object's detection may have at most this share of its pixels beyond the integrated depth (noise at the
/// boundary), else it waits for a nearer view.
constexpr double kMaxNewObjectShareBeyondRange = 0.05;
}  // namespace

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
  const auto apart = [&](const cv::Mat& a, const cv::Mat& b, Eigen::Vector3f& normal_W, float& offset_m) {
    const MaskSeparation s = separation(b, a, camera, depth_m);  // normal towards the new detection
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
  // Merge visible undetected objects whose render lies mostly inside a detection of the same class: they are
  // pieces of the detected object, or it of them.
  // An object split in this frame keeps its id: its split-off part is rendered as it until it forgets that side.
  std::set<std::uint32_t> split_sources;
  for (const auto& sp : split_from) split_sources.insert(sp.second.id);
  const std::map<std::uint32_t, std::uint32_t> merged_into =
      mergeSameObjects(camera, depth_m, rendered, masks, split_sources, result);
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

}  // namespace semexp

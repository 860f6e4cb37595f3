// ObjectMap's merges of step 2 of integrateFrame: which objects not detected in a frame are the same object as a
// detected one, and merging them.

#include "semantic_exploration/core/object_map.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "semantic_exploration/core/int_math.hpp"
#include "semantic_exploration/core/neighbour_cells.hpp"

namespace semexp {

double trackedSurfaceDistance(const TsdfMap& a, const TsdfMap& b, double max_m) {
  const double res_m = a.params().resolution_m;
  if (res_m != b.params().resolution_m || a.params().block_size != b.params().block_size)
    throw std::invalid_argument("trackedSurfaceDistance: the two maps must share one voxel grid");
  // Nearest pair of tracked surface voxels within r voxels per axis. b's surface voxels are binned in cubic
  // cells of r voxels, so every voxel within r of one of a's lies in the 27 cells around it: each of a's
  // voxels compares itself with b's voxels there instead of looking up all (2r + 1)^3 offsets: 1,331 hash
  // lookups per voxel at the piece rule's 0.1 m and a 2 cm chair map, 226,981 at its test's 0.6 m. The same
  // pairs are compared, so the same minimum.
  const int r = static_cast<int>(std::ceil(max_m / res_m));
  const int cell = std::max(r, 1);
  const auto cellOf = [cell](const Eigen::Vector3i& v) {
    return Eigen::Vector3i(floorDiv(v.x(), cell), floorDiv(v.y(), cell), floorDiv(v.z(), cell));
  };
  std::unordered_map<Eigen::Vector3i, std::vector<Eigen::Vector3i>, VoxelIndexHash> cells_b;
  b.forEachVoxel([&](const Eigen::Vector3i& index, const TsdfVoxel& vx) {
    if (b.isSurfaceVoxel(vx, true)) cells_b[cellOf(index)].push_back(index);
  });
  const int max_sq = std::numeric_limits<int>::max();
  int best_sq = max_sq;  // in voxels squared
  a.forEachVoxel([&](const Eigen::Vector3i& index, const TsdfVoxel& vx) {
    if (best_sq == 0 || cells_b.empty() || !a.isSurfaceVoxel(vx, true)) return;
    visitNeighbourCells(cells_b, cellOf(index), [&](const Eigen::Vector3i& j) {
      const Eigen::Vector3i d = j - index;
      if (std::abs(d.x()) <= r && std::abs(d.y()) <= r && std::abs(d.z()) <= r)
        best_sq = std::min(best_sq, d.squaredNorm());
      return false;  // the nearest pair: every candidate counts
    });
  });
  const double d_m = best_sq == max_sq ? std::numeric_limits<double>::infinity()
                                       : std::sqrt(static_cast<double>(best_sq)) * res_m;
  return d_m < max_m ? d_m : std::numeric_limits<double>::infinity();
}

MaskSeparation ObjectMap::separation(const cv::Mat& a, const cv::Mat& b, const PinholeCamera& camera,
                                     const cv::Mat& depth_m) const {
  cv::Mat ea = a.clone(), eb = b.clone();
  markDepthEdges(ea, depth_m, camera, config_.depthEdgeParams(), TsdfMap::kMaskUnknown);
  markDepthEdges(eb, depth_m, camera, config_.depthEdgeParams(), TsdfMap::kMaskUnknown);
  return separateMasks(ea, eb, depth_m, camera);
}

std::map<std::uint32_t, std::uint32_t> ObjectMap::mergeSameObjects(const PinholeCamera& camera, const cv::Mat& depth_m,
                                                                   const cv::Mat& rendered,
                                                                   std::map<std::uint32_t, cv::Mat>& masks,
                                                                   const std::set<std::uint32_t>& keep_ids,
                                                                   FrameIntegration& result) {
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
  // detected alone, whose rendered pixels would otherwise keep the chair's object from growing there): one
  // holds at most piece_max_share of the other's tracked surface voxels, and their surfaces touch: within x's
  // mask they lie under split_gap_m apart (separateMasks, the split rule's measure, mirrored), and their
  // nearest tracked surface voxels under piece_max_distance_m. The mask gap is negative, so "touching",
  // wherever the larger object reaches past the piece on both sides of the line between their centroids
  // (a small object 20 cm in front of a bench did in the tests). Neighbouring objects of a class touch too,
  // but are of a size (traced in docs/BENCHMARKS.md).
  const auto piece = [&](std::uint32_t y, std::uint32_t x, const cv::Mat& mask, std::string& why) {
    if (config_.split_gap_m <= 0 || config_.piece_max_share <= 0) return false;
    const TsdfSummary &sy = summary(y, true), &sx = summary(x, true);
    const double ny = static_cast<double>(sy.voxel_count), nx = static_cast<double>(sx.voxel_count);
    if (ny == 0 || nx == 0 || std::min(ny, nx) > config_.piece_max_share * std::max(ny, nx)) return false;
    // Boxes of the tracked surfaces farther apart than the 3D test allows (plus a voxel of rounding): no need to
    // look at the voxels.
    const double boxes_apart_m = Eigen::AlignedBox3d(sy.bbox_min_W, sy.bbox_max_W)
                                     .exteriorDistance(Eigen::AlignedBox3d(sx.bbox_min_W, sx.bbox_max_W));
    if (boxes_apart_m > config_.piece_max_distance_m + objects_.at(x)->resolution_m) return false;
    const double gap_m = separation(mask & (rendered == static_cast<int>(y)), mask & (rendered == static_cast<int>(x)),
                                    camera, depth_m)
                             .gap_m;
    if (!(gap_m < config_.split_gap_m)) return false;  // NaN: too few points to tell
    const TsdfMap &ty = objects_.at(y)->tsdf, &tx = objects_.at(x)->tsdf;
    const double d_m = ny <= nx ? trackedSurfaceDistance(ty, tx, config_.piece_max_distance_m)
                                : trackedSurfaceDistance(tx, ty, config_.piece_max_distance_m);
    if (!std::isfinite(d_m)) return false;
    char text[160];
    std::snprintf(text, sizeof(text), "a piece: %.0f of %.0f tracked surface voxels, %.3f m apart, mask gap %.3f m",
                  std::min(ny, nx), std::max(ny, nx), d_m, gap_m);
    why = text;
    return true;
  };
  std::map<std::uint32_t, std::uint32_t> merged_into;
  std::map<std::uint32_t, std::string> reasons;  // merged id -> why
  // y is the same object as the detected x: normally y goes into x. Where x is the piece (and not in keep_ids),
  // x goes into y, which takes over x's mask (and whatever was merged into x so far): the larger object's id
  // stays.
  const auto merge = [&](std::uint32_t y, std::uint32_t x, bool x_into_y, const std::string& why) {
    if (!x_into_y || keep_ids.count(x)) {
      merged_into[y] = x;
      reasons[y] = why;
      return;
    }
    reasons[x] = why + "; the detected one is the piece, the larger keeps its id";
    for (auto& m : merged_into)
      if (m.second == x) m.second = y;
    merged_into[x] = y;
    auto node = masks.extract(x);
    node.key() = y;
    const bool inserted = masks.insert(std::move(node)).inserted;
    assert(inserted);  // y was not detected: no mask of its own
    (void)inserted;
  };
  std::map<std::uint32_t, int> rendered_pixels;
  for (int v = 0; v < rendered.rows; ++v) {
    const std::uint16_t* row = rendered.ptr<std::uint16_t>(v);
    for (int u = 0; u < rendered.cols; ++u)
      if (row[u]) ++rendered_pixels[row[u]];
  }
  for (const auto& rp : rendered_pixels) {
    const std::uint32_t y = rp.first;
    if (masks.count(y) || merged_into.count(y) || !objects_.count(y)) continue;
    const MappedObject& oy = *objects_.at(y);
    for (const auto& kv : masks) {
      const std::uint32_t x = kv.first;
      const MappedObject& ox = *objects_.at(x);
      if (ox.class_id != oy.class_id || ox.resolution_m != oy.resolution_m) continue;
      const int inside = cv::countNonZero((rendered == static_cast<int>(y)) & kv.second);
      if (inside < config_.merge_fraction * rp.second) continue;
      // A detector may also merge two neighbouring objects into one mask: only merge if y's surface also lies
      // mostly inside x's box in 3D, or one of the two is a piece of the other.
      std::string why;
      if (inside_box(y, x, false)) {
        merge(y, x, false, "rendered inside its detection, inside its box");
      } else if (piece(y, x, kv.second, why)) {
        merge(y, x, summary(x, true).voxel_count < summary(y, true).voxel_count, why);  // a tie: the detected one's id
      } else {
        continue;
      }
      break;  // `masks` may have changed
    }
  }
  // A piece made from one detection and not rendered (too small or thin for the raycast to hit) is never
  // matched, updated or merged by the rule above: it would stay a ghost object that the planner keeps
  // visiting. It joins a larger detected object of its class whose box holds it.
  for (const auto& kv_y : objects_) {
    const std::uint32_t y = kv_y.first;
    const MappedObject& oy = *kv_y.second;
    if (masks.count(y) || merged_into.count(y) || rendered_pixels.count(y) || oy.detection_count > 1) continue;
    for (const auto& kv : masks) {
      const MappedObject& ox = *objects_.at(kv.first);
      if (ox.class_id != oy.class_id || ox.resolution_m != oy.resolution_m || !inside_box(y, kv.first, true)) continue;
      merge(y, kv.first, false, "made from one detection, never rendered, inside its box");
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
    result.merge_reasons.push_back(reasons[m.first]);
  }
  return merged_into;
}

}  // namespace semexp

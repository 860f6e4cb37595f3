#include "semantic_exploration/core/instance_matching.hpp"

#include <algorithm>
#include <stdexcept>
#include <unordered_map>

namespace semexp {

MatchingOutput matchDetections(const cv::Mat& instance_image, const std::vector<std::uint16_t>& instance_ids,
                               const cv::Mat& object_ids, const MatchingConfig& config, cv::Mat* cleaned) {
  if (instance_image.type() != CV_16UC1 || object_ids.type() != CV_16UC1 || instance_image.size() != object_ids.size())
    throw std::invalid_argument("matchDetections: instance and object-id images must be 16UC1 of the same size");

  MatchingOutput out;
  std::vector<int> index_of(65536, -1);  // instance id -> detection index
  for (const std::uint16_t id : instance_ids) {
    if (id == 0 || index_of[id] >= 0) {
      ++out.duplicate_ids;
      continue;
    }
    index_of[id] = static_cast<int>(out.detections.size());
    MatchResult r;
    r.instance_id = id;
    out.detections.push_back(r);
  }
  const size_t n_det = out.detections.size();

  // One pass: mask sizes, rendered object sizes and intersections.
  std::unordered_map<std::uint16_t, std::uint32_t> object_pixels;
  std::unordered_map<std::uint32_t, std::uint32_t> intersection;  // (detection index << 16 | object id) -> pixels
  for (int v = 0; v < instance_image.rows; ++v) {
    const std::uint16_t* irow = instance_image.ptr<std::uint16_t>(v);
    const std::uint16_t* orow = object_ids.ptr<std::uint16_t>(v);
    for (int u = 0; u < instance_image.cols; ++u) {
      const std::uint16_t o = orow[u];
      if (o) ++object_pixels[o];
      const std::uint16_t i = irow[u];
      if (!i) continue;
      const int d = index_of[i];
      if (d < 0) {
        ++out.unlisted_pixels;
        continue;
      }
      ++out.detections[d].mask_pixels;
      if (o) ++intersection[(static_cast<std::uint32_t>(d) << 16) | o];
    }
  }
  for (auto& r : out.detections) r.dropped = r.mask_pixels < static_cast<std::uint32_t>(config.min_mask_pixels);

  struct Pair {
    int det;
    std::uint16_t obj;
    float iou;
    float inside;   // fraction of the detection's pixels on the object
    float covered;  // fraction of the object's rendered pixels inside the detection
    std::uint32_t inter;
  };
  std::vector<Pair> pairs;
  for (const auto& kv : intersection) {
    const int d = static_cast<int>(kv.first >> 16);
    const auto o = static_cast<std::uint16_t>(kv.first & 0xffff);
    const MatchResult& r = out.detections[d];
    if (r.dropped) continue;
    const double inter = kv.second;
    const double uni = static_cast<double>(r.mask_pixels) + object_pixels[o] - inter;
    pairs.push_back({d, o, static_cast<float>(inter / uni), static_cast<float>(inter / r.mask_pixels),
                     static_cast<float>(inter / object_pixels[o]), kv.second});
  }
  std::sort(pairs.begin(), pairs.end(), [&](const Pair& a, const Pair& b) {
    if (a.iou != b.iou) return a.iou > b.iou;
    const auto ia = out.detections[a.det].instance_id, ib = out.detections[b.det].instance_id;
    return ia != ib ? ia < ib : a.obj < b.obj;
  });

  std::vector<bool> matched(n_det, false);
  std::unordered_map<std::uint16_t, bool> taken;
  for (const Pair& p : pairs) {
    if (p.iou < config.iou_threshold) break;
    if (matched[p.det] || taken[p.obj]) continue;
    matched[p.det] = true;
    taken[p.obj] = true;
    out.detections[p.det].object_id = p.obj;
    out.detections[p.det].iou = p.iou;
  }
  // Fragments: an unmatched detection lying mostly on rendered objects goes
  // to the one covering most of it (several renders may share it, e.g. an
  // object seen in pieces before).
  std::vector<float> inside_total(n_det, 0.f);
  std::vector<const Pair*> best(n_det, nullptr);
  for (const Pair& p : pairs) {
    inside_total[p.det] += p.inside;
    if (!best[p.det] || p.inside > best[p.det]->inside ||
        (p.inside == best[p.det]->inside && p.obj < best[p.det]->obj))
      best[p.det] = &p;
  }
  for (size_t d = 0; d < n_det; ++d) {
    if (matched[d] || !best[d] || inside_total[d] < config.fragment_fraction) continue;
    matched[d] = true;
    out.detections[d].object_id = best[d]->obj;
    out.detections[d].iou = best[d]->iou;
    out.detections[d].fragment = true;
  }
  // The other way round: a known object rendered mostly inside an unmatched
  // detection (so far seen only in part) is the object it detects; the one
  // with the largest overlap wins. Renders under a quarter of min_mask_pixels
  // are too small to tell.
  const std::uint32_t min_render = std::max<std::uint32_t>(1, static_cast<std::uint32_t>(config.min_mask_pixels) / 4);
  std::vector<const Pair*> cover(n_det, nullptr);
  for (const Pair& p : pairs) {
    if (matched[p.det] || p.covered < config.fragment_fraction || object_pixels[p.obj] < min_render) continue;
    if (!cover[p.det] || p.inter > cover[p.det]->inter) cover[p.det] = &p;
  }
  for (size_t d = 0; d < n_det; ++d) {
    if (!cover[d]) continue;
    matched[d] = true;
    out.detections[d].object_id = cover[d]->obj;
    out.detections[d].iou = cover[d]->iou;
    out.detections[d].fragment = true;
  }

  if (cleaned) {
    *cleaned = instance_image.clone();
    for (int v = 0; v < cleaned->rows; ++v) {
      std::uint16_t* row = cleaned->ptr<std::uint16_t>(v);
      for (int u = 0; u < cleaned->cols; ++u) {
        if (!row[u]) continue;
        const int d = index_of[row[u]];
        if (d < 0 || out.detections[d].dropped) row[u] = 0;
      }
    }
  }
  return out;
}

}  // namespace semexp

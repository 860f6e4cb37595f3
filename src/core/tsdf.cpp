#include "semantic_exploration/core/tsdf.hpp"

#include <climits>
#include <stdexcept>

namespace semexp {

namespace {

static_assert((-5 >> 1) == -3, "blockOf needs an arithmetic right shift");

constexpr double kFarOffImagePx = 1e9;  ///< pixel coordinates beyond this are skipped before rounding

inline bool validDepth(float d, const PinholeCamera& camera) {
  return std::isfinite(d) && d > 0.f && d >= camera.d_min_m && d <= camera.d_max_m;
}

// Packs a global voxel index and an axis into one key (20 bits per axis).
inline std::uint64_t edgeKey(const Eigen::Vector3i& v, int axis) {
  const auto c = [](int x) { return static_cast<std::uint64_t>(x + (1 << 19)) & 0xfffff; };
  return (c(v.x()) << 42) | (c(v.y()) << 22) | (c(v.z()) << 2) | static_cast<std::uint64_t>(axis);
}

}  // namespace

template <class V>
TsdfMapT<V>::TsdfMapT(const TsdfParams& params)
    : params_(params),
      voxels_per_block_(params.block_size * params.block_size * params.block_size),
      block_shift_(0),
      inv_resolution_(static_cast<float>(1.0 / params.resolution_m)),
      truncation_m_(static_cast<float>(params.truncation_m)),
      tracked_foreground_(params.trackedForeground()) {
  if (tracked_foreground_ < 0.5f) {
    V stored;
    stored.setForeground(static_cast<float>(params.foreground_prior));
    tracked_foreground_ = std::max(tracked_foreground_, stored.foreground());
  }
  if (!(params.resolution_m > 0) || !(params.truncation_m > 0) || params.block_size < 1 ||
      (params.block_size & (params.block_size - 1)) != 0)
    throw std::invalid_argument("TsdfMap: resolution and truncation must be > 0, block size a power of two");
  while ((1 << block_shift_) < params.block_size) ++block_shift_;
}

template <class V>
typename TsdfMapT<V>::Block& TsdfMapT<V>::allocate(const Eigen::Vector3i& b) {
  auto it = blocks_.find(b);
  if (it != blocks_.end()) return it->second;
  if (blocks_.empty()) {
    block_min_ = block_max_ = b;
  } else {
    block_min_ = block_min_.cwiseMin(b);
    block_max_ = block_max_.cwiseMax(b);
  }
  dense_.clear();  // stale until rebuildIndex(); look-ups fall back to the hash map
  return blocks_.emplace(b, Block(voxels_per_block_)).first->second;
}

template <class V>
const V* TsdfMapT<V>::voxel(const Eigen::Vector3i& index) const {
  const Eigen::Vector3i b = blockOf(index);
  const Block* block = findBlock(b);
  if (!block) return nullptr;
  const int B = params_.block_size;
  const Eigen::Vector3i l = index - b * B;
  return &(*block)[l.x() + B * (l.y() + B * l.z())];
}

template <class V>
void TsdfMapT<V>::rebuildIndex() {
  dense_.clear();
  if (blocks_.empty()) return;
  dense_min_ = block_min_;
  dense_dims_ = block_max_ - block_min_ + Eigen::Vector3i::Ones();
  const double cells = static_cast<double>(dense_dims_.x()) * dense_dims_.y() * dense_dims_.z();
  if (cells > kMaxDenseIndex) return;  // very large or scattered object: hash look-ups only
  dense_.assign(static_cast<std::size_t>(cells), nullptr);
  for (auto& kv : blocks_) {
    const Eigen::Vector3i r = kv.first - dense_min_;
    dense_[r.x() + dense_dims_.x() * (r.y() + dense_dims_.y() * r.z())] = &kv.second;
  }
}

template <class V>
bool TsdfMapT<V>::allocatedBox(Eigen::AlignedBox3f& box_W) const {
  if (blocks_.empty()) return false;
  const float edge = static_cast<float>(params_.resolution_m * params_.block_size);
  box_W = Eigen::AlignedBox3f(block_min_.cast<float>() * edge, (block_max_.cast<float>().array() + 1.f) * edge);
  return true;
}

template <class V>
std::size_t TsdfMapT<V>::integrate(const PinholeCamera& camera, const Eigen::Isometry3d& T_WC, const cv::Mat& depth_m,
                                   const cv::Mat& rgb, const cv::Mat& mask, bool update_foreground) {
  if (depth_m.type() != CV_32FC1 || mask.type() != CV_8UC1 || depth_m.size() != mask.size() ||
      depth_m.cols != camera.width || depth_m.rows != camera.height)
    throw std::invalid_argument("TsdfMap::integrate: depth (32FC1) and mask (8UC1) must match the camera size");
  revision_.bump();
  const bool use_rgb = !rgb.empty();
  if (use_rgb && (rgb.type() != CV_8UC3 || rgb.size() != depth_m.size()))
    throw std::invalid_argument("TsdfMap::integrate: rgb must be 8UC3 of the depth image's size");

  const float res = static_cast<float>(params_.resolution_m);
  const float trunc = truncation_m_;
  const float to_q = 32767.f / trunc;  // metres to the fixed-point voxel's SDF steps
  const float behind_fixed = static_cast<float>(std::min(params_.behind_surface_m, params_.truncation_m));
  const float q = static_cast<float>(params_.behind_surface_quadratic_per_m);
  const float max_depth = static_cast<float>(params_.maxIntegratedDepth_m());
  // The band behind a depth d (m), or -1 beyond the integrated depth, where the noise outgrows the truncation.
  auto behindAt = [&](float d) { return d > max_depth ? -1.f : std::max(behind_fixed, q * d * d); };
  const float max_w = static_cast<float>(params_.max_weight);
  const Eigen::Isometry3f T_WCf = T_WC.cast<float>();
  const Eigen::Isometry3f T_CWf = T_WCf.inverse();
  const int B = params_.block_size;

  // 1. Allocate the blocks of the truncation band around every masked measurement.
  Eigen::Vector3i last(INT_MIN, INT_MIN, INT_MIN);
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* drow = depth_m.ptr<float>(v);
    const std::uint8_t* mrow = mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      if (!mrow[u] || mrow[u] == kMaskUnknown || !validDepth(drow[u], camera)) continue;
      const float behind = behindAt(drow[u]);
      if (behind < 0.f) continue;
      const Eigen::Vector3f ray = camera.ray_C(static_cast<float>(u), static_cast<float>(v));
      const float n = ray.norm();
      const Eigen::Vector3f dir_W = T_WCf.linear() * (ray / n);
      const float D = drow[u] * n;
      for (float s = std::max(D - trunc, 0.f);; s += res) {
        const float sc = std::min(s, D + behind);
        const Eigen::Vector3i b = blockOf(voxelIndex(T_WCf.translation() + dir_W * sc));
        if (b != last) {
          allocate(b);
          last = b;
        }
        if (sc >= D + behind) break;
      }
    }
  }

  rebuildIndex();

  // 2. Projective update of every voxel of the blocks in front of the camera.
  float evidence[256];
  for (int m = 0; m < 256; ++m) evidence[m] = maskEvidence(static_cast<std::uint8_t>(m));
  const float block_radius = 0.87f * B * res;
  const float prior = static_cast<float>(params_.foreground_prior);
  const float prior_w = static_cast<float>(params_.foreground_prior_weight);
  std::size_t updated = 0;
  for (auto& kv : blocks_) {
    const Eigen::Vector3i base = kv.first * B;
    const Eigen::Vector3f centre_C = T_CWf * ((base.cast<float>().array() + 0.5f * B) * res).matrix();
    if (centre_C.z() < -block_radius) continue;
    Block& block = kv.second;
    int i = 0;
    for (int z = 0; z < B; ++z)
      for (int y = 0; y < B; ++y)
        for (int x = 0; x < B; ++x, ++i) {
          const Eigen::Vector3f p_C = T_CWf * voxelCentre(base + Eigen::Vector3i(x, y, z));
          if (p_C.z() <= 0.f) continue;
          const double u_px = camera.fx * p_C.x() / p_C.z() + camera.cx;
          const double v_px = camera.fy * p_C.y() / p_C.z() + camera.cy;
          // roundToInt needs |x| < 2^31 (the int conversion); anything past 1e9 px (or NaN) is off the image anyway.
          if (!(std::abs(u_px) < kFarOffImagePx && std::abs(v_px) < kFarOffImagePx)) continue;
          const int u = tsdf_fixed::roundToInt(u_px), v = tsdf_fixed::roundToInt(v_px);  // std::lround, inline
          if (u < 0 || v < 0 || u >= depth_m.cols || v >= depth_m.rows) continue;
          const float d = depth_m.at<float>(v, u);
          const std::uint8_t in_mask = mask.at<std::uint8_t>(v, u);
          if (!validDepth(d, camera) || in_mask == kMaskUnknown) continue;
          const float dist = p_C.norm();
          // Distance along the pixel's ray between the measured surface and the voxel.
          const float sdf = (d - p_C.z()) * dist / p_C.z();
          const float behind = behindAt(d);
          if (behind < 0.f || sdf < -behind) continue;
          V& vx = block[i];
          const float w = vx.weight();
          if (w <= 0.f) vx.setForeground(prior);  // before its first observation, the voxel holds the prior
          if (in_mask) {
            // Behind the surface the measurement says less (the voxel may be
            // free space hidden by an edge): weight drops linearly from 1 one
            // voxel behind to 0 at -behind_surface_m.
            const float w_obs =
                params_.depthWeight(d) * (sdf >= -res ? 1.f : (behind + sdf) / (behind - res + 1e-6f));
            if (w_obs <= 0.f) continue;
            const float w_new = w + w_obs;
            const float s = std::min(sdf, trunc);
            if (vx.fuseSdf(s, w, w_obs, w_new, trunc, to_q)) block.has_negative = true;
            vx.setWeight(std::min(w_new, max_w));
            if (std::abs(sdf) < trunc) {
              if (use_rgb) {
                const cv::Vec3b c = rgb.at<cv::Vec3b>(v, u);
                // A weighted mean of bytes, so in [0, 255]: rounded inline, as std::lround (a libm call per channel).
                for (int k = 0; k < 3; ++k)
                  vx.rgb[k] = static_cast<std::uint8_t>(
                      tsdf_fixed::roundNonNegativeToInt((vx.rgb[k] * w + c[k] * w_obs) / w_new));
              }
              vx.lowerMinDistance(dist);
            }
            if (update_foreground)
              vx.setForeground((vx.foreground() * (w + prior_w) + w_obs * evidence[in_mask]) / (w_new + prior_w));
            ++updated;
          } else if (update_foreground && w > 0.f && std::abs(sdf) < trunc) {
            // A surface outside this detection's mask passes through the voxel: likely not the object.
            vx.setForeground(vx.foreground() * (w + prior_w) / (w + prior_w + params_.depthWeight(d)));
          }
        }
  }
  return updated;
}

template <class V>
bool TsdfMapT<V>::interpolate(const Eigen::Vector3f& p_W, float& sdf_m) const {
  const Eigen::Vector3f q = p_W / static_cast<float>(params_.resolution_m) - Eigen::Vector3f::Constant(0.5f);
  const Eigen::Vector3f f0 = q.array().floor();
  const Eigen::Vector3i i0 = f0.cast<int>();
  const Eigen::Vector3f f = q - f0;
  const int B = params_.block_size;
  const Eigen::Vector3i b0 = blockOf(i0);
  const Eigen::Vector3i l0 = i0 - b0 * B;
  // Usually all 8 voxels lie in one block: one hash look-up instead of eight.
  const Block* same = nullptr;
  if (l0.x() < B - 1 && l0.y() < B - 1 && l0.z() < B - 1) {
    same = findBlock(b0);
    if (!same) return false;
  }
  float sum = 0.f;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3i o(c & 1, (c >> 1) & 1, (c >> 2) & 1);
    const V* vx;
    if (same) {
      const Eigen::Vector3i l = l0 + o;
      vx = &(*same)[l.x() + B * (l.y() + B * l.z())];
    } else {
      vx = voxel(i0 + o);
    }
    if (!vx || vx->weight() <= 0.f) return false;
    const float wgt = (o.x() ? f.x() : 1.f - f.x()) * (o.y() ? f.y() : 1.f - f.y()) * (o.z() ? f.z() : 1.f - f.z());
    sum += wgt * vx->sdf(truncation_m_);
  }
  sdf_m = sum;
  return true;
}

template <class V>
bool TsdfMapT<V>::castRay(const Eigen::Vector3f& o, const Eigen::Vector3f& dir, float t_min, float t_max,
                          TsdfRayHit& hit) const {
  Eigen::AlignedBox3f box;
  if (!allocatedBox(box)) return false;
  for (int i = 0; i < 3; ++i) {  // clip to the allocated box (slab test)
    if (std::abs(dir[i]) < 1e-9f) {
      if (o[i] < box.min()[i] || o[i] > box.max()[i]) return false;
      continue;
    }
    float a = (box.min()[i] - o[i]) / dir[i], b = (box.max()[i] - o[i]) / dir[i];
    if (a > b) std::swap(a, b);
    t_min = std::max(t_min, a);
    t_max = std::min(t_max, b);
  }
  if (t_min > t_max) return false;

  const int B = params_.block_size;
  const float res = static_cast<float>(params_.resolution_m);
  const float block_edge = res * B;
  const float step_min = 0.5f * res;
  Eigen::Vector3i key(INT_MIN, INT_MIN, INT_MIN);
  const Block* block = nullptr;
  const V* prev = nullptr;
  float prev_sdf = 0.f, prev_t = 0.f;
  for (float t = t_min; t <= t_max;) {
    const Eigen::Vector3f p = o + t * dir;
    const Eigen::Vector3i vi = voxelIndex(p);
    const Eigen::Vector3i bk = blockOf(vi);
    if (bk != key) {
      key = bk;
      block = findBlock(bk);
    }
    if (!block || !block->has_negative) {
      // No crossing can end in this block: step over it in one go.
      float t_exit = t_max;
      for (int i = 0; i < 3; ++i) {
        if (std::abs(dir[i]) < 1e-9f) continue;
        const float face = (dir[i] > 0 ? bk[i] + 1 : bk[i]) * block_edge;
        t_exit = std::min(t_exit, (face - o[i]) / dir[i]);
      }
      prev = nullptr;
      if (block) {  // its last voxel on the ray may start a crossing into the next block
        const float t_last = std::max(t, t_exit - 0.25f * res);
        const Eigen::Vector3i l = voxelIndex(o + t_last * dir) - bk * B;
        if ((l.array() >= 0).all() && (l.array() < B).all()) {
          const V& last = (*block)[l.x() + B * (l.y() + B * l.z())];
          if (last.weight() > 0.f) {
            prev = &last;
            prev_sdf = last.sdf(truncation_m_);
            prev_t = t_last;
          }
        }
      }
      t = std::max(t_exit, t) + 1e-3f * res;
      continue;
    }
    const Eigen::Vector3i l = vi - bk * B;
    const V& vx = (*block)[l.x() + B * (l.y() + B * l.z())];
    if (vx.weight() <= 0.f) {  // surfaces are bracketed by observed voxels: one voxel per step is enough
      prev = nullptr;
      t += res;
      continue;
    }
    float sdf = vx.sdf(truncation_m_);
    // Near the surface the nearest voxel is too coarse (a grazing ray can pass
    // between voxel centres that are all positive): interpolate there.
    float interpolated;
    if (std::abs(sdf) < res && interpolate(p, interpolated)) sdf = interpolated;
    if (prev && prev_sdf > 0.f && sdf <= 0.f && prev->foreground() + vx.foreground() > 2.f * tracked_foreground_) {
      hit.distance_m = prev_t + (t - prev_t) * prev_sdf / (prev_sdf - sdf);
      hit.min_distance_m = std::min(prev->minDistance(), vx.minDistance());
      return true;
    }
    prev = &vx;
    prev_sdf = sdf;
    prev_t = t;
    t += std::max(step_min, 0.5f * sdf);
  }
  return false;
}

template <class V>
std::size_t TsdfMapT<V>::dropForegroundBeyond(const Eigen::Vector3f& normal_W, float offset_m) {
  const int B = params_.block_size;
  std::size_t changed = 0;
  revision_.bump();
  for (auto& kv : blocks_) {
    const Eigen::Vector3i base = kv.first * B;
    for (int z = 0, i = 0; z < B; ++z)
      for (int y = 0; y < B; ++y)
        for (int x = 0; x < B; ++x, ++i) {
          V& vx = kv.second[i];
          if (vx.foreground() <= 0.f) continue;
          if (normal_W.dot(voxelCentre(base + Eigen::Vector3i(x, y, z))) <= offset_m) continue;
          vx.setForeground(0.f);
          ++changed;
        }
  }
  return changed;
}

template <class V>
void TsdfMapT<V>::loadBlocks(std::vector<SavedBlock> blocks) {
  for (const SavedBlock& b : blocks)
    if (b.voxels.size() != static_cast<std::size_t>(voxels_per_block_))
      throw std::invalid_argument("TsdfMap::loadBlocks: a block must hold block_size^3 voxels");
  revision_.bump();
  for (SavedBlock& b : blocks) {
    Block& dst = allocate(b.index);
    dst.voxels = std::move(b.voxels);
    dst.has_negative = b.has_negative;
  }
  rebuildIndex();
}

template <class V>
void TsdfMapT<V>::mergeFrom(const TsdfMapT& other) {
  if (other.params_.resolution_m != params_.resolution_m || other.params_.block_size != params_.block_size)
    throw std::invalid_argument("TsdfMap::mergeFrom: maps differ in resolution or block size");
  revision_.bump();
  const float trunc = truncation_m_, other_trunc = other.truncation_m_;
  const float max_w = static_cast<float>(params_.max_weight);
  for (const auto& kv : other.blocks_) {
    Block& dst = allocate(kv.first);
    for (int i = 0; i < voxels_per_block_; ++i) {
      const V& s = kv.second[i];
      const float w2 = s.weight();
      if (w2 <= 0.f) continue;
      V& d = dst[i];
      const float w1 = d.weight(), w = w1 + w2;
      const float sdf = (d.sdf(trunc) * w1 + std::max(-trunc, std::min(trunc, s.sdf(other_trunc))) * w2) / w;
      d.setSdf(sdf, trunc);
      if (sdf < 0.f) dst.has_negative = true;
      d.setForeground((d.foreground() * w1 + s.foreground() * w2) / w);
      for (int k = 0; k < 3; ++k) d.rgb[k] = static_cast<std::uint8_t>(std::lround((d.rgb[k] * w1 + s.rgb[k] * w2) / w));
      if (s.minDistance() < d.minDistance()) d.setMinDistance(s.minDistance());
      d.setWeight(std::min(w, max_w));
    }
  }
  rebuildIndex();
}

template <class V>
Mesh TsdfMapT<V>::extractMesh(const MeshGate& gate) const {
  const auto& table = MarchingCubesTable::get();
  const int B = params_.block_size;
  const float res = static_cast<float>(params_.resolution_m);
  Mesh mesh;
  std::unordered_map<std::uint64_t, std::uint32_t> vertex_of_edge;
  const float fg_sum_min = 8.f * gate.min_foreground;  // the mean of 8 over the bound: 0.5 gives exactly 4
  for (const auto& kv : blocks_) {
    // The block and its +x/+y/+z neighbours hold the 8 corners of every cube starting in this block.
    const Block* nb[8];
    for (int c = 0; c < 8; ++c) {
      nb[c] = findBlock(kv.first + Eigen::Vector3i(c & 1, (c >> 1) & 1, (c >> 2) & 1));
    }
    const Eigen::Vector3i base = kv.first * B;
    for (int z = 0; z < B; ++z)
      for (int y = 0; y < B; ++y)
        for (int x = 0; x < B; ++x) {
          const V* corner[8];
          float sdf[8];
          bool ok = true;
          int mc_case = 0;
          float fg = 0.f;
          for (int c = 0; c < 8 && ok; ++c) {
            const int cx = x + (c & 1), cy = y + ((c >> 1) & 1), cz = z + ((c >> 2) & 1);
            const int which = (cx == B) | ((cy == B) << 1) | ((cz == B) << 2);
            const Block* blk = nb[which];
            if (!blk) {
              ok = false;
              break;
            }
            const V& vx = (*blk)[(cx % B) + B * ((cy % B) + B * (cz % B))];
            if (!gate.passes(vx.weight(), vx.minDistance())) {
              ok = false;
              break;
            }
            corner[c] = &vx;
            sdf[c] = vx.sdf(truncation_m_);
            fg += vx.foreground();
            if (sdf[c] < 0.f) mc_case |= 1 << c;
          }
          if (!ok || mc_case == 0 || mc_case == 255 || fg <= fg_sum_min) continue;
          const Eigen::Vector3i g = base + Eigen::Vector3i(x, y, z);
          const auto& tris = table.triangles[mc_case];
          for (int k = 0; tris[k] >= 0; k += 3) {
            std::array<std::uint32_t, 3> tri;
            for (int j = 0; j < 3; ++j) {
              const int e = tris[k + j];
              const int a = MarchingCubesTable::kEdgeCorners[e][0], b = MarchingCubesTable::kEdgeCorners[e][1];
              const Eigen::Vector3i ga = g + Eigen::Vector3i(a & 1, (a >> 1) & 1, (a >> 2) & 1);
              const int axis = (a ^ b) == 1 ? 0 : ((a ^ b) == 2 ? 1 : 2);
              const auto ins = vertex_of_edge.emplace(edgeKey(ga, axis), static_cast<std::uint32_t>(mesh.vertices_W.size()));
              if (ins.second) {
                const float s = sdf[a] / (sdf[a] - sdf[b]);
                Eigen::Vector3f p = voxelCentre(ga);
                p[axis] += s * res;
                mesh.vertices_W.push_back(p);
                std::array<std::uint8_t, 3> col;
                for (int ch = 0; ch < 3; ++ch)
                  col[ch] = static_cast<std::uint8_t>(
                      std::lround(corner[a]->rgb[ch] + s * (corner[b]->rgb[ch] - corner[a]->rgb[ch])));
                mesh.colours.push_back(col);
              }
              tri[j] = ins.first->second;
            }
            mesh.triangles.push_back(tri);
          }
        }
  }
  return mesh;
}

template <class V>
TsdfSummary TsdfMapT<V>::summarize(double d_obj_m, bool tracked) const {
  TsdfSummary s;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::size_t observed = 0;
  Eigen::AlignedBox3d box;
  forEachVoxel([&](const Eigen::Vector3i& index, const V& vx) {
    s.weight_sum += vx.weight();
    if (!isSurfaceVoxel(vx, tracked)) return;
    const Eigen::Vector3d c = voxelCentre(index).template cast<double>();
    box.extend(c);
    sum += c;
    ++s.voxel_count;
    if (vx.minDistance() <= d_obj_m) ++observed;
  });
  if (s.voxel_count > 0) {
    const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5 * params_.resolution_m);
    s.bbox_min_W = box.min() - half;
    s.bbox_max_W = box.max() + half;
    s.centroid_W = sum / static_cast<double>(s.voxel_count);
    s.observed_fraction = static_cast<double>(observed) / static_cast<double>(s.voxel_count);
  }
  return s;
}

template <class V>
bool TsdfMapT<V>::hasSurface() const {
  for (const auto& kv : blocks_)
    for (const V& vx : kv.second.voxels)
      if (isSurfaceVoxel(vx, true)) return true;
  return false;
}

template class TsdfMapT<TsdfVoxel>;
template class TsdfMapT<TsdfVoxelFloat>;

}  // namespace semexp

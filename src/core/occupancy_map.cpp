// Background occupancy map: geometry, integration and summaries.
#include "semantic_exploration/core/occupancy_map.hpp"

#include "semantic_exploration/core/gains.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <stdexcept>

namespace semexp {

namespace {

// Calls f(cx, cy, cz) for each of the (up to eight) children of node
// (ix, iy, iz) that exist in the finer level of dimensions `child_dims`.
template <typename F>
inline void forEachChild(const Eigen::Vector3i& child_dims, int ix, int iy, int iz, F&& f) {
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const int cx = 2 * ix + dx, cy = 2 * iy + dy, cz = 2 * iz + dz;
        if (cx < child_dims.x() && cy < child_dims.y() && cz < child_dims.z()) f(cx, cy, cz);
      }
}

}  // namespace

namespace {
constexpr std::uint16_t kNoDist = 0xFFFF;

inline std::uint16_t toMm(float d_m) {
  return static_cast<std::uint16_t>(std::min(d_m * 1000.f + 0.5f, 65534.f));  // d_m >= 0
}
inline std::int16_t toFixed(double l) { return static_cast<std::int16_t>(std::lround(l * OccupancyMap::kScale)); }
}  // namespace

struct OccupancyMap::FrameCtx {
  Eigen::Matrix3d R_CW;
  Eigen::Vector3d t_CW;
  Eigen::Vector3d cam_W;
  float fx, fy, cx, cy;
  int W, H;
  const std::uint8_t* rgb;
  float band;
  IntegrationStats stats;
  std::vector<int> changed;

  // min free limit (0 where invalid) and max depth over valid pixels of the rectangle
  // (inclusive), read from the pyramid at the finest level where it spans <= 4x4 cells.
  void query(const OccupancyMap& m, int u0, int u1, int v0, int v1, float& mn, float& mx) const {
    int j = 0;
    while (((u1 >> j) - (u0 >> j)) > 3 || ((v1 >> j) - (v0 >> j)) > 3) ++j;
    const int w = m.pyr_dims_[j].x();
    // level 0 is the validated depth itself (invalid = 0 serves both min and max)
    const float* pmn = j == 0 ? m.free_buf_.data() : m.pyr_min_[j].data();
    const float* pmx = j == 0 ? m.depth_buf_.data() : m.pyr_max_[j].data();
    mn = std::numeric_limits<float>::infinity();
    mx = 0.f;
    for (int v = v0 >> j; v <= (v1 >> j); ++v)
      for (int u = u0 >> j; u <= (u1 >> j); ++u) {
        mn = std::min(mn, pmn[v * w + u]);
        mx = std::max(mx, pmx[v * w + u]);
      }
  }
};

OccupancyMap::OccupancyMap(const BackgroundMapConfig& config, const Bounds& bounds) : cfg_(config), bounds_(bounds) {
  cfg_.validate();
  bounds_.validate();
  initGeometry();
}

void OccupancyMap::initGeometry() {
  res_ = cfg_.resolution_m;
  bs_ = cfg_.block_size;
  bshift_ = 0;
  while ((1 << bshift_) < bs_) ++bshift_;
  bs3_ = bs_ * bs_ * bs_;
  fwords_ = (bs3_ + 63) / 64;
  for (int i = 0; i < 3; ++i) {
    origin_[i] = std::floor(bounds_.min_m[i] / res_ + 1e-6) * res_;
    const double nvox = std::ceil((bounds_.max_m[i] - origin_[i]) / res_ - 1e-6);
    nb_[i] = std::max(1, static_cast<int>(std::ceil(nvox / bs_)));
  }
  l_free_ = toFixed(cfg_.log_odds_free);
  l_occ_ = toFixed(cfg_.log_odds_occupied);
  l_min_ = toFixed(cfg_.log_odds_min);
  l_max_ = toFixed(cfg_.log_odds_max);
  // Reducible entropy (gains.hpp) of every storable log-odds value, indexed by value - l_min_.
  entropy_lut_.resize(static_cast<std::size_t>(l_max_ - l_min_ + 1));
  for (std::size_t i = 0; i < entropy_lut_.size(); ++i)
    entropy_lut_[i] = static_cast<float>(reducibleEntropy((l_min_ + static_cast<int>(i)) / kScale, l_min_ / kScale,
                                                          l_max_ / kScale));
  const std::size_t ncell = static_cast<std::size_t>(nb_.prod());
  cell_block_.assign(ncell, -1);
  cell_value_.assign(ncell, kUnknown);
  cell_dist_.assign(ncell, kNoDist);
  cell_flags_.assign(ncell, 0);
  cell_stamp_.assign(ncell, 0);
  levels_.clear();
  Level l0;
  l0.dims = nb_;
  l0.s.assign(ncell, Summary{INT16_MAX, INT16_MIN, 0, 1});
  levels_.push_back(std::move(l0));
  while ((levels_.back().dims.array() > 1).any()) {
    Level l;
    l.dims = (levels_.back().dims.array() + 1) / 2;
    l.s.assign(static_cast<std::size_t>(l.dims.prod()), Summary{INT16_MAX, INT16_MIN, 0, 1});
    levels_.push_back(std::move(l));
  }
}

int OccupancyMap::allocateBlock(int cell) {
  int b;
  if (!free_slots_.empty()) {
    b = free_slots_.back();
    free_slots_.pop_back();
  } else {
    b = static_cast<int>(block_cell_.size());
    if (block_cell_.size() == block_cell_.capacity()) {
      // Grow by a quarter rather than doubling: the pools are most of the memory.
      const std::size_t cap = block_cell_.capacity() + block_cell_.capacity() / 4 + 64;
      block_cell_.reserve(cap);
      block_surf_.reserve(cap);
      block_nfree_.reserve(cap);
      block_nocc_.reserve(cap);
      block_l_.reserve(cap * bs3_);
      block_front_.reserve(cap * fwords_);
      block_hit_.reserve(cap * fwords_);
    }
    block_cell_.push_back(-1);
    block_surf_.push_back(-1);
    block_nfree_.push_back(0);
    block_nocc_.push_back(0);
    block_l_.resize(block_l_.size() + bs3_);
    block_front_.resize(block_front_.size() + fwords_);
    block_hit_.resize(block_hit_.size() + fwords_);
  }
  block_cell_[b] = cell;
  const std::size_t o = static_cast<std::size_t>(b) * bs3_;
  std::fill_n(block_l_.begin() + o, bs3_, cell_value_[cell]);
  block_surf_[b] = -1;
  std::fill_n(block_front_.begin() + static_cast<std::size_t>(b) * fwords_, fwords_, 0);
  std::fill_n(block_hit_.begin() + static_cast<std::size_t>(b) * fwords_, fwords_, 0);
  cell_block_[cell] = b;
  ++block_count_;
  return b;
}

int OccupancyMap::ensureSurface(int b) {
  if (block_surf_[b] >= 0) return block_surf_[b];
  int sl;
  if (!surf_free_.empty()) {
    sl = surf_free_.back();
    surf_free_.pop_back();
  } else {
    sl = static_cast<int>(surf_slots_++);
    if (block_dist_.size() == block_dist_.capacity()) {
      const std::size_t cap = block_dist_.capacity() / bs3_ + block_dist_.capacity() / bs3_ / 4 + 64;
      block_dist_.reserve(cap * bs3_);
      if (cfg_.integrate_colour) block_rgbw_.reserve(cap * 4 * bs3_);
    }
    block_dist_.resize(block_dist_.size() + bs3_);
    if (cfg_.integrate_colour) block_rgbw_.resize(block_rgbw_.size() + 4 * bs3_);
  }
  const std::size_t o = static_cast<std::size_t>(sl) * bs3_;
  std::fill_n(block_dist_.begin() + o, bs3_, kNoDist);
  if (cfg_.integrate_colour) std::fill_n(block_rgbw_.begin() + 4 * o, 4 * bs3_, 0);
  block_surf_[b] = sl;
  return sl;
}

void OccupancyMap::releaseBlock(int cell) {
  const int b = cell_block_[cell];
  if (b < 0) return;
  if (block_surf_[b] >= 0) {
    surf_free_.push_back(block_surf_[b]);
    block_surf_[b] = -1;
  }
  if (cell_flags_[cell] & kBlockFrontier) {
    frontier_voxels_ -= static_cast<std::size_t>(blockFrontierBits(cell));
    --frontier_block_count_;
    cell_flags_[cell] &= static_cast<std::uint8_t>(~kBlockFrontier);
  }
  block_cell_[b] = -1;
  free_slots_.push_back(b);
  cell_block_[cell] = -1;
  --block_count_;
}

// ------------------------------------------------------------ integration

IntegrationStats OccupancyMap::integrate(const cv::Mat& depth, const cv::Mat& rgb, const PinholeCamera& camera,
                                         const Eigen::Isometry3d& T_WC) {
  if (depth.rows != camera.height || depth.cols != camera.width)
    throw std::invalid_argument("depth image size disagrees with the camera intrinsics");
  if (!rgb.empty() && (rgb.rows != depth.rows || rgb.cols != depth.cols || rgb.type() != CV_8UC3))
    throw std::invalid_argument("colour image must be CV_8UC3 of the depth image's size");
  cv::Mat d32;
  if (depth.type() == CV_32FC1)
    d32 = depth.isContinuous() ? depth : depth.clone();
  else if (depth.type() == CV_16UC1)
    depth.convertTo(d32, CV_32FC1, 0.001);
  else
    throw std::invalid_argument("depth image must be CV_32FC1 (m) or CV_16UC1 (mm)");
  cv::Mat c;
  if (!rgb.empty()) c = rgb.isContinuous() ? rgb : rgb.clone();
  return integrate(d32.ptr<float>(), c.empty() ? nullptr : c.ptr<std::uint8_t>(), camera, T_WC);
}

IntegrationStats OccupancyMap::integrate(const float* depth_m, const std::uint8_t* rgb, const PinholeCamera& camera,
                                         const Eigen::Isometry3d& T_WC) {
  camera.validate();
  FrameCtx ctx;
  ctx.W = camera.width;
  ctx.H = camera.height;
  ctx.fx = static_cast<float>(camera.fx);
  ctx.fy = static_cast<float>(camera.fy);
  ctx.cx = static_cast<float>(camera.cx);
  ctx.cy = static_cast<float>(camera.cy);
  ctx.rgb = cfg_.integrate_colour ? rgb : nullptr;
  ctx.band = static_cast<float>(cfg_.surface_band_m);
  const Eigen::Isometry3d T_CW = T_WC.inverse();
  ctx.R_CW = T_CW.linear();
  ctx.t_CW = T_CW.translation();
  ctx.cam_W = T_WC.translation();

  // Validated depth (0 = invalid) and its min/max pyramid.
  const int W = ctx.W, H = ctx.H;
  depth_buf_.resize(static_cast<std::size_t>(W) * H);
  const float dmin = static_cast<float>(camera.d_min_m), dmax = static_cast<float>(camera.d_max_m);
  free_buf_.resize(depth_buf_.size());
  const float front = static_cast<float>(cfg_.surface_front_m), quad = static_cast<float>(cfg_.surface_front_quadratic_per_m);
  std::size_t invalid = 0;
  for (std::size_t i = 0; i < depth_buf_.size(); ++i) {
    const float d = depth_m[i];
    const bool ok = d > 0.f && d >= dmin && d <= dmax;  // false for NaN; inf > dmax
    depth_buf_[i] = ok ? d : 0.f;
    free_buf_[i] = ok ? std::max(0.f, d - std::max(front, quad * d * d)) : 0.f;
    invalid += !ok;
  }
  ctx.stats.invalid_pixels = invalid;
  pyr_dims_.assign(1, Eigen::Vector2i(W, H));
  pyr_min_.resize(1);
  pyr_max_.resize(1);
  pyr_min_[0].clear();  // level 0 is free_buf_ / depth_buf_ itself
  pyr_max_[0].clear();
  while (pyr_dims_.back().x() > 1 || pyr_dims_.back().y() > 1) {
    const Eigen::Vector2i pd = pyr_dims_.back();
    const Eigen::Vector2i nd((pd.x() + 1) / 2, (pd.y() + 1) / 2);
    const std::size_t j = pyr_dims_.size();
    pyr_dims_.push_back(nd);
    pyr_min_.resize(j + 1);
    pyr_max_.resize(j + 1);
    pyr_min_[j].assign(static_cast<std::size_t>(nd.x()) * nd.y(), 0.f);
    pyr_max_[j].assign(static_cast<std::size_t>(nd.x()) * nd.y(), 0.f);
    const float* pmn = j == 1 ? free_buf_.data() : pyr_min_[j - 1].data();
    const float* pmx = j == 1 ? depth_buf_.data() : pyr_max_[j - 1].data();
    for (int v = 0; v < nd.y(); ++v)
      for (int u = 0; u < nd.x(); ++u) {
        float mn = std::numeric_limits<float>::infinity(), mx = 0.f;
        for (int dv = 0; dv < 2; ++dv)
          for (int du = 0; du < 2; ++du) {
            const int uu = 2 * u + du, vv = 2 * v + dv;
            if (uu >= pd.x() || vv >= pd.y()) continue;
            mn = std::min(mn, pmn[vv * pd.x() + uu]);
            mx = std::max(mx, pmx[vv * pd.x() + uu]);
          }
        pyr_min_[j][v * nd.x() + u] = mn;
        pyr_max_[j][v * nd.x() + u] = mx;
      }
  }

  ++stamp_;
  if (stamp_ == 0) {  // wrapped: clear stamps so no cell looks already-seen
    std::fill(cell_stamp_.begin(), cell_stamp_.end(), 0);
    stamp_ = 1;
  }
  changed_scratch_.clear();
  ctx.changed.swap(changed_scratch_);

  // The voxel holding each measured endpoint is a surface voxel this frame
  // (once, however many pixels fall into it: OctoMap's discretised update).
  // Marking them first lets the per-voxel pass apply "occupied wins".
  {
    const Eigen::Matrix3f R = T_WC.linear().cast<float>();
    const Eigen::Vector3f t = ((T_WC.translation() - origin_) / res_).cast<float>();
    const Eigen::Matrix3f Rv = R / static_cast<float>(res_);
    const Eigen::Vector3i nv = nb_ * bs_;
    const int m = bs_ - 1;
    hit_cells_.clear();
    for (int v = 0; v < H; ++v) {
      const float yc = static_cast<float>((v - camera.cy) / camera.fy);
      for (int u = 0; u < W; ++u) {
        const float d = depth_buf_[v * W + u];
        if (d <= 0.f) continue;
        const float xc = static_cast<float>((u - camera.cx) / camera.fx);
        const Eigen::Vector3f q = Rv * Eigen::Vector3f(xc * d, yc * d, d) + t;  // voxel units
        if (!(q.x() >= 0.f && q.y() >= 0.f && q.z() >= 0.f && q.x() < nv.x() && q.y() < nv.y() && q.z() < nv.z()))
          continue;
        const int x = static_cast<int>(q.x()), y = static_cast<int>(q.y()), z = static_cast<int>(q.z());
        const int cell = cellIndex(x >> bshift_, y >> bshift_, z >> bshift_);
        int b = cell_block_[cell];
        if (b < 0) {
          b = allocateBlock(cell);
          ++ctx.stats.blocks_allocated;
        }
        const int i = (x & m) + bs_ * ((y & m) + bs_ * (z & m));
        std::uint64_t* hb = block_hit_.data() + static_cast<std::size_t>(b) * fwords_;
        bool first = true;
        for (int w = 0; w < fwords_; ++w) first = first && hb[w] == 0;
        if (first) hit_cells_.push_back(cell);
        hb[i >> 6] |= std::uint64_t{1} << (i & 63);
      }
    }
  }
  visitNode(ctx, static_cast<int>(levels_.size()) - 1, 0, 0, 0);
  // Endpoint cells the octree walk did not reach (numerical edge cases).
  for (int cell : hit_cells_) {
    const std::uint64_t* hb = block_hit_.data() + static_cast<std::size_t>(cell_block_[cell]) * fwords_;
    bool any = false;
    for (int w = 0; w < fwords_; ++w) any = any || hb[w] != 0;
    if (any) updateCellVoxels(ctx, cell);
  }
  ctx.stats.changed_cells = ctx.changed.size();
  refreshSummaries(ctx.changed);
  changed_scratch_.swap(ctx.changed);
  return ctx.stats;
}

void OccupancyMap::visitNode(FrameCtx& ctx, int k, int ix, int iy, int iz) {
  const int S = bs_ << k;
  const Eigen::Vector3i lo(ix * S, iy * S, iz * S);
  const Eigen::Vector3i hi = (lo.array() + S).min(nb_.array() * bs_);
  const Eigen::Vector3d lo_W = origin_ + lo.cast<double>() * res_;
  const Eigen::Vector3d ext = (hi - lo).cast<double>() * res_;
  const Eigen::Vector3d c0 = ctx.R_CW * lo_W + ctx.t_CW;
  const Eigen::Vector3d ax = ctx.R_CW.col(0) * ext.x(), ay = ctx.R_CW.col(1) * ext.y(),
                        az = ctx.R_CW.col(2) * ext.z();
  double zmin = 1e300, zmax = -1e300, umin = 1e300, umax = -1e300, vmin = 1e300, vmax = -1e300;
  bool crosses = false;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p = c0 + ((c & 1) ? ax : Eigen::Vector3d::Zero()) + ((c & 2) ? ay : Eigen::Vector3d::Zero()) +
                              ((c & 4) ? az : Eigen::Vector3d::Zero());
    zmin = std::min(zmin, p.z());
    zmax = std::max(zmax, p.z());
    if (p.z() <= 1e-3) {
      crosses = true;
      continue;
    }
    const double u = ctx.fx * p.x() / p.z() + ctx.cx, v = ctx.fy * p.y() / p.z() + ctx.cy;
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    vmin = std::min(vmin, v);
    vmax = std::max(vmax, v);
  }
  if (zmax <= 1e-3) return;  // wholly behind the camera
  // Visit the children (or, at the cell level, update the voxels).
  const auto descend = [&]() {
    if (k == 0) {
      updateCellVoxels(ctx, cellIndex(ix, iy, iz));
      return;
    }
    forEachChild(levels_[k - 1].dims, ix, iy, iz, [&](int cx, int cy, int cz) { visitNode(ctx, k - 1, cx, cy, cz); });
  };
  if (crosses) {  // contains or touches the camera plane: cannot bound the footprint
    descend();
    return;
  }
  const double lim = 1e7;
  const int u0 = static_cast<int>(std::floor(std::max(-lim, umin) + 0.5));
  const int u1 = static_cast<int>(std::floor(std::min(lim, umax) + 0.5));
  const int v0 = static_cast<int>(std::floor(std::max(-lim, vmin) + 0.5));
  const int v1 = static_cast<int>(std::floor(std::min(lim, vmax) + 0.5));
  if (u1 < 0 || v1 < 0 || u0 >= ctx.W || v0 >= ctx.H) return;  // outside the frustum
  const bool partial = u0 < 0 || v0 < 0 || u1 >= ctx.W || v1 >= ctx.H;
  float mn, mx;
  ctx.query(*this, std::max(u0, 0), std::min(u1, ctx.W - 1), std::max(v0, 0), std::min(v1, ctx.H - 1), mn, mx);
  if (zmin > mx + ctx.band) return;  // behind every measured surface (or no valid depth at all)
  if (!partial && zmax < mn) {  // wholly in front of the nearest surface (and its margin): free at this scale
    freeRegion(ctx, k, ix, iy, iz);
    return;
  }
  descend();
}

void OccupancyMap::freeRegion(FrameCtx& ctx, int k, int ix, int iy, int iz) {
  const Level& L = levels_[k];
  const Summary& s = L.s[ix + L.dims.x() * (iy + L.dims.y() * iz)];
  // Everything below already at the free clamp: the update cannot change it.
  if (s.known_any && !s.unknown_any && s.max_l <= l_min_) return;
  if (k == 0) {
    freeCell(ctx, cellIndex(ix, iy, iz));
    return;
  }
  forEachChild(levels_[k - 1].dims, ix, iy, iz, [&](int cx, int cy, int cz) { freeRegion(ctx, k - 1, cx, cy, cz); });
}

void OccupancyMap::freeCell(FrameCtx& ctx, int cell) {
  const int bz = cell / (nb_.x() * nb_.y()), by = (cell / nb_.x()) % nb_.y(), bx = cell % nb_.x();
  const int b = cell_block_[cell];
  const int lf = l_free_, lmin = l_min_;
  if (b < 0) {
    const std::int16_t v = cell_value_[cell];
    const std::int16_t nv = static_cast<std::int16_t>(v == kUnknown ? std::max(lf, lmin) : std::max(lmin, v + lf));
    if (nv != v) {
      cell_value_[cell] = nv;
      if (cell_stamp_[cell] != stamp_) {
        cell_stamp_[cell] = stamp_;
        ctx.changed.push_back(cell);
      }
    }
    if (cfg_.integrate_min_distance) {
      const Eigen::Vector3d c = origin_ + (Eigen::Vector3d(bx, by, bz) * bs_ + Eigen::Vector3d::Constant(0.5 * bs_)) * res_;
      cell_dist_[cell] = std::min(cell_dist_[cell], toMm(static_cast<float>((c - ctx.cam_W).norm())));
    }
    return;
  }
  std::int16_t* L = block_l_.data() + static_cast<std::size_t>(b) * bs3_;
  std::uint16_t* D = block_surf_[b] >= 0 ? block_dist_.data() + static_cast<std::size_t>(block_surf_[b]) * bs3_ : nullptr;
  bool changed = false;
  const Eigen::Vector3d c0 = origin_ + (Eigen::Vector3d(bx, by, bz) * bs_ + Eigen::Vector3d::Constant(0.5)) * res_ - ctx.cam_W;
  int i = 0;
  for (int z = 0; z < bs_; ++z)
    for (int y = 0; y < bs_; ++y)
      for (int x = 0; x < bs_; ++x, ++i) {
        const std::int16_t v = L[i];
        const std::int16_t nv = static_cast<std::int16_t>(v == kUnknown ? std::max(lf, lmin) : std::max(lmin, v + lf));
        if (nv != v) {
          L[i] = nv;
          changed = true;
        }
        if (D && cfg_.integrate_min_distance) {
          const double d = (c0 + Eigen::Vector3d(x, y, z) * res_).norm();
          D[i] = std::min(D[i], toMm(static_cast<float>(d)));
        }
      }
  if (changed && cell_stamp_[cell] != stamp_) {
    cell_stamp_[cell] = stamp_;
    ctx.changed.push_back(cell);
  }
}

void OccupancyMap::updateCellVoxels(FrameCtx& ctx, int cell) {
  const bool was_uniform = cell_block_[cell] < 0;
  const int b = was_uniform ? allocateBlock(cell) : cell_block_[cell];
  const int bz = cell / (nb_.x() * nb_.y()), by = (cell / nb_.x()) % nb_.y(), bx = cell % nb_.x();
  std::int16_t* L = block_l_.data() + static_cast<std::size_t>(b) * bs3_;
  // Surface data pointers; allocated at the first occupied update of this block.
  std::uint16_t* Dm = nullptr;
  std::uint8_t* C = nullptr;
  auto attachSurface = [&] {
    const std::size_t sl = static_cast<std::size_t>(ensureSurface(b));
    Dm = block_dist_.data() + sl * bs3_;
    if (cfg_.integrate_colour) C = block_rgbw_.data() + sl * bs3_ * 4;
  };
  if (block_surf_[b] >= 0) attachSurface();
  const Eigen::Vector3d c0_W = origin_ + (Eigen::Vector3d(bx, by, bz) * bs_ + Eigen::Vector3d::Constant(0.5)) * res_;
  const Eigen::Vector3f c0 = (ctx.R_CW * c0_W + ctx.t_CW).cast<float>();
  const Eigen::Vector3f ex = (ctx.R_CW.col(0) * res_).cast<float>();
  const Eigen::Vector3f ey = (ctx.R_CW.col(1) * res_).cast<float>();
  const Eigen::Vector3f ez = (ctx.R_CW.col(2) * res_).cast<float>();
  const float fx = ctx.fx, fy = ctx.fy, cx = ctx.cx, cy = ctx.cy;
  const float umax = ctx.W - 0.5f, vmax = ctx.H - 0.5f;
  const float band = ctx.band;
  const float half_vox_px = 0.5f * static_cast<float>(res_) * std::min(fx, fy);
  const int lf = l_free_, lo = l_occ_, lmin = l_min_, lmax = l_max_;
  const float* depth = depth_buf_.data();
  const float* freelim = free_buf_.data();
  const int W = ctx.W;
  const bool track_dist = cfg_.integrate_min_distance;
  std::uint64_t* hits = block_hit_.data() + static_cast<std::size_t>(b) * fwords_;
  bool changed = false;
  std::size_t updated = 0;
  int i = 0;
  for (int z = 0; z < bs_; ++z)
    for (int y = 0; y < bs_; ++y) {
      Eigen::Vector3f p = c0 + ey * static_cast<float>(y) + ez * static_cast<float>(z);
      for (int x = 0; x < bs_; ++x, ++i, p += ex) {
        const bool hit = (hits[i >> 6] >> (i & 63)) & 1u;
        int pix = -1;
        float d = 0.f, fl = 0.f;
        if (p.z() > 1e-3f) {
          const float iz = 1.f / p.z();
          float uf = fx * p.x() * iz + cx, vf = fy * p.y() * iz + cy;
          // A voxel whose centre projects just outside the image is still
          // crossed by the border rays: use the nearest border pixel.
          const float margin = half_vox_px * iz;
          if (uf >= -0.5f - margin && vf >= -0.5f - margin && uf < umax + margin && vf < vmax + margin) {
            uf = std::min(std::max(uf, 0.f), umax - 0.5f);
            vf = std::min(std::max(vf, 0.f), vmax - 0.5f);
            pix = static_cast<int>(vf + 0.5f) * W + static_cast<int>(uf + 0.5f);
            d = depth[pix];
            fl = freelim[pix];
          }
        }
        if (!hit && d <= 0.f) continue;
        const std::int16_t old = L[i];
        const int base = old == kUnknown ? 0 : old;
        std::int16_t nv;
        if (!hit && p.z() < fl) {
          nv = static_cast<std::int16_t>(std::max(lmin, base + lf));
        } else if (hit || p.z() <= d + band) {
          nv = static_cast<std::int16_t>(std::min(lmax, base + lo));
          if (!Dm) attachSurface();
          if (C && ctx.rgb && d > 0.f) {
            std::uint8_t* c = C + 4 * i;
            const int w = c[3];
            const std::uint8_t* in = ctx.rgb + 3 * pix;
            for (int ch = 0; ch < 3; ++ch) c[ch] = static_cast<std::uint8_t>((c[ch] * w + in[ch] + (w + 1) / 2) / (w + 1));
            c[3] = static_cast<std::uint8_t>(std::min(255, w + 1));
          }
        } else {
          continue;
        }
        ++updated;
        if (nv != old) {
          L[i] = nv;
          changed = true;
        }
        if (track_dist && Dm) {
          const std::uint16_t dm = toMm(p.norm());
          if (dm < Dm[i]) Dm[i] = dm;
        }
      }
    }
  std::fill_n(hits, fwords_, 0);
  ctx.stats.voxels_updated += updated;
  if (changed) {
    if (was_uniform) ++ctx.stats.blocks_allocated;
    if (cell_stamp_[cell] != stamp_) {
      cell_stamp_[cell] = stamp_;
      ctx.changed.push_back(cell);
    }
  } else if (was_uniform) {
    // Nothing measurable fell into it: keep the uniform leaf (distances are
    // dropped with it; they only matter for occupied voxels).
    releaseBlock(cell);
  }
}

OccupancyMap::Summary OccupancyMap::cellSummary(int cell) {
  const int b = cell_block_[cell];
  if (b < 0) {
    const std::int16_t v = cell_value_[cell];
    if (v == kUnknown) return Summary{INT16_MAX, INT16_MIN, 0, 1};
    return Summary{v, v, 1, 0};
  }
  const std::int16_t* L = block_l_.data() + static_cast<std::size_t>(b) * bs3_;
  int mn = INT16_MAX, mx = INT16_MIN, nfree = 0, nocc = 0;
  bool unk = false;
  for (int i = 0; i < bs3_; ++i) {
    const int v = L[i];
    if (v == kUnknown) {
      unk = true;
      continue;
    }
    mn = std::min(mn, v);
    mx = std::max(mx, v);
    nfree += v < 0;
    nocc += v >= 0;
  }
  block_nfree_[b] = static_cast<std::uint32_t>(nfree);
  block_nocc_[b] = static_cast<std::uint32_t>(nocc);
  const bool known = mn <= mx;
  return Summary{static_cast<std::int16_t>(mn), static_cast<std::int16_t>(mx), static_cast<std::uint8_t>(known),
                 static_cast<std::uint8_t>(unk)};
}

void OccupancyMap::refreshSummaries(std::vector<int>& cells, bool track) {
  std::vector<int> cur;
  cur.reserve(cells.size());
  for (int c : cells) {
    Summary sm = cellSummary(c);
    if (cell_block_[c] >= 0 && !sm.unknown_any && sm.min_l == sm.max_l && sm.max_l < 0) {
      // A block of equal free voxels is a uniform leaf again: give the memory back.
      releaseBlock(c);
      cell_value_[c] = sm.min_l;
      cell_dist_[c] = kNoDist;
    }
    levels_[0].s[c] = sm;
    cur.push_back(c);
    if (!track) continue;
    if (!(cell_flags_[c] & kDirty)) {
      cell_flags_[c] |= kDirty;
      dirty_cells_.push_back(c);
    }
    if (!(cell_flags_[c] & kFrontierCand)) {
      cell_flags_[c] |= kFrontierCand;
      frontier_cand_.push_back(c);
    }
  }
  for (std::size_t k = 1; k < levels_.size(); ++k) {
    const Eigen::Vector3i& pd = levels_[k - 1].dims;
    const Eigen::Vector3i& d = levels_[k].dims;
    for (int& c : cur) {
      const int x = c % pd.x(), y = (c / pd.x()) % pd.y(), z = c / (pd.x() * pd.y());
      c = (x >> 1) + d.x() * ((y >> 1) + d.y() * (z >> 1));
    }
    std::sort(cur.begin(), cur.end());
    cur.erase(std::unique(cur.begin(), cur.end()), cur.end());
    for (int c : cur) {
      const int x = c % d.x(), y = (c / d.x()) % d.y(), z = c / (d.x() * d.y());
      Summary s{INT16_MAX, INT16_MIN, 0, 0};
      for (int dz = 0; dz < 2; ++dz)
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int cx = 2 * x + dx, cy = 2 * y + dy, cz = 2 * z + dz;
            if (cx >= pd.x() || cy >= pd.y() || cz >= pd.z()) continue;
            const Summary& ch = levels_[k - 1].s[cx + pd.x() * (cy + pd.y() * cz)];
            s.min_l = std::min(s.min_l, ch.min_l);
            s.max_l = std::max(s.max_l, ch.max_l);
            s.known_any |= ch.known_any;
            s.unknown_any |= ch.unknown_any;
          }
      levels_[k].s[c] = s;
    }
  }
}

void OccupancyMap::markFreeSphere(const Eigen::Vector3d& centre_W, double radius_m) {
  if (!(radius_m > 0.0) || !centre_W.allFinite()) return;
  const Eigen::Vector3d c = (centre_W - origin_) / res_;  // voxel units
  const double r = radius_m / res_, r2 = r * r;
  const std::int16_t lf = static_cast<std::int16_t>(std::max<int>(l_free_, l_min_));
  Eigen::Vector3i lo, hi;
  for (int i = 0; i < 3; ++i) {
    lo[i] = std::max(0, static_cast<int>(std::floor((c[i] - r) / bs_)));
    hi[i] = std::min(nb_[i] - 1, static_cast<int>(std::floor((c[i] + r) / bs_)));
  }
  std::vector<int> changed;
  for (int bz = lo.z(); bz <= hi.z(); ++bz)
    for (int by = lo.y(); by <= hi.y(); ++by)
      for (int bx = lo.x(); bx <= hi.x(); ++bx) {
        const int cell = cellIndex(bx, by, bz);
        if (!levels_[0].s[cell].unknown_any) continue;  // nothing unknown to mark
        // voxel-centre distances: is every centre of the cell inside the sphere, or any?
        double far2 = 0.0, near2 = 0.0;
        for (int i = 0; i < 3; ++i) {
          const double a = (Eigen::Vector3i(bx, by, bz)[i] * bs_ + 0.5) - c[i];
          const double b = a + (bs_ - 1);
          far2 += std::max(a * a, b * b);
          const double e = std::max({a, 0.0, -b});
          near2 += e * e;
        }
        if (near2 > r2) continue;
        if (cell_block_[cell] < 0 && far2 <= r2) {
          cell_value_[cell] = lf;  // wholly inside and uniform unknown
          changed.push_back(cell);
          continue;
        }
        const int b = cell_block_[cell] >= 0 ? cell_block_[cell] : allocateBlock(cell);
        std::int16_t* L = block_l_.data() + static_cast<std::size_t>(b) * bs3_;
        int i = 0;
        for (int z = 0; z < bs_; ++z)
          for (int y = 0; y < bs_; ++y)
            for (int x = 0; x < bs_; ++x, ++i) {
              const Eigen::Vector3d v(bx * bs_ + x + 0.5, by * bs_ + y + 0.5, bz * bs_ + z + 0.5);
              if (L[i] == kUnknown && (v - c).squaredNorm() <= r2) L[i] = lf;
            }
        changed.push_back(cell);
      }
  refreshSummaries(changed);
}

// --------------------------------------------------------------- figures

double OccupancyMap::freeVolume() const {
  std::size_t n = 0;
  for (std::size_t c = 0; c < cell_block_.size(); ++c) {
    const int b = cell_block_[c];
    if (b < 0) {
      const std::int16_t v = cell_value_[c];
      if (v != kUnknown && v < 0) n += bs3_;
      continue;
    }
    n += block_nfree_[b];
  }
  return static_cast<double>(n) * res_ * res_ * res_;
}

double OccupancyMap::occupiedVolume() const {
  std::size_t n = 0;
  for (std::size_t c = 0; c < cell_block_.size(); ++c) {
    const int b = cell_block_[c];
    if (b < 0) {
      if (cell_value_[c] >= 0) n += bs3_;
      continue;
    }
    n += block_nocc_[b];
  }
  return static_cast<double>(n) * res_ * res_ * res_;
}

std::size_t OccupancyMap::memoryBytes() const {
  std::size_t m = sizeof(*this);
  m += cell_block_.capacity() * sizeof(std::int32_t) + cell_value_.capacity() * sizeof(std::int16_t) +
       cell_dist_.capacity() * sizeof(std::uint16_t) + cell_flags_.capacity() + cell_stamp_.capacity() * sizeof(std::uint32_t);
  m += block_cell_.capacity() * sizeof(std::int32_t) + block_l_.capacity() * sizeof(std::int16_t) +
       block_dist_.capacity() * sizeof(std::uint16_t) + block_rgbw_.capacity() + block_front_.capacity() * sizeof(std::uint64_t) +
       block_surf_.capacity() * sizeof(std::int32_t) + surf_free_.capacity() * sizeof(std::int32_t) +
       (block_nfree_.capacity() + block_nocc_.capacity()) * sizeof(std::uint32_t) +
       block_hit_.capacity() * sizeof(std::uint64_t) + hit_cells_.capacity() * sizeof(int) +
       free_slots_.capacity() * sizeof(std::int32_t);
  for (const Level& l : levels_) m += l.s.capacity() * sizeof(Summary);
  m += (dirty_cells_.capacity() + frontier_cand_.capacity() + frontier_blocks_.capacity() + frontier_cells_.capacity() +
        changed_scratch_.capacity()) * sizeof(int);
  m += (depth_buf_.capacity() + free_buf_.capacity()) * sizeof(float);
  for (const auto& p : pyr_min_) m += p.capacity() * sizeof(float);
  for (const auto& p : pyr_max_) m += p.capacity() * sizeof(float);
  return m;
}

}  // namespace semexp

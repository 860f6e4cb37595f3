// Background occupancy map integration: octree walk against the depth
// pyramid, voxel update of the cells at the surface, spread over a pool.
#include "semantic_exploration/core/occupancy/integrator.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "lanes.hpp"

namespace semexp {
namespace occupancy {

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

void Integrator::TaskOut::clear() {
  changed.clear();
  state_changed.clear();
  distance_changed.clear();
  voxels_updated = blocks_allocated = 0;
  pending.clear();
  l.clear();
  dist.clear();
  rgbw.clear();
}

Integrator::Integrator(const BackgroundMapConfig& config)
    : cfg_(config),
      l_free_(toFixed(config.log_odds_free)),
      l_occ_(toFixed(config.log_odds_occupied)),
      l_min_(toFixed(config.log_odds_min)),
      l_max_(toFixed(config.log_odds_max)),
      pool_(std::make_unique<WorkerPool>(config.integration_threads)) {}

Integrator::Integrator(const Integrator& o)
    : cfg_(o.cfg_),
      l_free_(o.l_free_),
      l_occ_(o.l_occ_),
      l_min_(o.l_min_),
      l_max_(o.l_max_),
      hit_(o.hit_),
      cell_stamp_(o.cell_stamp_),
      hit_stamp_(o.hit_stamp_),
      stamp_(o.stamp_),
      pool_(std::make_unique<WorkerPool>(o.pool_->threads())) {}

Integrator& Integrator::operator=(const Integrator& o) {
  if (this != &o) *this = Integrator(o);
  return *this;
}

Integrator::~Integrator() = default;

IntegrationStats Integrator::integrate(BlockStore& store, const float* depth_m, const std::uint8_t* rgb,
                                       const PinholeCamera& camera, const Eigen::Isometry3d& T_WC,
                                       std::vector<int>& changed, SurfaceChanges* surface) {
  camera.validate();
  Frame fr;
  fr.W = camera.width;
  fr.H = camera.height;
  fr.fx = static_cast<float>(camera.fx);
  fr.fy = static_cast<float>(camera.fy);
  fr.cx = static_cast<float>(camera.cx);
  fr.cy = static_cast<float>(camera.cy);
  fr.rgb = cfg_.integrate_colour ? rgb : nullptr;
  fr.band = static_cast<float>(cfg_.surface_band_m);
  fr.gap = cfg_.free_margin_quadratic_per_m > cfg_.surface_front_quadratic_per_m;
  fr.front_m = static_cast<float>(cfg_.surface_front_m);
  fr.front_quad_per_m = static_cast<float>(cfg_.surface_front_quadratic_per_m);
  const Eigen::Isometry3d T_CW = T_WC.inverse();
  fr.R_CW = T_CW.linear();
  fr.t_CW = T_CW.translation();
  fr.cam_W = T_WC.translation();

  IntegrationStats stats;
  stats.invalid_pixels = pyr_.build(depth_m, fr.W, fr.H, static_cast<float>(camera.d_min_m),
                                    static_cast<float>(camera.d_max_m), static_cast<float>(cfg_.surface_front_m),
                                    static_cast<float>(std::max(cfg_.surface_front_quadratic_per_m,
                                                                cfg_.free_margin_quadratic_per_m)));
  if (cell_stamp_.size() != store.cellCount()) {
    cell_stamp_.assign(store.cellCount(), 0);
    hit_stamp_.assign(store.cellCount(), 0);
  }
  ++stamp_;
  if (stamp_ == 0) {  // wrapped: clear stamps so no cell looks already listed
    std::fill(cell_stamp_.begin(), cell_stamp_.end(), 0);
    std::fill(hit_stamp_.begin(), hit_stamp_.end(), 0);
    stamp_ = 1;
  }
  markEndpoints(store, camera, T_WC, stats);

  // The walk down to kSplitLevel lists the tasks; the pool does them.
  tasks_.clear();
  plan(store, fr, static_cast<int>(store.levels.size()) - 1, 0, 0, 0);
  if (outs_.size() < tasks_.size() + 1) outs_.resize(tasks_.size() + 1);
  pool_->run(tasks_.size(), [&](std::size_t i) {
    const Task& t = tasks_[i];
    TaskOut& out = outs_[i];
    out.clear();
    if (t.free)
      freeRegion(store, fr, out, t.k, t.ix, t.iy, t.iz);
    else
      descend(store, fr, out, t.k, t.ix, t.iy, t.iz);
  });
  for (std::size_t i = 0; i < tasks_.size(); ++i) merge(store, outs_[i], changed, surface, stats);
  // Endpoint cells the octree walk did not reach (numerical edge cases).
  TaskOut& rest = outs_[tasks_.size()];
  rest.clear();
  for (int cell : hit_cells_) {
    const std::uint64_t* hb = hits(store, store.cell_block[cell]);
    bool any = false;
    for (int w = 0; w < store.fwords; ++w) any = any || hb[w] != 0;
    if (any) updateCellVoxels(store, fr, rest, cell);
  }
  merge(store, rest, changed, surface, stats);
  stats.changed_cells = changed.size();
  return stats;
}

// The voxel holding each measured endpoint is a surface voxel this frame
// (once, however many pixels fall into it: OctoMap's discretised update).
// Marking them first lets the per-voxel pass apply "occupied wins". Their
// blocks are allocated here, before the walk, in pixel order.
void Integrator::markEndpoints(BlockStore& store, const PinholeCamera& camera, const Eigen::Isometry3d& T_WC,
                               IntegrationStats& stats) {
  const int bs = store.bs, bshift = store.bshift, fw = store.fwords;
  const auto fit = [&] {
    if (hit_.size() < store.slotCount() * fw) hit_.resize(store.block_cell.capacity() * fw, 0);
  };
  fit();
  const Eigen::Matrix3f R = T_WC.linear().cast<float>();
  const Eigen::Vector3f t = ((T_WC.translation() - store.origin) / store.res).cast<float>();
  const Eigen::Matrix3f Rv = R / static_cast<float>(store.res);
  const Eigen::Vector3i nv = store.nb * bs;
  const Eigen::Vector3f nvf = nv.cast<float>();
  const int m = bs - 1;
  const int W = camera.width, H = camera.height;
  const float* depth = pyr_.depth();
  // Each pixel's endpoint voxel (cell, voxel in cell; cell -1: none), rows
  // spread over the pool; then blocks and bits in pixel order on this thread.
  endpoint_.resize(static_cast<std::size_t>(W) * H);
  // Ray x per column, as each pixel computed it (a double division per pixel before).
  ray_x_.resize(static_cast<std::size_t>(W));
  for (int u = 0; u < W; ++u) ray_x_[u] = static_cast<float>((u - camera.cx) / camera.fx);
  const float* ray_x = ray_x_.data();
  const int rows = 16;
  pool_->run(static_cast<std::size_t>((H + rows - 1) / rows), [&](std::size_t chunk) {
    const int v_end = std::min(H, static_cast<int>(chunk + 1) * rows);
    for (int v = static_cast<int>(chunk) * rows; v < v_end; ++v) {
      const float yc = static_cast<float>((v - camera.cy) / camera.fy);
      int u = 0;
      // Four pixels at a time: q = Rv (xc d, yc d, d) + t with Eigen's
      // operation order (each row a0 + (a1 + a2), then + t), so the same
      // voxels as one pixel at a time.
      for (; u + lanes::kLanes <= W; u += lanes::kLanes) {
        lanes::Vf d, xc;
        std::memcpy(&d, depth + v * W + u, sizeof(d));
        std::memcpy(&xc, ray_x + u, sizeof(xc));
        const lanes::Vf X = xc * d, Y = yc * d;
        const lanes::Vf qx = (Rv(0, 0) * X + (Rv(0, 1) * Y + Rv(0, 2) * d)) + t.x();
        const lanes::Vf qy = (Rv(1, 0) * X + (Rv(1, 1) * Y + Rv(1, 2) * d)) + t.y();
        const lanes::Vf qz = (Rv(2, 0) * X + (Rv(2, 1) * Y + Rv(2, 2) * d)) + t.z();
        const lanes::Vi ok = (d > 0.f) & (qx >= 0.f) & (qy >= 0.f) & (qz >= 0.f) & (qx < nvf.x()) &
                             (qy < nvf.y()) & (qz < nvf.z());
        const lanes::Vi x = __builtin_convertvector(lanes::floats(lanes::bits(qx) & ok), lanes::Vi);
        const lanes::Vi y = __builtin_convertvector(lanes::floats(lanes::bits(qy) & ok), lanes::Vi);
        const lanes::Vi z = __builtin_convertvector(lanes::floats(lanes::bits(qz) & ok), lanes::Vi);
        for (int k = 0; k < lanes::kLanes; ++k) {
          Endpoint& e = endpoint_[static_cast<std::size_t>(v) * W + u + k];
          e.cell = ok[k] ? store.cellIndex(x[k] >> bshift, y[k] >> bshift, z[k] >> bshift) : -1;
          e.voxel = store.voxelIndex(x[k] & m, y[k] & m, z[k] & m);
        }
      }
      for (; u < W; ++u) {
        Endpoint& e = endpoint_[static_cast<std::size_t>(v) * W + u];
        e.cell = -1;
        const float d = depth[v * W + u];
        if (d <= 0.f) continue;
        const float xc = ray_x[u];
        const Eigen::Vector3f q = Rv * Eigen::Vector3f(xc * d, yc * d, d) + t;  // voxel units
        if (!(q.x() >= 0.f && q.y() >= 0.f && q.z() >= 0.f && q.x() < nv.x() && q.y() < nv.y() && q.z() < nv.z()))
          continue;
        const int x = static_cast<int>(q.x()), y = static_cast<int>(q.y()), z = static_cast<int>(q.z());
        e.cell = store.cellIndex(x >> bshift, y >> bshift, z >> bshift);
        e.voxel = store.voxelIndex(x & m, y & m, z & m);
      }
    }
  });
  hit_cells_.clear();
  // Neighbouring pixels mostly share a cell: the last cell's bits are reused.
  int last_cell = -1;
  std::uint64_t* last_bits = nullptr;
  for (const Endpoint& e : endpoint_) {
    if (e.cell < 0) continue;
    if (e.cell == last_cell) {
      last_bits[e.voxel >> 6] |= std::uint64_t{1} << (e.voxel & 63);
      continue;
    }
    int b = store.cell_block[e.cell];
    if (b < 0) {
      b = store.allocateBlock(e.cell);
      fit();
      ++stats.blocks_allocated;
    }
    if (hit_stamp_[e.cell] != stamp_) {  // the cell's first endpoint this frame
      hit_stamp_[e.cell] = stamp_;
      hit_cells_.push_back(e.cell);
    }
    last_cell = e.cell;
    last_bits = hits(store, b);  // hit_ only grows in fit(), after an allocation, before this
    last_bits[e.voxel >> 6] |= std::uint64_t{1} << (e.voxel & 63);
  }
}

Integrator::NodeClass Integrator::classify(const BlockStore& store, const Frame& fr, int k, int ix, int iy,
                                           int iz) const {
  const int S = store.bs << k;
  const Eigen::Vector3i lo(ix * S, iy * S, iz * S);
  const Eigen::Vector3i hi = (lo.array() + S).min(store.nb.array() * store.bs);
  const Eigen::Vector3d lo_W = store.origin + lo.cast<double>() * store.res;
  const Eigen::Vector3d ext = (hi - lo).cast<double>() * store.res;
  const Eigen::Vector3d c0 = fr.R_CW * lo_W + fr.t_CW;
  const Eigen::Vector3d ax = fr.R_CW.col(0) * ext.x(), ay = fr.R_CW.col(1) * ext.y(), az = fr.R_CW.col(2) * ext.z();
  double zmin = 1e300, zmax = -1e300, umin = 1e300, umax = -1e300, vmin = 1e300, vmax = -1e300;
  // Largest value over the corners of each side of the frustum as the voxel
  // update sees it (updateCellVoxels: a voxel centre p with p.z > 0 gets a
  // pixel iff all four are >= 0, e.g. left: u >= -0.5 - half_vox_px / p.z
  // <=> fx p.x + (cx + 0.5) p.z + half_vox_px >= 0). Linear in p, so a box
  // whose corners are all below zero on one side holds no voxel that gets a
  // pixel (nor a measured endpoint): skipping it changes nothing. This also
  // bounds the boxes that cross the camera plane, which the footprint below
  // cannot.
  const double hv = 0.5 * store.res * std::min(fr.fx, fr.fy);
  const double u_hi = fr.W - 0.5, v_hi = fr.H - 0.5;
  double side_max[4] = {-1e300, -1e300, -1e300, -1e300};
  bool crosses = false;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p = c0 + ((c & 1) ? ax : Eigen::Vector3d::Zero()) + ((c & 2) ? ay : Eigen::Vector3d::Zero()) +
                              ((c & 4) ? az : Eigen::Vector3d::Zero());
    zmin = std::min(zmin, p.z());
    zmax = std::max(zmax, p.z());
    side_max[0] = std::max(side_max[0], fr.fx * p.x() + (fr.cx + 0.5) * p.z() + hv);
    side_max[1] = std::max(side_max[1], (u_hi - fr.cx) * p.z() - fr.fx * p.x() + hv);
    side_max[2] = std::max(side_max[2], fr.fy * p.y() + (fr.cy + 0.5) * p.z() + hv);
    side_max[3] = std::max(side_max[3], (v_hi - fr.cy) * p.z() - fr.fy * p.y() + hv);
    if (p.z() <= 1e-3) {
      crosses = true;
      continue;
    }
    const double u = fr.fx * p.x() / p.z() + fr.cx, v = fr.fy * p.y() / p.z() + fr.cy;
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    vmin = std::min(vmin, v);
    vmax = std::max(vmax, v);
  }
  if (zmax <= 1e-3) return NodeClass::kSkip;     // wholly behind the camera
  // Wholly outside one side of the frustum, by more than a voxel's worth
  // (the voxel update computes in float: the margin covers its rounding).
  const double tol = store.res * (fr.fx + fr.fy);
  for (double g : side_max)
    if (g < -tol) return NodeClass::kSkip;
  if (crosses) return NodeClass::kDescend;        // contains or touches the camera plane: cannot bound the footprint
  const double lim = 1e7;
  const int u0 = static_cast<int>(std::floor(std::max(-lim, umin) + 0.5));
  const int u1 = static_cast<int>(std::floor(std::min(lim, umax) + 0.5));
  const int v0 = static_cast<int>(std::floor(std::max(-lim, vmin) + 0.5));
  const int v1 = static_cast<int>(std::floor(std::min(lim, vmax) + 0.5));
  if (u1 < 0 || v1 < 0 || u0 >= fr.W || v0 >= fr.H) return NodeClass::kSkip;  // outside the frustum
  const bool partial = u0 < 0 || v0 < 0 || u1 >= fr.W || v1 >= fr.H;
  float mn, mx;
  pyr_.query(std::max(u0, 0), std::min(u1, fr.W - 1), std::max(v0, 0), std::min(v1, fr.H - 1), mn, mx);
  if (zmin > mx + fr.band) return NodeClass::kSkip;  // behind every measured surface (or no valid depth at all)
  // Wholly in front of the nearest surface (and its margin): free at this scale.
  if (!partial && zmax < mn) return NodeClass::kFree;
  return NodeClass::kDescend;
}

// The same depth-first walk as visitNode, stopping at kSplitLevel to list tasks.
void Integrator::plan(const BlockStore& store, const Frame& fr, int k, int ix, int iy, int iz) {
  const NodeClass c = classify(store, fr, k, ix, iy, iz);
  if (c == NodeClass::kSkip) return;
  if (c == NodeClass::kFree) {
    planFree(store, k, ix, iy, iz);
    return;
  }
  if (k <= kSplitLevel) {
    tasks_.push_back({k, ix, iy, iz, false});
    return;
  }
  forEachChild(store.levels[k - 1].dims, ix, iy, iz, [&](int cx, int cy, int cz) { plan(store, fr, k - 1, cx, cy, cz); });
}

void Integrator::planFree(const BlockStore& store, int k, int ix, int iy, int iz) {
  const Summary& s = store.levels[k].at(ix, iy, iz);
  if (s.known_any && !s.unknown_any && s.max_l <= l_min_) return;  // see freeRegion
  if (k <= kSplitLevel) {
    tasks_.push_back({k, ix, iy, iz, true});
    return;
  }
  forEachChild(store.levels[k - 1].dims, ix, iy, iz, [&](int cx, int cy, int cz) { planFree(store, k - 1, cx, cy, cz); });
}

void Integrator::visitNode(BlockStore& store, const Frame& fr, TaskOut& out, int k, int ix, int iy, int iz) {
  switch (classify(store, fr, k, ix, iy, iz)) {
    case NodeClass::kSkip:
      return;
    case NodeClass::kFree:
      freeRegion(store, fr, out, k, ix, iy, iz);
      return;
    case NodeClass::kDescend:
      descend(store, fr, out, k, ix, iy, iz);
      return;
  }
}

// Visits the children (or, at the cell level, updates the voxels).
void Integrator::descend(BlockStore& store, const Frame& fr, TaskOut& out, int k, int ix, int iy, int iz) {
  if (k == 0) {
    updateCellVoxels(store, fr, out, store.cellIndex(ix, iy, iz));
    return;
  }
  forEachChild(store.levels[k - 1].dims, ix, iy, iz,
               [&](int cx, int cy, int cz) { visitNode(store, fr, out, k - 1, cx, cy, cz); });
}

void Integrator::freeRegion(BlockStore& store, const Frame& fr, TaskOut& out, int k, int ix, int iy, int iz) {
  const Summary& s = store.levels[k].at(ix, iy, iz);
  // Everything below already at the free clamp: the update cannot change it.
  if (s.known_any && !s.unknown_any && s.max_l <= l_min_) return;
  if (k == 0) {
    freeCell(store, fr, out, store.cellIndex(ix, iy, iz));
    return;
  }
  forEachChild(store.levels[k - 1].dims, ix, iy, iz,
               [&](int cx, int cy, int cz) { freeRegion(store, fr, out, k - 1, cx, cy, cz); });
}

// Allocates the task's new blocks and surfaces in the store (in the order the
// task met them) and appends its changed cells.
void Integrator::merge(BlockStore& store, TaskOut& out, std::vector<int>& changed, SurfaceChanges* surface,
                       IntegrationStats& stats) {
  const std::size_t bs3 = static_cast<std::size_t>(store.bs3);
  for (const Pending& p : out.pending) {
    int b = store.cell_block[p.cell];
    if (p.scratch_block >= 0) {
      b = store.allocateBlock(p.cell);
      std::memcpy(store.logOdds(b), out.l.data() + p.scratch_block * bs3, bs3 * sizeof(std::int16_t));
    }
    if (p.scratch_surface >= 0) {
      const int sl = store.ensureSurface(b);
      std::memcpy(store.dist(sl), out.dist.data() + p.scratch_surface * bs3, bs3 * sizeof(std::uint16_t));
      if (store.colour) std::memcpy(store.rgbw(sl), out.rgbw.data() + p.scratch_surface * bs3 * 4, bs3 * 4);
    }
  }
  changed.insert(changed.end(), out.changed.begin(), out.changed.end());
  if (surface) {
    surface->state_changed.insert(surface->state_changed.end(), out.state_changed.begin(), out.state_changed.end());
    surface->distance_changed.insert(surface->distance_changed.end(), out.distance_changed.begin(),
                                     out.distance_changed.end());
  }
  stats.voxels_updated += out.voxels_updated;
  stats.blocks_allocated += out.blocks_allocated;
  // Scratch blocks are rare after the first frames: give their memory back
  // rather than keep a high-water mark per task.
  std::vector<std::int16_t>().swap(out.l);
  std::vector<std::uint16_t>().swap(out.dist);
  std::vector<std::uint8_t>().swap(out.rgbw);
}

void Integrator::summarise(BlockStore& store, const std::vector<int>& cells, std::vector<Summary>& out) {
  out.resize(cells.size());
  // Chunks of 64 cells: enough work per task to pay for the hand-over.
  const std::size_t chunk = 64, n = (cells.size() + chunk - 1) / chunk;
  pool_->run(n, [&](std::size_t t) {
    const std::size_t end = std::min(cells.size(), (t + 1) * chunk);
    for (std::size_t i = t * chunk; i < end; ++i) out[i] = store.cellSummary(cells[i]);
  });
}

std::size_t Integrator::memoryBytes() const {
  std::size_t m = sizeof(*this) + pyr_.memoryBytes() + hit_.capacity() * sizeof(std::uint64_t) +
                  endpoint_.capacity() * sizeof(Endpoint) + ray_x_.capacity() * sizeof(float) +
                  hit_cells_.capacity() * sizeof(int) + (cell_stamp_.capacity() + hit_stamp_.capacity()) * sizeof(std::uint32_t) +
                  tasks_.capacity() * sizeof(Task);
  for (const TaskOut& o : outs_)
    m += (o.changed.capacity() + o.state_changed.capacity() + o.distance_changed.capacity()) * sizeof(int) +
         o.pending.capacity() * sizeof(Pending) +
         o.l.capacity() * sizeof(std::int16_t) + o.dist.capacity() * sizeof(std::uint16_t) + o.rgbw.capacity();
  return m;
}

}  // namespace occupancy
}  // namespace semexp

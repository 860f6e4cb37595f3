// Background occupancy map integration, the per-cell part: the free update
// of a whole cell and the voxel update of a cell at the measured surface.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "semantic_exploration/core/occupancy/integrator.hpp"
#include "lanes.hpp"

namespace semexp {
namespace occupancy {

namespace {

using lanes::bits;
using lanes::floats;
using lanes::kLanes;
using lanes::select;
using lanes::sqrtLanes;
using lanes::Vf;
using lanes::Vi;
constexpr int kMaxSlabX = 64;  // the largest block_size (BackgroundMapConfig::validate)

/// Camera constants of the voxel projection.
struct Projector {
  float fx, fy, cx, cy;
  float umax, vmax;   ///< W - 0.5, H - 0.5
  float half_vox_px;  ///< half a voxel at 1 m, pixels
};

// Camera-frame depth, pixel and distance of the voxels of rows r0 .. r0 + 3
// of a cell (row r = y + bs z). Lane j holds row r0 + j; entry x * kLanes + j
// of each output is voxel x of that row. PZ: depth, m. PU, PV: the pixel
// whose depth the voxel uses, PV -1 if none (behind the camera, or outside
// the image and its border margin). PD (if not null): toMm(distance to the
// camera). p0 = centre of voxel (0,0,0), e* = camera-frame voxel steps.
inline void projectSlab(const Projector& pr, const Eigen::Vector3f& p0, const Eigen::Vector3f& ex,
                        const Eigen::Vector3f& ey, const Eigen::Vector3f& ez, int bs, int bshift, int r0, float* PZ,
                        std::int32_t* PU, std::int32_t* PV, std::int32_t* PD) {
  const Vi r = Vi{0, 1, 2, 3} + r0;
  const Vf yf = __builtin_convertvector(r & (bs - 1), Vf), zf = __builtin_convertvector(r >> bshift, Vf);
  // The scalar code's p = c0 + ey * y + ez * z, then p += ex per voxel.
  Vf px = (p0.x() + ey.x() * yf) + ez.x() * zf;
  Vf py = (p0.y() + ey.y() * yf) + ez.y() * zf;
  Vf pz = (p0.z() + ey.z() * yf) + ez.z() * zf;
  const Vf zero = {}, umax_in = zero + (pr.umax - 0.5f), vmax_in = zero + (pr.vmax - 0.5f);
  for (int x = 0; x < bs; ++x) {
    const Vf iz = 1.f / pz;
    Vf uf = pr.fx * px * iz + pr.cx, vf = pr.fy * py * iz + pr.cy;
    // A voxel whose centre projects just outside the image is still crossed
    // by the border rays: it uses the nearest border pixel.
    const Vf margin = pr.half_vox_px * iz;
    const Vi in = (pz > 1e-3f) & (uf >= -0.5f - margin) & (vf >= -0.5f - margin) & (uf < pr.umax + margin) &
                  (vf < pr.vmax + margin);
    // std::min(std::max(u, 0), umax - 0.5) per lane; lanes not in the image become 0.
    uf = floats(bits(uf) & ~(uf < 0.f));
    uf = select(umax_in < uf, umax_in, uf);
    vf = floats(bits(vf) & ~(vf < 0.f));
    vf = select(vmax_in < vf, vmax_in, vf);
    const Vi u = __builtin_convertvector(floats(bits(uf) & in) + 0.5f, Vi);
    const Vi v = __builtin_convertvector(floats(bits(vf) & in) + 0.5f, Vi);
    const Vi v_or_none = (v & in) | ~in;  // -1 where not in
    std::memcpy(PZ + x * kLanes, &pz, sizeof(pz));
    std::memcpy(PU + x * kLanes, &u, sizeof(u));
    std::memcpy(PV + x * kLanes, &v_or_none, sizeof(v_or_none));
    if (PD) {  // toMm(p.norm()) per lane, summed in the order of Eigen's unrolled 3-vector squaredNorm
      const Vf dmm = sqrtLanes(px * px + (py * py + pz * pz)) * 1000.f + 0.5f;
      const Vf cap = zero + 65534.f;
      const Vi dm = __builtin_convertvector(select(cap < dmm, cap, dmm), Vi);
      std::memcpy(PD + x * kLanes, &dm, sizeof(dm));
    }
    px += ex.x();
    py += ex.y();
    pz += ex.z();
  }
}

// Unknown, free (< 0) and occupied (>= 0) are what the surface count reads (SurfaceCounter); nv is never unknown.
bool stateChanged(std::int16_t old, std::int16_t nv) { return old == kUnknown || (old < 0) != (nv < 0); }

}  // namespace

void Integrator::markChanged(TaskOut& out, int cell) {
  if (cell_stamp_[cell] == stamp_) return;
  cell_stamp_[cell] = stamp_;
  out.changed.push_back(cell);
}

void Integrator::freeCell(BlockStore& store, const Frame& fr, TaskOut& out, int cell) {
  const Eigen::Vector3i bc = store.cellCoords(cell);
  const int bs = store.bs;
  const double res = store.res;
  const int b = store.cell_block[cell];
  const int lf = l_free_, lmin = l_min_;
  if (b < 0) {
    const std::int16_t v = store.cell_value[cell];
    const std::int16_t nv = static_cast<std::int16_t>(v == kUnknown ? std::max(lf, lmin) : std::max(lmin, v + lf));
    if (nv != v) {
      store.cell_value[cell] = nv;
      markChanged(out, cell);
      if (stateChanged(v, nv)) out.state_changed.push_back(cell);
    }
    if (cfg_.integrate_min_distance) {
      const Eigen::Vector3d c = store.cellCentre(cell);
      const std::uint16_t dm = toMm(static_cast<float>((c - fr.cam_W).norm()));
      if (dm < store.cell_dist[cell]) {
        store.cell_dist[cell] = dm;
        if (nv >= 0) out.distance_changed.push_back(cell);
      }
    }
    return;
  }
  std::int16_t* L = store.logOdds(b);
  std::uint16_t* D = store.block_surf[b] >= 0 && cfg_.integrate_min_distance ? store.dist(store.block_surf[b]) : nullptr;
  bool changed = false, state_changed = false, dist_lowered = false;
  const Eigen::Vector3d c0 = store.voxelCentre(bc * bs) - fr.cam_W;
  int i = 0;
  for (int z = 0; z < bs; ++z)
    for (int y = 0; y < bs; ++y)
      for (int x = 0; x < bs; ++x, ++i) {
        const std::int16_t v = L[i];
        const std::int16_t nv = static_cast<std::int16_t>(v == kUnknown ? std::max(lf, lmin) : std::max(lmin, v + lf));
        if (nv != v) {
          L[i] = nv;
          changed = true;
          state_changed |= stateChanged(v, nv);
        }
        if (D) {
          const std::uint16_t dm = toMm(static_cast<float>((c0 + Eigen::Vector3d(x, y, z) * res).norm()));
          if (dm < D[i]) {
            D[i] = dm;
            dist_lowered |= nv >= 0;
          }
        }
      }
  if (changed) markChanged(out, cell);
  if (state_changed) out.state_changed.push_back(cell);
  if (dist_lowered) out.distance_changed.push_back(cell);
}

void Integrator::updateCellVoxels(BlockStore& store, const Frame& fr, TaskOut& out, int cell) {
  const int bs = store.bs, bs3 = store.bs3;
  const int b = store.cell_block[cell];
  const bool was_uniform = b < 0;
  // A uniform cell is refined in scratch memory: the store allocates at the merge.
  int scratch_block = -1, scratch_surface = -1;
  std::int16_t* L;
  std::uint64_t* hit_bits = nullptr;  // a uniform cell holds no endpoint (markEndpoints gave those blocks)
  if (was_uniform) {
    scratch_block = static_cast<int>(out.l.size() / bs3);
    out.l.resize(out.l.size() + bs3, store.cell_value[cell]);
    L = out.l.data() + static_cast<std::size_t>(scratch_block) * bs3;
  } else {
    L = store.logOdds(b);
    hit_bits = hits(store, b);
  }
  // Surface data pointers; allocated at the first occupied update of this block.
  std::uint16_t* Dm = nullptr;
  std::uint8_t* C = nullptr;
  const bool colour = cfg_.integrate_colour;
  auto attachSurface = [&] {
    scratch_surface = static_cast<int>(out.dist.size() / bs3);
    out.dist.resize(out.dist.size() + bs3, kNoDist);
    Dm = out.dist.data() + static_cast<std::size_t>(scratch_surface) * bs3;
    if (colour) {
      out.rgbw.resize(out.rgbw.size() + 4 * static_cast<std::size_t>(bs3), 0);
      C = out.rgbw.data() + static_cast<std::size_t>(scratch_surface) * bs3 * 4;
    }
  };
  if (!was_uniform && store.block_surf[b] >= 0) {
    Dm = store.dist(store.block_surf[b]);
    if (colour) C = store.rgbw(store.block_surf[b]);
  }
  const Eigen::Vector3i bc = store.cellCoords(cell);
  const double res = store.res;
  const Eigen::Vector3d c0_W = store.voxelCentre(bc * bs);
  const Eigen::Vector3f c0 = (fr.R_CW * c0_W + fr.t_CW).cast<float>();
  const Eigen::Vector3f ex = (fr.R_CW.col(0) * res).cast<float>();
  const Eigen::Vector3f ey = (fr.R_CW.col(1) * res).cast<float>();
  const Eigen::Vector3f ez = (fr.R_CW.col(2) * res).cast<float>();
  const float band = fr.band;
  Projector pr;
  pr.fx = fr.fx;
  pr.fy = fr.fy;
  pr.cx = fr.cx;
  pr.cy = fr.cy;
  pr.umax = fr.W - 0.5f;
  pr.vmax = fr.H - 0.5f;
  pr.half_vox_px = 0.5f * static_cast<float>(res) * std::min(fr.fx, fr.fy);
  const int W = fr.W;
  const int lf = l_free_, lo = l_occ_, lmin = l_min_, lmax = l_max_;
  const float* depth = pyr_.depth();
  const float* freelim = pyr_.freeLimit();
  const bool track_dist = cfg_.integrate_min_distance;
  bool changed = false, state_changed = false, dist_lowered = false;
  std::size_t updated = 0;
  // The cell's rows of bs voxels (row r = y + bs z, voxel i = x + bs r) go
  // in slabs of kLanes rows: the projection runs on all rows of a slab at
  // once (one vector lane per row, the same float operations in the same
  // order as one voxel at a time), then the update visits the slab's voxels
  // in index order (bs >= 2, so bs^2 rows are whole slabs).
  const int rows = bs * bs;
  alignas(32) float PZ[kLanes * kMaxSlabX];
  alignas(32) std::int32_t PU[kLanes * kMaxSlabX], PV[kLanes * kMaxSlabX], PD[kLanes * kMaxSlabX];
  for (int r0 = 0; r0 < rows; r0 += kLanes) {
    projectSlab(pr, c0, ex, ey, ez, bs, store.bshift, r0, PZ, PU, PV, track_dist ? PD : nullptr);
    const int lanes = std::min(kLanes, rows - r0);
    for (int j = 0; j < lanes; ++j) {
      int i = (r0 + j) * bs;
      for (int x = 0; x < bs; ++x, ++i) {
        const int t = x * kLanes + j;
        const bool hit = hit_bits && ((hit_bits[i >> 6] >> (i & 63)) & 1u);
        const int pix = PV[t] < 0 ? -1 : PV[t] * W + PU[t];
        const float d = pix >= 0 ? depth[pix] : 0.f;
        if (!hit && d <= 0.f) continue;
        const float fl = pix >= 0 ? freelim[pix] : 0.f;
        const float pz = PZ[t];
        const std::int16_t old = L[i];
        const int base = old == kUnknown ? 0 : old;
        std::int16_t nv;
        if (!hit && pz < fl) {
          nv = static_cast<std::int16_t>(std::max(lmin, base + lf));
        } else if (hit || (pz <= d + band && (!fr.gap || pz >= d - std::max(fr.front_m, fr.front_quad_per_m * d * d)))) {
          nv = static_cast<std::int16_t>(std::min(lmax, base + lo));
          if (!Dm) attachSurface();
          if (C && fr.rgb && d > 0.f) {
            std::uint8_t* c = C + 4 * i;
            const int w = c[3];
            const std::uint8_t* in = fr.rgb + 3 * pix;
            for (int ch = 0; ch < 3; ++ch) c[ch] = blendColour(c[ch], w, in[ch]);
            c[3] = static_cast<std::uint8_t>(std::min(255, w + 1));
          }
        } else {
          continue;
        }
        ++updated;
        if (nv != old) {
          L[i] = nv;
          changed = true;
          state_changed |= stateChanged(old, nv);
        }
        if (track_dist && Dm) {
          const std::uint16_t dm = static_cast<std::uint16_t>(PD[t]);  // toMm(p.norm())
          if (dm < Dm[i]) {
            Dm[i] = dm;
            dist_lowered |= nv >= 0;  // only an occupied voxel's distance counts (SurfaceCounter)
          }
        }
      }
    }
  }
  if (hit_bits) std::fill_n(hit_bits, store.fwords, 0);
  out.voxels_updated += updated;
  if (was_uniform && !changed) {
    // Nothing measurable fell into it: it stays a uniform leaf (distances are
    // dropped with the scratch block; they only matter for occupied voxels).
    out.l.resize(out.l.size() - bs3);
    if (scratch_surface >= 0) {
      out.dist.resize(out.dist.size() - bs3);
      if (colour) out.rgbw.resize(out.rgbw.size() - 4 * static_cast<std::size_t>(bs3));
    }
    return;
  }
  if (changed) {
    if (was_uniform) ++out.blocks_allocated;
    markChanged(out, cell);
  }
  if (state_changed) out.state_changed.push_back(cell);
  // A uniform occupied cell refined into a block keeps its log-odds but not its distance (the block's surface
  // slot starts unobserved, cell_value still holds the uniform value): its count seen from close by changes.
  if (dist_lowered || (was_uniform && store.cell_value[cell] >= 0)) out.distance_changed.push_back(cell);
  if (scratch_block >= 0 || scratch_surface >= 0) out.pending.push_back({cell, scratch_block, scratch_surface});
}

}  // namespace occupancy
}  // namespace semexp

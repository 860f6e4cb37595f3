// Background occupancy map integration, the per-cell part: the free update
// of a whole cell and the voxel update of a cell at the measured surface.
#include <algorithm>
#include <cmath>

#include "semantic_exploration/core/occupancy/integrator.hpp"

namespace semexp {
namespace occupancy {

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
    }
    if (cfg_.integrate_min_distance) {
      const Eigen::Vector3d c = store.origin + (bc.cast<double>() * bs + Eigen::Vector3d::Constant(0.5 * bs)) * res;
      store.cell_dist[cell] = std::min(store.cell_dist[cell], toMm(static_cast<float>((c - fr.cam_W).norm())));
    }
    return;
  }
  std::int16_t* L = store.logOdds(b);
  std::uint16_t* D = store.block_surf[b] >= 0 && cfg_.integrate_min_distance ? store.dist(store.block_surf[b]) : nullptr;
  bool changed = false;
  const Eigen::Vector3d c0 = store.origin + (bc.cast<double>() * bs + Eigen::Vector3d::Constant(0.5)) * res - fr.cam_W;
  int i = 0;
  for (int z = 0; z < bs; ++z)
    for (int y = 0; y < bs; ++y)
      for (int x = 0; x < bs; ++x, ++i) {
        const std::int16_t v = L[i];
        const std::int16_t nv = static_cast<std::int16_t>(v == kUnknown ? std::max(lf, lmin) : std::max(lmin, v + lf));
        if (nv != v) {
          L[i] = nv;
          changed = true;
        }
        if (D) {
          const double d = (c0 + Eigen::Vector3d(x, y, z) * res).norm();
          D[i] = std::min(D[i], toMm(static_cast<float>(d)));
        }
      }
  if (changed) markChanged(out, cell);
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
  const Eigen::Vector3d c0_W = store.origin + (bc.cast<double>() * bs + Eigen::Vector3d::Constant(0.5)) * res;
  const Eigen::Vector3f c0 = (fr.R_CW * c0_W + fr.t_CW).cast<float>();
  const Eigen::Vector3f ex = (fr.R_CW.col(0) * res).cast<float>();
  const Eigen::Vector3f ey = (fr.R_CW.col(1) * res).cast<float>();
  const Eigen::Vector3f ez = (fr.R_CW.col(2) * res).cast<float>();
  const float fx = fr.fx, fy = fr.fy, cx = fr.cx, cy = fr.cy;
  const float umax = fr.W - 0.5f, vmax = fr.H - 0.5f;
  const float band = fr.band;
  const float half_vox_px = 0.5f * static_cast<float>(res) * std::min(fx, fy);
  const int lf = l_free_, lo = l_occ_, lmin = l_min_, lmax = l_max_;
  const float* depth = pyr_.depth();
  const float* freelim = pyr_.freeLimit();
  const int W = fr.W;
  const bool track_dist = cfg_.integrate_min_distance;
  bool changed = false;
  std::size_t updated = 0;
  int i = 0;
  for (int z = 0; z < bs; ++z)
    for (int y = 0; y < bs; ++y) {
      Eigen::Vector3f p = c0 + ey * static_cast<float>(y) + ez * static_cast<float>(z);
      for (int x = 0; x < bs; ++x, ++i, p += ex) {
        const bool hit = hit_bits && ((hit_bits[i >> 6] >> (i & 63)) & 1u);
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
        } else if (hit || (p.z() <= d + band &&
                           (!fr.gap || p.z() >= d - std::max(fr.front_m, fr.front_quad_per_m * d * d)))) {
          nv = static_cast<std::int16_t>(std::min(lmax, base + lo));
          if (!Dm) attachSurface();
          if (C && fr.rgb && d > 0.f) {
            std::uint8_t* c = C + 4 * i;
            const int w = c[3];
            const std::uint8_t* in = fr.rgb + 3 * pix;
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
  if (scratch_block >= 0 || scratch_surface >= 0) out.pending.push_back({cell, scratch_block, scratch_surface});
}

}  // namespace occupancy
}  // namespace semexp

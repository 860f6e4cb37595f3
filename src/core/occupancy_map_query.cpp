// Background occupancy map: point, sphere and ray queries, gain raycasts.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "semantic_exploration/core/gains.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"
#include "semantic_exploration/core/parallel_for.hpp"

namespace semexp {

using occupancy::kNoDist;
using occupancy::kScale;
using occupancy::isFreeValue;
using occupancy::kUnknown;
using occupancy::Summary;

namespace {

inline VoxelState stateOf(std::int16_t l) {
  if (l == kUnknown) return VoxelState::kUnknown;
  return l >= 0 ? VoxelState::kOccupied : VoxelState::kFree;
}
}  // namespace

static bool locate(const Eigen::Vector3d& p_W, const Eigen::Vector3d& origin, double res, const Eigen::Vector3i& nb,
                   int bs, Eigen::Vector3i& v) {
  const Eigen::Vector3d q = (p_W - origin) / res;
  for (int i = 0; i < 3; ++i) {
    if (!(q[i] >= 0.0) || q[i] >= static_cast<double>(nb[i]) * bs) return false;
    v[i] = static_cast<int>(std::floor(q[i]));
  }
  return true;
}

VoxelState OccupancyMap::state(const Eigen::Vector3d& p_W) const {
  Eigen::Vector3i v;
  if (!locate(p_W, store_.origin, store_.res, store_.nb, store_.bs, v)) return VoxelState::kUnknown;
  return stateOf(store_.voxelValue(v.x(), v.y(), v.z()));
}

bool OccupancyMap::logOdds(const Eigen::Vector3d& p_W, double& l) const {
  Eigen::Vector3i v;
  if (!locate(p_W, store_.origin, store_.res, store_.nb, store_.bs, v)) return false;
  const std::int16_t s = store_.voxelValue(v.x(), v.y(), v.z());
  if (s == kUnknown) return false;
  l = s / kScale;
  return true;
}

bool OccupancyMap::colour(const Eigen::Vector3d& p_W, std::uint8_t rgb[3]) const {
  Eigen::Vector3i v;
  if (!cfg_.integrate_colour || !locate(p_W, store_.origin, store_.res, store_.nb, store_.bs, v)) return false;
  const int cell = store_.cellIndex(v.x() >> store_.bshift, v.y() >> store_.bshift, v.z() >> store_.bshift);
  const int b = store_.cell_block[cell];
  if (b < 0) return false;
  const int m = store_.bs - 1;
  if (store_.block_surf[b] < 0) return false;
  const std::uint8_t* c = store_.surf_rgbw.data() + 4 * (static_cast<std::size_t>(store_.block_surf[b]) * store_.bs3 +
                                                    ((v.x() & m) + store_.bs * ((v.y() & m) + store_.bs * (v.z() & m))));
  if (c[3] == 0) return false;
  std::copy(c, c + 3, rgb);
  return true;
}

double OccupancyMap::minObservedDistance(const Eigen::Vector3d& p_W) const {
  Eigen::Vector3i v;
  const double inf = std::numeric_limits<double>::infinity();
  if (!locate(p_W, store_.origin, store_.res, store_.nb, store_.bs, v)) return inf;
  const int cell = store_.cellIndex(v.x() >> store_.bshift, v.y() >> store_.bshift, v.z() >> store_.bshift);
  const int b = store_.cell_block[cell];
  const int m = store_.bs - 1;
  const std::uint16_t d =
      b < 0 ? store_.cell_dist[cell]
      : store_.block_surf[b] < 0
          ? kNoDist
          : store_.surf_dist[static_cast<std::size_t>(store_.block_surf[b]) * store_.bs3 + ((v.x() & m) + store_.bs * ((v.y() & m) + store_.bs * (v.z() & m)))];
  return d == kNoDist ? inf : d / 1000.0;
}

// ---------------------------------------------------------------- sphere

bool OccupancyMap::isSphereFree(const Eigen::Vector3d& centre_W, double radius_m) const {
  const Eigen::Vector3d c = (centre_W - store_.origin) / store_.res;
  const double rad = radius_m / store_.res;
  if (!c.allFinite() || !(rad >= 0.0)) return false;
  for (int i = 0; i < 3; ++i)
    if (c[i] - rad < 0.0 || c[i] + rad > static_cast<double>(store_.nb[i]) * store_.bs) return false;  // reaches outside the map
  if (rad == 0.0) return state(centre_W) == VoxelState::kFree;
  return sphereFreeRec(static_cast<int>(store_.levels.size()) - 1, 0, 0, 0, c, rad);
}

bool OccupancyMap::sphereFreeRec(int k, int ix, int iy, int iz, const Eigen::Vector3d& c, double rad) const {
  const int S = store_.bs << k;
  const Eigen::Vector3i lo(ix * S, iy * S, iz * S);
  const Eigen::Vector3i hi = (lo.array() + S).min(store_.nb.array() * store_.bs);
  double d2 = 0.0, far2 = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double a = lo[i] - c[i], b = c[i] - hi[i];
    const double e = std::max({a, 0.0, b});
    d2 += e * e;
    const double f = std::max(std::abs(a), std::abs(b));
    far2 += f * f;
  }
  const double r2 = rad * rad;
  if (d2 >= r2) return true;  // does not intersect
  const occupancy::SummaryLevel& L = store_.levels[k];
  const Summary& s = L.s[ix + L.dims.x() * (iy + L.dims.y() * iz)];
  if (s.known_any && !s.unknown_any && s.max_l < 0) return true;  // all free below
  if (far2 <= r2) return false;                                    // wholly inside and not all free
  if (k == 0) {
    const int cell = store_.cellIndex(ix, iy, iz);
    const int b = store_.cell_block[cell];
    if (b < 0) return false;  // uniform, not free
    const std::int16_t* Lv = store_.logOdds(b);
    int vlo[3], vhi[3];
    for (int i = 0; i < 3; ++i) {
      vlo[i] = std::max(lo[i], static_cast<int>(std::floor(c[i] - rad)));
      vhi[i] = std::min(hi[i] - 1, static_cast<int>(std::floor(c[i] + rad)));
    }
    for (int z = vlo[2]; z <= vhi[2]; ++z) {
      const double ez = std::max({z - c.z(), 0.0, c.z() - (z + 1)});
      for (int y = vlo[1]; y <= vhi[1]; ++y) {
        const double ey = std::max({y - c.y(), 0.0, c.y() - (y + 1)});
        for (int x = vlo[0]; x <= vhi[0]; ++x) {
          const double ex = std::max({x - c.x(), 0.0, c.x() - (x + 1)});
          if (ex * ex + ey * ey + ez * ez >= r2) continue;
          if (!isFreeValue(Lv[(x - lo[0]) + store_.bs * ((y - lo[1]) + store_.bs * (z - lo[2]))])) return false;
        }
      }
    }
    return true;
  }
  const Eigen::Vector3i& cd = store_.levels[k - 1].dims;
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const int cx = 2 * ix + dx, cy = 2 * iy + dy, cz = 2 * iz + dz;
        if (cx < cd.x() && cy < cd.y() && cz < cd.z() && !sphereFreeRec(k - 1, cx, cy, cz, c, rad)) return false;
      }
  return true;
}

// ------------------------------------------------------------------- rays

// Calls f(t_in_m, t_out_m, log-odds, cell, voxel-in-block or -1) for each leaf
// (voxel, or the largest uniform octree node) the ray crosses between t0 and
// t1, in order, until f returns false or the ray leaves the map.
template <class F>
void OccupancyMap::march(const Eigen::Vector3d& o_W, const Eigen::Vector3d& dir_W, double t0, double t1, F&& f) const {
  const Eigen::Vector3d d = dir_W.normalized();
  const Eigen::Vector3d o = (o_W - store_.origin) / store_.res;
  const double inf = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d inv(d.x() != 0 ? 1.0 / d.x() : inf, d.y() != 0 ? 1.0 / d.y() : inf,
                            d.z() != 0 ? 1.0 / d.z() : inf);
  const Eigen::Vector3i nv = store_.nb * store_.bs;
  const int m = store_.bs - 1;
  double t = t0 / store_.res;
  double tend = t1 / store_.res;
  for (int i = 0; i < 3; ++i) {  // coarse nodes may reach past the map: stop where the ray leaves it
    if (d[i] > 0) tend = std::min(tend, (nv[i] - o[i]) * inv[i]);
    if (d[i] < 0) tend = std::min(tend, (0.0 - o[i]) * inv[i]);
  }
  while (t < tend) {
    const Eigen::Vector3d p = o + d * (t + 1e-7);
    int v[3];
    for (int i = 0; i < 3; ++i) {
      if (!(p[i] >= 0.0) || p[i] >= nv[i]) return;
      v[i] = static_cast<int>(p[i]);
    }
    const int cx = v[0] >> store_.bshift, cy = v[1] >> store_.bshift, cz = v[2] >> store_.bshift;
    const int cell = store_.cellIndex(cx, cy, cz);
    const int b = store_.cell_block[cell];
    std::int16_t l;
    int vox = -1;
    int size = 1;
    int lo[3];
    if (b >= 0) {
      // Inside a dense block: integer 3D DDA voxel by voxel until the ray leaves it.
      const std::int16_t* Lb = store_.logOdds(b);
      int idx[3], step[3];
      double tmax[3], tdelta[3];
      for (int i = 0; i < 3; ++i) {
        idx[i] = v[i] & m;
        step[i] = d[i] > 0 ? 1 : (d[i] < 0 ? -1 : 0);
        tmax[i] = d[i] > 0 ? (v[i] + 1 - o[i]) * inv[i] : (d[i] < 0 ? (v[i] - o[i]) * inv[i] : inf);
        tdelta[i] = step[i] != 0 ? std::abs(inv[i]) : inf;
      }
      while (true) {
        const int vx = idx[0] + store_.bs * (idx[1] + store_.bs * idx[2]);
        const int a = tmax[0] < tmax[1] ? (tmax[0] < tmax[2] ? 0 : 2) : (tmax[1] < tmax[2] ? 1 : 2);
        double tx = tmax[a];
        if (!(tx > t)) tx = t + 1e-6;
        if (!f(t * store_.res, std::min(tx, tend) * store_.res, Lb[vx], cell, vx)) return;
        t = tx;
        if (t >= tend) return;
        idx[a] += step[a];
        tmax[a] += tdelta[a];
        if (idx[a] < 0 || idx[a] > m) break;  // left the block: the outer loop finds the next leaf
      }
      continue;
    } else {
      l = store_.cell_value[cell];
      int k = 0;
      for (int kk = 1; kk < static_cast<int>(store_.levels.size()); ++kk) {
        const occupancy::SummaryLevel& L = store_.levels[kk];
        const Summary& s = L.s[(cx >> kk) + L.dims.x() * ((cy >> kk) + L.dims.y() * (cz >> kk))];
        const bool same = l == kUnknown ? !s.known_any : (!s.unknown_any && s.min_l == l && s.max_l == l);
        if (!same) break;
        k = kk;
      }
      size = store_.bs << k;
      const int sh = store_.bshift + k;
      for (int i = 0; i < 3; ++i) lo[i] = (v[i] >> sh) << sh;
    }
    double texit = inf;
    for (int i = 0; i < 3; ++i) {
      if (d[i] > 0)
        texit = std::min(texit, (lo[i] + size - o[i]) * inv[i]);
      else if (d[i] < 0)
        texit = std::min(texit, (lo[i] - o[i]) * inv[i]);
    }
    if (!(texit > t)) texit = t + 1e-6;
    if (!f(t * store_.res, std::min(texit, tend) * store_.res, l, cell, vox)) return;
    t = texit;
  }
}

RaycastHit OccupancyMap::raycast(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& dir_W, double max_range_m,
                                 bool stop_at_unknown) const {
  RaycastHit hit;
  hit.distance_m = max_range_m;
  if (!(dir_W.squaredNorm() > 0.0)) return hit;
  const Eigen::Vector3d d = dir_W.normalized();
  march(origin_W, d, 0.0, max_range_m, [&](double t_in, double, std::int16_t l, int cell, int vox) {
    const bool occ = l != kUnknown && l >= 0;
    if (!occ && !(stop_at_unknown && l == kUnknown)) return true;
    hit.hit = true;
    hit.state = stateOf(l);
    hit.distance_m = t_in;
    if (vox >= 0) {
      hit.voxel_centre_W = store_.voxelCentre(store_.mapVoxel(cell, vox));
    } else {
      // centre of the finest voxel at the entry point
      const Eigen::Vector3d p = ((origin_W + d * (t_in + 1e-7 * store_.res)) - store_.origin) / store_.res;
      hit.voxel_centre_W = store_.origin + (p.array().floor() + 0.5).matrix() * store_.res;
    }
    return false;
  });
  return hit;
}

std::vector<GainImages> OccupancyMap::computeGains(const std::vector<Eigen::Vector3d>& positions_W,
                                                   const SphericalGrid& grid, const GainSettings& st,
                                                   const std::vector<float>& max_depth_m) const {
  if (const std::string why = SphericalGrid::checkRequest(static_cast<long>(positions_W.size()), grid.width,
                                                         grid.height); !why.empty())
    throw std::invalid_argument("OccupancyMap::computeGains: " + why);
  if (st.threads < 1) throw std::invalid_argument("OccupancyMap::computeGains: threads must be >= 1");
  const std::vector<float>& H = entropy_lut_;
  const int W = grid.width, Hh = grid.height, n = W * Hh;  // <= SphericalGrid::kMaxPixels: no overflow
  const bool have_max = max_depth_m.size() == positions_W.size() * static_cast<std::size_t>(n) && n > 0;
  const double norm = st.d_max_m - st.d_min_m;
  std::vector<Eigen::Vector3d> dirs(static_cast<std::size_t>(n));
  for (int v = 0; v < Hh; ++v)
    for (int u = 0; u < W; ++u) dirs[v * W + u] = grid.direction(u, v);
  // The images are allocated here, on the caller's thread; the positions are
  // independent and each job writes only its own images.
  std::vector<GainImages> out(positions_W.size());
  for (GainImages& g : out) {
    g.width = W;
    g.height = Hh;
    g.entropy.assign(n, 0.f);
    g.distance.assign(n, 0.f);
    g.hit_depth_m.assign(n, static_cast<float>(st.d_max_m));
  }
  parallelFor(positions_W.size(), st.threads, [&](std::size_t j) {
    GainImages& g = out[j];
    const Eigen::Vector3d& pos = positions_W[j];
    for (int i = 0; i < n; ++i) {
      double t_end = st.d_max_m;
      if (have_max) {
        const float md = max_depth_m[j * n + i];
        if (std::isfinite(md) && md >= 0.f) t_end = std::min(t_end, static_cast<double>(md));
      }
      double ent = 0.0;
      march(pos, dirs[i], 0.0, t_end, [&](double a, double b, std::int16_t l, int cell, int vox) {
        if (l != kUnknown && l >= 0) {
          g.hit_depth_m[i] = static_cast<float>(a);
          // leaf centre and its minimum observed distance
          Eigen::Vector3d centre;
          std::uint16_t dmm;
          if (vox >= 0) {
            centre = store_.voxelCentre(store_.mapVoxel(cell, vox));
            const int sl = store_.block_surf[store_.cell_block[cell]];
            dmm = sl < 0 ? kNoDist : store_.surf_dist[static_cast<std::size_t>(sl) * store_.bs3 + vox];
          } else {
            centre = store_.cellCentre(cell);
            dmm = store_.cell_dist[cell];
          }
          const double d_node = dmm == kNoDist ? std::numeric_limits<double>::infinity() : dmm / 1000.0;
          const double d_exp = (centre - pos).norm();
          const double gain = std::isfinite(d_node) ? distanceGain(d_node, d_exp, st.d_desired_m, st.d_max_m) : 0.0;
          g.distance[i] = static_cast<float>(gain);
          return false;
        }
        const double s = std::max(a, st.d_min_m), e = b;
        if (e > s) {
          const double h = l == kUnknown ? 1.0 : H[static_cast<std::size_t>(std::clamp(l, l_min_, l_max_) - l_min_)];
          ent += h * (e - s);
        }
        return true;
      });
      g.entropy[i] = static_cast<float>(std::clamp(ent / norm, 0.0, 1.0));
    }
  });
  return out;
}

// ------------------------------------------------------------- iteration

void OccupancyMap::forEachOccupied(
    const std::function<void(const Eigen::Vector3d&, double, const std::uint8_t*)>& f) const {
  const std::uint8_t grey[3] = {128, 128, 128};
  for (int cell = 0; cell < static_cast<int>(store_.cell_block.size()); ++cell) {
    const Summary& s = store_.levels[0].s[cell];
    if (!s.known_any || s.max_l < 0) continue;
    const int b = store_.cell_block[cell];
    if (b < 0) {
      f(store_.cellCentre(cell), store_.bs * store_.res, grey);
      continue;
    }
    const std::int16_t* L = store_.logOdds(b);
    const Eigen::Vector3i base = store_.cellCoords(cell) * store_.bs;
    for (int i = 0; i < store_.bs3; ++i) {
      if (L[i] == kUnknown || L[i] < 0) continue;
      const std::uint8_t* c = grey;
      if (cfg_.integrate_colour && store_.block_surf[b] >= 0) {
        const std::uint8_t* cc = store_.surf_rgbw.data() + 4 * (static_cast<std::size_t>(store_.block_surf[b]) * store_.bs3 + i);
        if (cc[3] > 0) c = cc;
      }
      f(store_.voxelCentre(base + store_.voxelInCell(i)), store_.res, c);
    }
  }
}

}  // namespace semexp

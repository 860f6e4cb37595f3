// Background occupancy map: the share of the surface observed from <= d (the
// background half of the paper's termination condition, Section IV-D).
#include <algorithm>
#include <cmath>

#include "semantic_exploration/core/occupancy_map.hpp"

namespace semexp {

using occupancy::kNoDist;
using occupancy::kUnknown;
using occupancy::Summary;

namespace {
// The longest walk across a free-margin gap, voxels: 32 x 4 cm covers sqrt(3) q d^2 for q = 0.006 up to 11 m.
constexpr int kMaxGapSteps = 32;
}  // namespace

OccupancyMap::SurfaceObservation OccupancyMap::surfaceObservedWithin(double d_m) const {
  SurfaceObservation out;
  // Distances are stored in whole mm, rounded (see the integrator): compare in mm.
  const double d_mm = std::floor(d_m * 1000.0 + 0.5);
  const auto within = [d_mm](std::uint16_t d) { return d != kNoDist && d <= d_mm; };
  const auto isFree = [](std::int16_t v) { return v != kUnknown && v < 0; };
  const int m = store_.bs - 1;
  // With a free margin (free_margin_quadratic_per_m), carving stops q d^2 in front of a depth d and the voxels
  // in between stay unknown, so a surface seen only from far has no free neighbour. It still bounds observed
  // free space across that gap: look along each axis through unknown voxels only, as far as the gap reaches
  // along the axis nearest to the ray (at most sqrt(3) q d^2), d being the voxel's own observed distance.
  const double gap_q = cfg_.free_margin_quadratic_per_m > cfg_.surface_front_quadratic_per_m ? cfg_.free_margin_quadratic_per_m : 0.0;
  const auto gapSteps = [&](std::uint16_t d) {
    if (gap_q <= 0.0 || d == kNoDist) return 0;
    const double dd = d * 1e-3;
    return std::min(kMaxGapSteps, static_cast<int>(std::ceil(std::sqrt(3.0) * gap_q * dd * dd / store_.res)));
  };
  // Whether voxel (x, y, z) of the grid bounds observed free space: a free 6-neighbour, or free space along an
  // axis beyond at most `gap_steps` unknown voxels. Surface, not the inside of a wall that noisy far returns
  // marked occupied.
  const auto exposed = [&](int x, int y, int z, int gap_steps) {
    static const int kDir[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& dir : kDir)
      for (int s = 1; s <= gap_steps + 1; ++s) {
        const std::int16_t v = store_.voxelValue(x + s * dir[0], y + s * dir[1], z + s * dir[2]);
        if (isFree(v)) return true;
        if (v != kUnknown) break;  // occupied: the walk left the gap
      }
    return false;
  };
  for (int cell = 0; cell < static_cast<int>(store_.cell_block.size()); ++cell) {
    const Summary& s = store_.levels[0].s[cell];
    if (!s.known_any || s.max_l < 0) continue;  // nothing occupied below
    const int bz = cell / (store_.nb.x() * store_.nb.y()), by = (cell / store_.nb.x()) % store_.nb.y(), bx = cell % store_.nb.x();
    const int gx0 = bx * store_.bs, gy0 = by * store_.bs, gz0 = bz * store_.bs;
    const int b = store_.cell_block[cell];
    if (b < 0) {  // a uniform occupied cell: only voxels on its faces can touch free space
      const bool near = within(store_.cell_dist[cell]);
      const int steps = gapSteps(store_.cell_dist[cell]);
      for (int z = 0; z < store_.bs; ++z)
        for (int y = 0; y < store_.bs; ++y)
          for (int x = 0; x < store_.bs; ++x) {
            if (x != 0 && x != m && y != 0 && y != m && z != 0 && z != m) continue;
            if (!exposed(gx0 + x, gy0 + y, gz0 + z, steps)) continue;
            ++out.occupied_voxels;
            out.within_voxels += near;
          }
      continue;
    }
    const std::int16_t* L = store_.logOdds(b);
    const std::uint16_t* D =
        store_.block_surf[b] >= 0 ? store_.dist(store_.block_surf[b]) : nullptr;
    const int stride[3] = {1, store_.bs, store_.bs * store_.bs};
    // exposed() for voxel i of this block, the same answer in fewer reads: the steps that stay inside the block
    // read it directly, only those past its faces go through the grid, and the gap (a square root) is only
    // worked out when a direct neighbour is unknown (most are free or occupied: the walk ends at step 1).
    const auto value = [&](int i, const int xyz[3], int a, int sign, int s) {
      const int inside = sign > 0 ? m - xyz[a] : xyz[a];  // steps before the walk leaves the block
      if (s <= inside) return L[i + sign * s * stride[a]];
      int g[3] = {gx0 + xyz[0], gy0 + xyz[1], gz0 + xyz[2]};
      g[a] += sign * s;
      return store_.voxelValue(g[0], g[1], g[2]);
    };
    const auto exposedInBlock = [&](int i, const int xyz[3]) {
      bool unknown_next = false;
      for (int a = 0; a < 3; ++a)
        for (int sign = -1; sign <= 1; sign += 2) {
          const std::int16_t v = value(i, xyz, a, sign, 1);
          if (isFree(v)) return true;
          unknown_next |= v == kUnknown;
        }
      const int gap_steps = unknown_next && D ? gapSteps(D[i]) : 0;
      for (int a = 0; a < 3 && gap_steps > 0; ++a)
        for (int sign = -1; sign <= 1; sign += 2) {
          if (value(i, xyz, a, sign, 1) != kUnknown) continue;
          for (int s = 2; s <= gap_steps + 1; ++s) {
            const std::int16_t v = value(i, xyz, a, sign, s);
            if (isFree(v)) return true;
            if (v != kUnknown) break;  // occupied: the walk left the gap
          }
        }
      return false;
    };
    for (int i = 0; i < store_.bs3; ++i) {
      if (L[i] == kUnknown || L[i] < 0) continue;
      const int xyz[3] = {i & m, (i >> store_.bshift) & m, i >> (2 * store_.bshift)};
      if (!exposedInBlock(i, xyz)) continue;
      ++out.occupied_voxels;
      if (D && within(D[i])) ++out.within_voxels;
    }
  }
  return out;
}

}  // namespace semexp

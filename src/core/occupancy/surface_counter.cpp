// The observed surface counted per cell (see surface_counter.hpp).
#include "semantic_exploration/core/occupancy/surface_counter.hpp"

#include <algorithm>
#include <cmath>

namespace semexp {
namespace occupancy {

int SurfaceRule::reachCells(const BlockStore& store) const {
  const int walk = (gap_q_per_m > 0.0 ? kMaxGapSteps : 0) + 1;  // voxels past the counted one
  return (walk + store.bs - 1) / store.bs;
}

SurfaceCount countSurface(const BlockStore& store, int cell, const SurfaceRule& rule) {
  SurfaceCount out;
  const Summary& s = store.levels[0].s[cell];
  if (!s.known_any || s.max_l < 0) return out;  // nothing occupied in it
  const double d_mm = rule.d_mm;
  const auto within = [d_mm](std::uint16_t d) { return d != kNoDist && d <= d_mm; };
  const int m = store.bs - 1;
  // With a free margin, carving stops q d^2 in front of a depth d and the voxels in between stay unknown, so a
  // surface seen only from far has no free neighbour. It still bounds observed free space across that gap:
  // look along each axis through unknown voxels only, as far as the gap reaches along the axis nearest to the
  // ray (at most sqrt(3) q d^2), d being the voxel's own observed distance.
  const double gap_q = rule.gap_q_per_m;
  const auto gapSteps = [&](std::uint16_t d) {
    if (gap_q <= 0.0 || d == kNoDist) return 0;
    const double dd = d * 1e-3;
    return std::min(kMaxGapSteps, static_cast<int>(std::ceil(std::sqrt(3.0) * gap_q * dd * dd / store.res)));
  };
  const Eigen::Vector3i bc = store.cellCoords(cell);
  const int gx0 = bc.x() * store.bs, gy0 = bc.y() * store.bs, gz0 = bc.z() * store.bs;
  const int b = store.cell_block[cell];
  if (b < 0) {
    // A uniform occupied cell: only voxels on its faces can touch free space. A face voxel bounds observed
    // free space if a free voxel lies along an axis beyond at most `steps` unknown ones: surface, not the
    // inside of a wall that noisy far returns marked occupied.
    static const int kDir[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    const bool near = within(store.cell_dist[cell]);
    const int steps = gapSteps(store.cell_dist[cell]);
    const auto exposed = [&](int x, int y, int z) {
      for (const auto& dir : kDir)
        for (int st = 1; st <= steps + 1; ++st) {
          const std::int16_t v = store.voxelValue(x + st * dir[0], y + st * dir[1], z + st * dir[2]);
          if (isFreeValue(v)) return true;
          if (v != kUnknown) break;  // occupied: the walk left the gap
        }
      return false;
    };
    for (int z = 0; z < store.bs; ++z)
      for (int y = 0; y < store.bs; ++y)
        for (int x = 0; x < store.bs; ++x) {
          if (x != 0 && x != m && y != 0 && y != m && z != 0 && z != m) continue;
          if (!exposed(gx0 + x, gy0 + y, gz0 + z)) continue;
          ++out.occupied;
          out.within += near;
        }
    return out;
  }
  const std::int16_t* L = store.logOdds(b);
  const std::uint16_t* D = store.block_surf[b] >= 0 ? store.dist(store.block_surf[b]) : nullptr;
  const int stride[3] = {1, store.bs, store.bs * store.bs};
  // The same test for voxel i of a block in fewer reads: the steps that stay inside the block read it directly,
  // only those past its faces go through the grid, and the gap (a square root) is only worked out when a direct
  // neighbour is unknown (most are free or occupied: the walk ends at step 1).
  const auto value = [&](int i, const int xyz[3], int a, int sign, int st) {
    const int inside = sign > 0 ? m - xyz[a] : xyz[a];  // steps before the walk leaves the block
    if (st <= inside) return L[i + sign * st * stride[a]];
    int g[3] = {gx0 + xyz[0], gy0 + xyz[1], gz0 + xyz[2]};
    g[a] += sign * st;
    return store.voxelValue(g[0], g[1], g[2]);
  };
  const auto exposedInBlock = [&](int i, const int xyz[3]) {
    bool unknown_next = false;
    for (int a = 0; a < 3; ++a)
      for (int sign = -1; sign <= 1; sign += 2) {
        const std::int16_t v = value(i, xyz, a, sign, 1);
        if (isFreeValue(v)) return true;
        unknown_next |= v == kUnknown;
      }
    const int gap_steps = unknown_next && D ? gapSteps(D[i]) : 0;
    for (int a = 0; a < 3 && gap_steps > 0; ++a)
      for (int sign = -1; sign <= 1; sign += 2) {
        if (value(i, xyz, a, sign, 1) != kUnknown) continue;
        for (int st = 2; st <= gap_steps + 1; ++st) {
          const std::int16_t v = value(i, xyz, a, sign, st);
          if (isFreeValue(v)) return true;
          if (v != kUnknown) break;  // occupied: the walk left the gap
        }
      }
    return false;
  };
  for (int i = 0; i < store.bs3; ++i) {
    if (L[i] == kUnknown || L[i] < 0) continue;
    const int xyz[3] = {i & m, (i >> store.bshift) & m, i >> (2 * store.bshift)};
    if (!exposedInBlock(i, xyz)) continue;
    ++out.occupied;
    if (D && within(D[i])) ++out.within;
  }
  return out;
}

SurfaceTotals countSurfaceAll(const BlockStore& store, const SurfaceRule& rule) {
  SurfaceTotals t;
  for (int cell = 0; cell < static_cast<int>(store.cellCount()); ++cell) {
    const SurfaceCount c = countSurface(store, cell, rule);
    t.occupied += c.occupied;
    t.within += c.within;
  }
  return t;
}

void SurfaceCounter::reset() {
  all_stale_ = true;
  for (const int c : stale_cells_) stale_[c] = 0;
  stale_cells_.clear();
}

void SurfaceCounter::mark(int cell) {
  if (all_stale_ || stale_[cell]) return;
  stale_[cell] = 1;
  stale_cells_.push_back(cell);
}

void SurfaceCounter::occupancyChanged(const BlockStore& store, int cell, const SurfaceRule& rule) {
  if (all_stale_) return;
  const Eigen::Vector3i c = store.cellCoords(cell);
  const int r = rule.reachCells(store);
  mark(cell);
  for (int a = 0; a < 3; ++a)
    for (int k = -r; k <= r; ++k) {
      if (k == 0) continue;
      Eigen::Vector3i n = c;
      n[a] += k;
      if (n[a] < 0 || n[a] >= store.nb[a]) continue;
      mark(store.cellIndex(n.x(), n.y(), n.z()));
    }
}

void SurfaceCounter::distanceChanged(int cell) { mark(cell); }

SurfaceTotals SurfaceCounter::update(const BlockStore& store, const SurfaceRule& rule) {
  const int n = static_cast<int>(store.cellCount());
  if (static_cast<int>(per_cell_.size()) != n || rule.d_mm != last_rule_.d_mm ||
      rule.gap_q_per_m != last_rule_.gap_q_per_m)
    reset();
  last_rule_ = rule;
  if (all_stale_) {
    per_cell_.assign(static_cast<std::size_t>(n), SurfaceCount{});
    stale_.assign(static_cast<std::size_t>(n), 0);
    sum_ = SurfaceTotals{};
    for (int c = 0; c < n; ++c) {
      per_cell_[c] = countSurface(store, c, rule);
      sum_.occupied += per_cell_[c].occupied;
      sum_.within += per_cell_[c].within;
    }
    all_stale_ = false;
    last_counted_ = static_cast<std::size_t>(n);
  } else {
    for (const int c : stale_cells_) {
      sum_.occupied -= per_cell_[c].occupied;
      sum_.within -= per_cell_[c].within;
      per_cell_[c] = countSurface(store, c, rule);
      sum_.occupied += per_cell_[c].occupied;
      sum_.within += per_cell_[c].within;
      stale_[c] = 0;
    }
    last_counted_ = stale_cells_.size();
    stale_cells_.clear();
  }
  return sum_;
}

std::size_t SurfaceCounter::memoryBytes() const {
  return per_cell_.capacity() * sizeof(SurfaceCount) + stale_.capacity() + stale_cells_.capacity() * sizeof(int);
}

}  // namespace occupancy
}  // namespace semexp

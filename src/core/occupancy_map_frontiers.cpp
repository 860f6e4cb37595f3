// Background occupancy map: incrementally maintained frontiers (free leaves
// with an unknown 6-neighbour, paper IV-A.1).
//
// Why re-checking the changed cells plus the previous frontiers next to them
// is exact: voxels never become unknown again, so a voxel whose own cell did
// not change can only lose frontier status (its unknown neighbour, in an
// adjacent changed cell, got observed), never gain it.
#include <algorithm>

#include "semantic_exploration/core/occupancy_map.hpp"

namespace semexp {

namespace {

// Keeps the cells of `list` whose flags still hold `keep` and clears the
// `listed` flag of the ones dropped (stale entries of a lazily pruned list).
void compactCellList(std::vector<int>& list, std::vector<std::uint8_t>& flags, std::uint8_t keep,
                     std::uint8_t listed) {
  std::size_t k = 0;
  for (int c : list) {
    if (flags[c] & keep)
      list[k++] = c;
    else
      flags[c] &= static_cast<std::uint8_t>(~listed);
  }
  list.resize(k);
}

inline int popcount64(std::uint64_t x) { return __builtin_popcountll(x); }
}  // namespace

bool OccupancyMap::cellIsFrontier(int cell) const {
  if (cell_block_[cell] >= 0) return false;
  const std::int16_t v = cell_value_[cell];
  if (v == kUnknown || v >= 0) return false;
  const int bz = cell / (nb_.x() * nb_.y()), by = (cell / nb_.x()) % nb_.y(), bx = cell % nb_.x();
  const int m = bs_ - 1;
  for (int axis = 0; axis < 3; ++axis)
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      Eigen::Vector3i n(bx, by, bz);
      n[axis] += sgn;
      if (n[axis] < 0 || n[axis] >= nb_[axis]) continue;
      const int nc = cellIndex(n.x(), n.y(), n.z());
      const int nbk = cell_block_[nc];
      if (nbk < 0) {
        if (cell_value_[nc] == kUnknown) return true;
        continue;
      }
      if (!levels_[0].s[nc].unknown_any) continue;
      const std::int16_t* L = block_l_.data() + static_cast<std::size_t>(nbk) * bs3_;
      const int layer = sgn > 0 ? 0 : m;  // the neighbour's face touching this cell
      for (int a = 0; a < bs_; ++a)
        for (int b = 0; b < bs_; ++b) {
          int q[3];
          q[axis] = layer;
          q[(axis + 1) % 3] = a;
          q[(axis + 2) % 3] = b;
          if (L[q[0] + bs_ * (q[1] + bs_ * q[2])] == kUnknown) return true;
        }
    }
  return false;
}

void OccupancyMap::recheckBlockFrontiers(int cell, bool full) {
  const int b = cell_block_[cell];
  std::uint64_t* F = block_front_.data() + static_cast<std::size_t>(b) * fwords_;
  const std::int16_t* L = block_l_.data() + static_cast<std::size_t>(b) * bs3_;
  const int bz = cell / (nb_.x() * nb_.y()), by = (cell / nb_.x()) % nb_.y(), bx = cell % nb_.x();
  const int gx0 = bx * bs_, gy0 = by * bs_, gz0 = bz * bs_;
  const int m = bs_ - 1, s1 = bs_, s2 = bs_ * bs_;
  auto isFrontier = [&](int i) {
    const std::int16_t l = L[i];
    if (l == kUnknown || l >= 0) return false;
    const int x = i & m, y = (i >> bshift_) & m, z = i >> (2 * bshift_);
    if (x < m ? L[i + 1] == kUnknown : voxelValueOrKnown(gx0 + x + 1, gy0 + y, gz0 + z) == kUnknown) return true;
    if (x > 0 ? L[i - 1] == kUnknown : voxelValueOrKnown(gx0 + x - 1, gy0 + y, gz0 + z) == kUnknown) return true;
    if (y < m ? L[i + s1] == kUnknown : voxelValueOrKnown(gx0 + x, gy0 + y + 1, gz0 + z) == kUnknown) return true;
    if (y > 0 ? L[i - s1] == kUnknown : voxelValueOrKnown(gx0 + x, gy0 + y - 1, gz0 + z) == kUnknown) return true;
    if (z < m ? L[i + s2] == kUnknown : voxelValueOrKnown(gx0 + x, gy0 + y, gz0 + z + 1) == kUnknown) return true;
    if (z > 0 ? L[i - s2] == kUnknown : voxelValueOrKnown(gx0 + x, gy0 + y, gz0 + z - 1) == kUnknown) return true;
    return false;
  };
  if (!full) {
    for (int w = 0; w < fwords_; ++w) {
      std::uint64_t bits = F[w];
      while (bits) {
        const int j = __builtin_ctzll(bits);
        bits &= bits - 1;
        if (!isFrontier(w * 64 + j)) F[w] &= ~(std::uint64_t{1} << j);
      }
    }
    return;
  }
  std::fill_n(F, fwords_, 0);
  const Summary& s = levels_[0].s[cell];
  if (!s.known_any || s.min_l >= 0) return;  // no free voxel
  if (s.unknown_any) {
    for (int i = 0; i < bs3_; ++i)
      if (isFrontier(i)) F[i >> 6] |= std::uint64_t{1} << (i & 63);
    return;
  }
  // No unknown voxel inside: only faces next to a cell with unknown space can hold frontiers.
  for (int axis = 0; axis < 3; ++axis)
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      Eigen::Vector3i n(bx, by, bz);
      n[axis] += sgn;
      if (n[axis] < 0 || n[axis] >= nb_[axis]) continue;
      if (!levels_[0].s[cellIndex(n.x(), n.y(), n.z())].unknown_any) continue;
      const int layer = sgn > 0 ? m : 0;
      for (int a = 0; a < bs_; ++a)
        for (int c = 0; c < bs_; ++c) {
          int q[3];
          q[axis] = layer;
          q[(axis + 1) % 3] = a;
          q[(axis + 2) % 3] = c;
          const int i = q[0] + bs_ * (q[1] + bs_ * q[2]);
          if (isFrontier(i)) F[i >> 6] |= std::uint64_t{1} << (i & 63);
        }
    }
}

std::int16_t OccupancyMap::voxelValueOrKnown(int x, int y, int z) const {
  // Outside the map nothing can be explored: report it as known (not a frontier cause).
  if (x < 0 || y < 0 || z < 0 || x >= nb_.x() * bs_ || y >= nb_.y() * bs_ || z >= nb_.z() * bs_) return 0;
  return voxelValue(x, y, z);
}

int OccupancyMap::blockFrontierBits(int cell) const {
  const std::uint64_t* F = block_front_.data() + static_cast<std::size_t>(cell_block_[cell]) * fwords_;
  int n = 0;
  for (int w = 0; w < fwords_; ++w) n += popcount64(F[w]);
  return n;
}

void OccupancyMap::checkFrontierCell(int cell, bool full) {
  std::uint8_t& fl = cell_flags_[cell];
  if (cell_block_[cell] >= 0) {
    if (fl & kCoarseFrontier) {  // refined into a block since
      fl &= static_cast<std::uint8_t>(~kCoarseFrontier);
      --frontier_cell_count_;
    }
    const bool had = fl & kBlockFrontier;
    const int before = had ? blockFrontierBits(cell) : 0;
    if (!had && !full) return;
    recheckBlockFrontiers(cell, full);
    const int after = blockFrontierBits(cell);
    frontier_voxels_ = frontier_voxels_ - before + after;
    if (after > 0 && !had) {
      fl |= kBlockFrontier;
      ++frontier_block_count_;
      if (!(fl & kListedBlock)) {
        fl |= kListedBlock;
        frontier_blocks_.push_back(cell);
      }
    } else if (after == 0 && had) {
      fl &= static_cast<std::uint8_t>(~kBlockFrontier);
      --frontier_block_count_;
    }
    return;
  }
  const bool was = fl & kCoarseFrontier;
  const bool is = cellIsFrontier(cell);
  if (is && !was) {
    fl |= kCoarseFrontier;
    ++frontier_cell_count_;
    if (!(fl & kListedCell)) {
      fl |= kListedCell;
      frontier_cells_.push_back(cell);
    }
  } else if (!is && was) {
    fl &= static_cast<std::uint8_t>(~kCoarseFrontier);
    --frontier_cell_count_;
  }
}

void OccupancyMap::updateFrontiers() {
  // A voxel's frontier status depends on itself and its 6 neighbours only, so
  // besides the changed cells just the frontier-holding cells face-adjacent to
  // them can change (and only by losing frontiers): cost follows the update,
  // not the size of the frontier set.
  for (int c : frontier_cand_) cell_flags_[c] |= kVisited;
  for (int c : frontier_cand_) checkFrontierCell(c, true);
  std::vector<int> extra;
  for (int c : frontier_cand_) {
    const int bz = c / (nb_.x() * nb_.y()), by = (c / nb_.x()) % nb_.y(), bx = c % nb_.x();
    for (int axis = 0; axis < 3; ++axis)
      for (int sgn = -1; sgn <= 1; sgn += 2) {
        Eigen::Vector3i n(bx, by, bz);
        n[axis] += sgn;
        if (n[axis] < 0 || n[axis] >= nb_[axis]) continue;
        const int nc = cellIndex(n.x(), n.y(), n.z());
        std::uint8_t& fl = cell_flags_[nc];
        if ((fl & kVisited) || !(fl & (kBlockFrontier | kCoarseFrontier))) continue;
        fl |= kVisited;
        extra.push_back(nc);
        checkFrontierCell(nc, false);
      }
  }
  const std::uint8_t clear = static_cast<std::uint8_t>(~(kVisited | kFrontierCand));
  for (int c : frontier_cand_) cell_flags_[c] &= clear;
  for (int c : extra) cell_flags_[c] &= clear;
  frontier_cand_.clear();
  // Drop stale list entries once they dominate.
  if (frontier_blocks_.size() > 2 * frontier_block_count_ + 256)
    compactCellList(frontier_blocks_, cell_flags_, kBlockFrontier, kListedBlock);
  if (frontier_cells_.size() > 2 * frontier_cell_count_ + 256)
    compactCellList(frontier_cells_, cell_flags_, kCoarseFrontier, kListedCell);
}

std::size_t OccupancyMap::frontierCount() const { return frontier_voxels_ + frontier_cell_count_; }

void OccupancyMap::forEachFrontier(const std::function<void(const Eigen::Vector3d&, double)>& f) const {
  for (int cell : frontier_blocks_) {
    if (!(cell_flags_[cell] & kBlockFrontier)) continue;
    const int bz = cell / (nb_.x() * nb_.y()), by = (cell / nb_.x()) % nb_.y(), bx = cell % nb_.x();
    const std::uint64_t* F = block_front_.data() + static_cast<std::size_t>(cell_block_[cell]) * fwords_;
    for (int w = 0; w < fwords_; ++w) {
      std::uint64_t bits = F[w];
      while (bits) {
        const int i = w * 64 + __builtin_ctzll(bits);
        bits &= bits - 1;
        const Eigen::Vector3d v(bx * bs_ + (i & (bs_ - 1)), by * bs_ + ((i >> bshift_) & (bs_ - 1)),
                                bz * bs_ + (i >> (2 * bshift_)));
        f(origin_ + (v + Eigen::Vector3d::Constant(0.5)) * res_, res_);
      }
    }
  }
  for (int cell : frontier_cells_) {
    if (!(cell_flags_[cell] & kCoarseFrontier)) continue;
    const int bz = cell / (nb_.x() * nb_.y()), by = (cell / nb_.x()) % nb_.y(), bx = cell % nb_.x();
    f(origin_ + (Eigen::Vector3d(bx, by, bz) * bs_ + Eigen::Vector3d::Constant(0.5 * bs_)) * res_, bs_ * res_);
  }
}

}  // namespace semexp

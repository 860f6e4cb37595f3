// Background occupancy map: the frontier tracker, incrementally maintained frontiers (free leaves
// with an unknown 6-neighbour, paper IV-A.1).
//
// Why re-checking the changed cells plus the previous frontiers next to them
// is exact: integration never makes a voxel unknown again, so a voxel whose
// own cell did not change can only lose frontier status (its unknown
// neighbour, in an adjacent changed cell, got observed), never gain it.
// OccupancyMap::applyBlocks may write unknown over known voxels; it marks the
// written cells' face neighbours as candidates too.
#include "semantic_exploration/core/occupancy/frontier_tracker.hpp"

#include <algorithm>

namespace semexp {
namespace occupancy {

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

// flags_ bits
constexpr std::uint8_t kCandidate = 2;      // changed since the last update()
constexpr std::uint8_t kCoarseFrontier = 4; // uniform cell that is a frontier
constexpr std::uint8_t kBlockFrontier = 8;  // block with frontier bits
constexpr std::uint8_t kListedBlock = 16;   // in blocks_
constexpr std::uint8_t kListedCell = 32;    // in cells_
constexpr std::uint8_t kVisited = 64;       // scratch of update()

// Outside the map nothing can be explored: report it as known (not a frontier cause).
std::int16_t voxelValueOrKnown(const BlockStore& S, int x, int y, int z) {
  if (x < 0 || y < 0 || z < 0 || x >= S.nb.x() * S.bs || y >= S.nb.y() * S.bs || z >= S.nb.z() * S.bs) return 0;
  return S.voxelValue(x, y, z);
}
}  // namespace

bool FrontierTracker::uniformCellIsFrontier(const BlockStore& S, int cell) const {
  if (S.cell_block[cell] >= 0) return false;
  const std::int16_t v = S.cell_value[cell];
  if (!isFreeValue(v)) return false;
  return facesUnknown(S, cell, true);
}

bool FrontierTracker::facesUnknown(const BlockStore& S, int cell, bool trust_summaries) {
  const Eigen::Vector3i c = S.cellCoords(cell);
  const int m = S.bs - 1;
  for (int axis = 0; axis < 3; ++axis)
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      Eigen::Vector3i n = c;
      n[axis] += sgn;
      if (n[axis] < 0 || n[axis] >= S.nb[axis]) continue;
      const int nc = S.cellIndex(n.x(), n.y(), n.z());
      const int nbk = S.cell_block[nc];
      if (nbk < 0) {
        if (S.cell_value[nc] == kUnknown) return true;
        continue;
      }
      if (trust_summaries && !S.levels[0].s[nc].unknown_any) continue;
      const std::int16_t* L = S.logOdds(nbk);
      const int layer = sgn > 0 ? 0 : m;  // the neighbour's face touching this cell
      for (int a = 0; a < S.bs; ++a)
        for (int b = 0; b < S.bs; ++b) {
          int q[3];
          q[axis] = layer;
          q[(axis + 1) % 3] = a;
          q[(axis + 2) % 3] = b;
          if (L[q[0] + S.bs * (q[1] + S.bs * q[2])] == kUnknown) return true;
        }
    }
  return false;
}

void FrontierTracker::recheckBlock(const BlockStore& S, int cell, bool full) {
  const int b = S.cell_block[cell];
  std::uint64_t* F = bits_.data() + static_cast<std::size_t>(b) * fwords_;
  const std::int16_t* L = S.logOdds(b);
  const Eigen::Vector3i bc = S.cellCoords(cell);
  const int gx0 = bc.x() * S.bs, gy0 = bc.y() * S.bs, gz0 = bc.z() * S.bs;
  const int m = S.bs - 1, s1 = S.bs, s2 = S.bs * S.bs;
  auto isFrontier = [&](int i) {
    if (!isFreeValue(L[i])) return false;
    const int x = i & m, y = (i >> S.bshift) & m, z = i >> (2 * S.bshift);
    if (x < m ? L[i + 1] == kUnknown : voxelValueOrKnown(S, gx0 + x + 1, gy0 + y, gz0 + z) == kUnknown) return true;
    if (x > 0 ? L[i - 1] == kUnknown : voxelValueOrKnown(S, gx0 + x - 1, gy0 + y, gz0 + z) == kUnknown) return true;
    if (y < m ? L[i + s1] == kUnknown : voxelValueOrKnown(S, gx0 + x, gy0 + y + 1, gz0 + z) == kUnknown) return true;
    if (y > 0 ? L[i - s1] == kUnknown : voxelValueOrKnown(S, gx0 + x, gy0 + y - 1, gz0 + z) == kUnknown) return true;
    if (z < m ? L[i + s2] == kUnknown : voxelValueOrKnown(S, gx0 + x, gy0 + y, gz0 + z + 1) == kUnknown) return true;
    if (z > 0 ? L[i - s2] == kUnknown : voxelValueOrKnown(S, gx0 + x, gy0 + y, gz0 + z - 1) == kUnknown) return true;
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
  const Summary& s = S.levels[0].s[cell];
  if (!s.known_any || s.min_l >= 0) return;  // no free voxel
  if (s.unknown_any) {
    for (int i = 0; i < S.bs3; ++i)
      if (isFrontier(i)) F[i >> 6] |= std::uint64_t{1} << (i & 63);
    return;
  }
  // No unknown voxel inside: only faces next to a cell with unknown space can hold frontiers.
  for (int axis = 0; axis < 3; ++axis)
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      Eigen::Vector3i n = bc;
      n[axis] += sgn;
      if (n[axis] < 0 || n[axis] >= S.nb[axis]) continue;
      if (!S.levels[0].s[S.cellIndex(n.x(), n.y(), n.z())].unknown_any) continue;
      const int layer = sgn > 0 ? m : 0;
      for (int a = 0; a < S.bs; ++a)
        for (int c = 0; c < S.bs; ++c) {
          int q[3];
          q[axis] = layer;
          q[(axis + 1) % 3] = a;
          q[(axis + 2) % 3] = c;
          const int i = q[0] + S.bs * (q[1] + S.bs * q[2]);
          if (isFrontier(i)) F[i >> 6] |= std::uint64_t{1} << (i & 63);
        }
    }
}

int FrontierTracker::blockBitCount(const BlockStore& S, int cell) const {
  const std::uint64_t* F = blockBits(S.cell_block[cell]);
  int n = 0;
  for (int w = 0; w < fwords_; ++w) n += popcount64(F[w]);
  return n;
}

void FrontierTracker::checkCell(const BlockStore& S, int cell, bool full) {
  std::uint8_t& fl = flags_[cell];
  if (S.cell_block[cell] >= 0) {
    if (fl & kCoarseFrontier) {  // refined into a block since
      fl &= static_cast<std::uint8_t>(~kCoarseFrontier);
      --cell_count_;
    }
    const bool had = fl & kBlockFrontier;
    const int before = had ? blockBitCount(S, cell) : 0;
    if (!had && !full) return;
    recheckBlock(S, cell, full);
    const int after = blockBitCount(S, cell);
    voxels_ = voxels_ - before + after;
    if (after > 0 && !had) {
      fl |= kBlockFrontier;
      ++block_count_;
      if (!(fl & kListedBlock)) {
        fl |= kListedBlock;
        blocks_.push_back(cell);
      }
    } else if (after == 0 && had) {
      fl &= static_cast<std::uint8_t>(~kBlockFrontier);
      --block_count_;
      emptied_.push_back(cell);
    }
    return;
  }
  const bool was = fl & kCoarseFrontier;
  const bool is = uniformCellIsFrontier(S, cell);
  if (is && !was) {
    fl |= kCoarseFrontier;
    ++cell_count_;
    if (!(fl & kListedCell)) {
      fl |= kListedCell;
      cells_.push_back(cell);
    }
  } else if (!is && was) {
    fl &= static_cast<std::uint8_t>(~kCoarseFrontier);
    --cell_count_;
  }
}

void FrontierTracker::update(const BlockStore& S) {
  // A voxel's frontier status depends on itself and its 6 neighbours only, so
  // besides the changed cells just the frontier-holding cells face-adjacent to
  // them can change (and only by losing frontiers): cost follows the update,
  // not the size of the frontier set.
  fit(S);
  for (int c : cand_) flags_[c] |= kVisited;
  for (int c : cand_) checkCell(S, c, true);
  std::vector<int> extra;
  for (int c : cand_)
    S.forEachFaceNeighbour(c, [&](int nc) {
      std::uint8_t& fl = flags_[nc];
      if ((fl & kVisited) || !(fl & (kBlockFrontier | kCoarseFrontier))) return;
      fl |= kVisited;
      extra.push_back(nc);
      checkCell(S, nc, false);
    });
  const std::uint8_t clear = static_cast<std::uint8_t>(~(kVisited | kCandidate));
  for (int c : cand_) flags_[c] &= clear;
  for (int c : extra) flags_[c] &= clear;
  cand_.clear();
  // Drop stale list entries once they dominate.
  if (blocks_.size() > 2 * block_count_ + 256)
    compactCellList(blocks_, flags_, kBlockFrontier, kListedBlock);
  if (cells_.size() > 2 * cell_count_ + 256)
    compactCellList(cells_, flags_, kCoarseFrontier, kListedCell);
}

std::uint64_t* FrontierTracker::mutableBlockBits(const BlockStore& S, int b) {
  fit(S);
  return bits_.data() + static_cast<std::size_t>(b) * fwords_;
}

void FrontierTracker::reset(std::size_t cells, int fwords) {
  fwords_ = fwords;
  flags_.assign(cells, 0);
  bits_.clear();
  zeros_.assign(static_cast<std::size_t>(fwords), 0);
  cand_.clear();
  emptied_.clear();
  blocks_.clear();
  cells_.clear();
  voxels_ = 0;
  block_count_ = cell_count_ = 0;
}

// Bits for every block slot of the store, following the store's pool capacity.
void FrontierTracker::fit(const BlockStore& S) {
  if (bits_.size() < S.slotCount() * fwords_) bits_.resize(S.block_cell.capacity() * fwords_, 0);
}

void FrontierTracker::markCandidate(int cell) {
  if (flags_[cell] & kCandidate) return;
  flags_[cell] |= kCandidate;
  cand_.push_back(cell);
}

void FrontierTracker::onBlockReleased(const BlockStore& S, int cell) {
  const int b = S.cell_block[cell];
  if (b < 0 || !(flags_[cell] & kBlockFrontier)) return;
  voxels_ -= static_cast<std::size_t>(blockBitCount(S, cell));
  --block_count_;
  flags_[cell] &= static_cast<std::uint8_t>(~kBlockFrontier);
  std::fill_n(bits_.data() + static_cast<std::size_t>(b) * fwords_, fwords_, 0);
}

const std::uint64_t* FrontierTracker::blockBits(int b) const {
  const std::size_t o = static_cast<std::size_t>(b) * fwords_;
  return o < bits_.size() ? bits_.data() + o : zeros_.data();
}

bool FrontierTracker::cellIsListedFrontier(int cell) const { return flags_[cell] & kCoarseFrontier; }
bool FrontierTracker::blockHasFrontier(int cell) const { return flags_[cell] & kBlockFrontier; }

void FrontierTracker::forEach(const BlockStore& S, const std::function<void(const Eigen::Vector3d&, double)>& f) const {
  const int bs = S.bs;
  for (int cell : blocks_) {
    if (!(flags_[cell] & kBlockFrontier)) continue;
    const Eigen::Vector3i base = S.cellCoords(cell) * S.bs;
    const std::uint64_t* F = blockBits(S.cell_block[cell]);
    for (int w = 0; w < fwords_; ++w) {
      std::uint64_t bits = F[w];
      while (bits) {
        const int i = w * 64 + __builtin_ctzll(bits);
        bits &= bits - 1;
        f(S.voxelCentre(base + S.voxelInCell(i)), S.res);
      }
    }
  }
  for (int cell : cells_) {
    if (!(flags_[cell] & kCoarseFrontier)) continue;
    f(S.cellCentre(cell), bs * S.res);
  }
}

void FrontierTracker::liveLists(std::vector<int>& blocks, std::vector<int>& cells) const {
  blocks.clear();
  cells.clear();
  for (int c : blocks_)
    if (flags_[c] & kBlockFrontier) blocks.push_back(c);
  for (int c : cells_)
    if (flags_[c] & kCoarseFrontier) cells.push_back(c);
}

bool FrontierTracker::restore(const BlockStore& S, const std::vector<int>& blocks, const std::vector<int>& cells) {
  const auto inside = [&](int c) { return c >= 0 && static_cast<std::size_t>(c) < S.cellCount(); };
  for (int c : cells) {
    if (!inside(c) || S.cell_block[c] >= 0) return false;
    flags_[c] |= kCoarseFrontier | kListedCell;
  }
  for (int c : blocks) {
    if (!inside(c) || S.cell_block[c] < 0) return false;
    flags_[c] |= kBlockFrontier | kListedBlock;
  }
  cells_ = cells;
  cell_count_ = cells.size();
  blocks_ = blocks;
  block_count_ = blocks.size();
  voxels_ = 0;
  for (int c : blocks) voxels_ += static_cast<std::size_t>(blockBitCount(S, c));
  return true;
}

std::size_t FrontierTracker::memoryBytes() const {
  return flags_.capacity() + (bits_.capacity() + zeros_.capacity()) * sizeof(std::uint64_t) +
         (cand_.capacity() + emptied_.capacity() + blocks_.capacity() + cells_.capacity()) * sizeof(int);
}

}  // namespace occupancy
}  // namespace semexp

#pragma once
/// @file block_store.hpp
/// Storage of the background occupancy map (internal to OccupancyMap; see
/// occupancy_map.hpp for the structure).
///
/// The bounds are covered by a grid of cells of bs^3 voxels. A cell is a
/// uniform leaf (one log-odds value and one minimum distance for all of its
/// voxels) or owns a dense block slot. Blocks that ever held an occupied
/// voxel also own a surface slot (minimum observed distance, colour). Above
/// the cells a pyramid of Summary levels (each node 2x2x2 nodes of the level
/// below, up to one root) holds min/max log-odds and known/unknown flags.
///
/// Allocation policy: released block and surface slots are reused last-in
/// first-out; the pools grow by a quarter (+64 slots) rather than doubling,
/// since they are most of the memory.

#include <Eigen/Core>
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <vector>

#include "semantic_exploration/core/bounds.hpp"

namespace semexp {
namespace occupancy {

constexpr std::int16_t kUnknown = INT16_MIN;  ///< log-odds of a voxel never updated
constexpr double kScale = 1000.0;             ///< stored log-odds per unit log-odds (int16 thousandths)
constexpr std::uint16_t kNoDist = 0xFFFF;     ///< minimum distance of a voxel never observed

/// A stored log-odds that is known and free: kUnknown is negative too, so `< 0` alone would count it.
constexpr bool isFreeValue(std::int16_t l) { return l != kUnknown && l < 0; }

/// Log-odds (natural) -> stored thousandths.
inline std::int16_t toFixed(double l) { return static_cast<std::int16_t>(std::lround(l * kScale)); }
/// Distance (m, >= 0) -> stored whole mm, rounded, capped below kNoDist.
inline std::uint16_t toMm(float d_m) {
  return static_cast<std::uint16_t>(std::min(d_m * 1000.f + 0.5f, 65534.f));
}

/// What is below a node of the summary pyramid.
struct Summary {
  std::int16_t min_l;        ///< min log-odds over known voxels below (INT16_MAX if none)
  std::int16_t max_l;        ///< max log-odds over known voxels below (INT16_MIN if none)
  std::uint8_t known_any;    ///< some voxel below is known
  std::uint8_t unknown_any;  ///< some voxel below is unknown
  /// Every voxel below known and free at one value.
  bool uniformFree() const { return !unknown_any && min_l == max_l && max_l < 0; }
};

/// One level of the summary pyramid: dims nodes per axis, x fastest.
struct SummaryLevel {
  Eigen::Vector3i dims;
  std::vector<Summary> s;
  const Summary& at(int x, int y, int z) const { return s[x + dims.x() * (y + dims.y() * z)]; }
};

/// Cells, block and surface pools and the summary pyramid. Data members are
/// public (the map's parts read them in their inner loops); the methods keep
/// the slot bookkeeping consistent.
class BlockStore {
 public:
  /// Voxel (0,0,0)'s corner is bounds.min_m snapped down to a multiple of
  /// resolution_m; the cells cover the bounds rounded outwards to whole cells.
  /// `colour`: surface slots carry r, g, b, weight per voxel.
  BlockStore(double resolution_m, int block_size, const Bounds& bounds, bool colour);

  /// Everything unknown again, all slots dropped.
  void reset();

  // ---------------------------------------------------------- geometry
  double res = 0.04;          ///< voxel edge, m
  int bs = 8;                 ///< voxels per cell edge (power of two)
  int bshift = 3;             ///< log2(bs)
  int bs3 = 512;              ///< voxels per cell
  int fwords = 8;             ///< 64-bit words of one bit per voxel of a block
  Eigen::Vector3d origin;     ///< corner of voxel (0,0,0), world, m
  Eigen::Vector3i nb;         ///< cells per axis
  bool colour = true;

  int cellIndex(int bx, int by, int bz) const { return bx + nb.x() * (by + nb.y() * bz); }
  Eigen::Vector3i cellCoords(int cell) const {
    return {cell % nb.x(), (cell / nb.x()) % nb.y(), cell / (nb.x() * nb.y())};
  }
  /// Calls f(neighbour cell index) for each face neighbour of `cell` inside the grid.
  template <class F>
  void forEachFaceNeighbour(int cell, F&& f) const {
    const Eigen::Vector3i c = cellCoords(cell);
    for (int axis = 0; axis < 3; ++axis)
      for (int sgn = -1; sgn <= 1; sgn += 2) {
        Eigen::Vector3i n = c;
        n[axis] += sgn;
        if (n[axis] >= 0 && n[axis] < nb[axis]) f(cellIndex(n.x(), n.y(), n.z()));
      }
  }

  std::size_t cellCount() const { return cell_block.size(); }
  /// Index of voxel (x, y, z) of a cell, each in [0, bs).
  int voxelIndex(int x, int y, int z) const { return x + bs * (y + bs * z); }
  /// (x, y, z) in [0, bs) of voxel `vox` in [0, bs3) of a cell: the inverse of voxelIndex.
  Eigen::Vector3i voxelInCell(int vox) const {
    const int m = bs - 1;
    return {vox & m, (vox >> bshift) & m, vox >> (2 * bshift)};
  }
  /// Map voxel coordinates (voxels from the origin) of voxel `vox` in [0, bs3) of `cell` in [0, cellCount()).
  Eigen::Vector3i mapVoxel(int cell, int vox) const { return cellCoords(cell) * bs + voxelInCell(vox); }
  /// Centre of the map voxel with coordinates v (voxels from the origin), world, m.
  Eigen::Vector3d voxelCentre(const Eigen::Vector3i& v) const {
    return origin + (v.cast<double>() + Eigen::Vector3d::Constant(0.5)) * res;
  }
  /// Centre of `cell` in [0, cellCount()) (the whole cell: a uniform leaf), world, m.
  Eigen::Vector3d cellCentre(int cell) const {
    return origin + (cellCoords(cell).cast<double>() * bs + Eigen::Vector3d::Constant(0.5 * bs)) * res;
  }

  // ---------------------------------------------------------- per cell
  std::vector<std::int32_t> cell_block;  ///< block slot or -1 (uniform leaf)
  std::vector<std::int16_t> cell_value;  ///< log-odds of a uniform leaf
  std::vector<std::uint16_t> cell_dist;  ///< min observed distance of a uniform leaf, mm (kNoDist never)

  // ---------------------------------------------------- per block slot
  std::vector<std::int32_t> block_cell;   ///< owning cell or -1 (free slot)
  std::vector<std::int16_t> block_l;      ///< bs3 log-odds per slot
  std::vector<std::int32_t> block_surf;   ///< surface slot of each block or -1
  std::vector<std::uint32_t> block_nfree, block_nocc;  ///< free / occupied voxels per block (set by cellSummary)
  // ---------------------------------------------------- per surface slot
  std::vector<std::uint16_t> surf_dist;   ///< bs3 per slot, mm (kNoDist never)
  std::vector<std::uint8_t> surf_rgbw;    ///< 4 * bs3 per slot (r, g, b, weight) if colour

  // ------------------------------------------------- summary pyramid
  std::vector<SummaryLevel> levels;  ///< levels[0]: per cell; levels[k]: nodes of 2^k x 2^k x 2^k cells

  std::int16_t* logOdds(int b) { return block_l.data() + static_cast<std::size_t>(b) * bs3; }
  const std::int16_t* logOdds(int b) const { return block_l.data() + static_cast<std::size_t>(b) * bs3; }
  std::uint16_t* dist(int sl) { return surf_dist.data() + static_cast<std::size_t>(sl) * bs3; }
  const std::uint16_t* dist(int sl) const { return surf_dist.data() + static_cast<std::size_t>(sl) * bs3; }
  std::uint8_t* rgbw(int sl) { return surf_rgbw.data() + static_cast<std::size_t>(sl) * bs3 * 4; }
  const std::uint8_t* rgbw(int sl) const { return surf_rgbw.data() + static_cast<std::size_t>(sl) * bs3 * 4; }

  /// Gives `cell` a block slot holding its uniform value everywhere (no surface); returns the slot.
  int allocateBlock(int cell);
  /// Surface slot of block b, allocated (distances never, no colour) if missing.
  int ensureSurface(int b);
  /// Drops block b's surface slot, if any.
  void releaseSurface(int b);
  /// Makes `cell` a uniform leaf again (its value is left as it was: set it).
  void releaseBlock(int cell);
  std::size_t blockCount() const { return block_count_; }
  std::size_t slotCount() const { return block_cell.size(); }  ///< block slots ever allocated

  /// Log-odds of voxel (x, y, z) in map voxel coordinates; kUnknown outside.
  std::int16_t voxelValue(int x, int y, int z) const {
    if (x < 0 || y < 0 || z < 0 || x >= nb.x() * bs || y >= nb.y() * bs || z >= nb.z() * bs) return kUnknown;
    const int cell = cellIndex(x >> bshift, y >> bshift, z >> bshift);
    const int b = cell_block[cell];
    if (b < 0) return cell_value[cell];
    const int m = bs - 1;
    return logOdds(b)[voxelIndex(x & m, y & m, z & m)];
  }

  /// Summary of one cell from its voxels; also refreshes the block's free/occupied counts.
  Summary cellSummary(int cell);
  /// Recomputes levels[1..] above `cells` (their levels[0] entries already set).
  void propagateSummaries(std::vector<int> cells);

  std::size_t memoryBytes() const;

 private:
  std::vector<std::int32_t> free_slots_;  ///< released block slots
  std::vector<std::int32_t> surf_free_;   ///< released surface slots
  std::size_t surf_slots_ = 0;            ///< surface slots ever allocated
  std::size_t block_count_ = 0;
};

}  // namespace occupancy
}  // namespace semexp

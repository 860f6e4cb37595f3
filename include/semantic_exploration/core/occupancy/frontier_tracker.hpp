#pragma once
/// @file frontier_tracker.hpp
/// Incrementally maintained frontiers of the background occupancy map
/// (internal to OccupancyMap; paper IV-A.1): free leaves with an unknown
/// 6-neighbour. Owns its per-cell flags, its lists and one bit per voxel of
/// every block slot.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "semantic_exploration/core/occupancy/block_store.hpp"

namespace semexp {
namespace occupancy {

class FrontierTracker {
 public:
  /// No frontiers; `cells` cells, `fwords` 64-bit words per block slot.
  void reset(std::size_t cells, int fwords);
  /// The cell's voxels changed since the last update(): re-check it there.
  void markCandidate(int cell);
  /// Re-checks the candidates (and the frontier cells face-adjacent to them)
  /// against the store's current voxels; clears the candidates.
  void update(const BlockStore& store);
  /// Call before the store releases `cell`'s block: drops its frontier bits.
  void onBlockReleased(const BlockStore& store, int cell);

  /// Frontier voxels in blocks plus frontier uniform cells.
  std::size_t count() const { return voxels_ + cell_count_; }
  /// Centre and edge length (m) of every frontier leaf.
  void forEach(const BlockStore& store, const std::function<void(const Eigen::Vector3d& centre_W, double size_m)>& f) const;
  /// Is this uniform cell a frontier / does this cell's block hold frontier bits?
  bool cellIsListedFrontier(int cell) const;
  bool blockHasFrontier(int cell) const;
  /// Does a voxel of a face-adjacent cell that touches `cell` hold unknown?
  /// (A free uniform cell that does is a coarse frontier leaf.) With
  /// trust_summaries, a neighbour block whose level-0 summary has no unknown
  /// voxel is not read (the summaries must be current).
  static bool facesUnknown(const BlockStore& store, int cell, bool trust_summaries = false);
  /// Cells whose block lost its last frontier voxel in the updates since the
  /// last call (the map releases those that are uniform free: OccupancyMap::updateFrontiers).
  std::vector<int> takeEmptiedBlocks() { std::vector<int> out; out.swap(emptied_); return out; }

  // ------------------------------------- persistence (OccupancyMap::save/load)
  /// fwords frontier bits of block slot b (all zero for a block without frontiers).
  const std::uint64_t* blockBits(int b) const;
  /// Writable bits of slot b (sized for the store's slots).
  std::uint64_t* mutableBlockBits(const BlockStore& store, int b);
  /// Cells of the live frontier blocks and frontier uniform cells, in list order.
  void liveLists(std::vector<int>& blocks, std::vector<int>& cells) const;
  /// Rebuilds flags and counts from saved lists (bits already restored).
  /// False if an entry names a cell of the wrong kind or outside the map.
  bool restore(const BlockStore& store, const std::vector<int>& blocks, const std::vector<int>& cells);

  std::size_t memoryBytes() const;

 private:
  void fit(const BlockStore& store);
  void recheckBlock(const BlockStore& store, int cell, bool full);
  void checkCell(const BlockStore& store, int cell, bool full);
  int blockBitCount(const BlockStore& store, int cell) const;
  bool uniformCellIsFrontier(const BlockStore& store, int cell) const;

  int fwords_ = 8;
  std::vector<std::uint8_t> flags_;   ///< per cell, bits in frontier_tracker.cpp
  std::vector<std::uint64_t> bits_;   ///< fwords_ per block slot
  std::vector<std::uint64_t> zeros_;  ///< fwords_ zero words (blockBits of slots beyond bits_)
  std::vector<int> cand_;             ///< changed since the last update()
  std::vector<int> emptied_;          ///< cells whose block lost its last frontier bit (takeEmptiedBlocks)
  std::vector<int> blocks_;           ///< cells whose block has frontier bits (entries without the flag are stale)
  std::vector<int> cells_;            ///< uniform cells that are frontiers (entries without the flag are stale)
  std::size_t voxels_ = 0;            ///< set frontier bits over all blocks
  std::size_t block_count_ = 0, cell_count_ = 0;
};

}  // namespace occupancy
}  // namespace semexp

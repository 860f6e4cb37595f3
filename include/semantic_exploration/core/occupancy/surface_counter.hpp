#pragma once
/// @file surface_counter.hpp
/// The observed surface of the background map and the part of it observed
/// from close by (OccupancyMap::surfaceObservedWithin, the background half of
/// the paper's termination condition, Section IV-D), counted per cell, and a
/// cache of those counts that counts again only the cells a frame can have
/// changed (OccupancyMap::trackSurfaceObservedWithin). Internal to
/// OccupancyMap.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "semantic_exploration/core/occupancy/block_store.hpp"

namespace semexp {
namespace occupancy {

/// Surface voxels of one cell and, of those, the ones updated from <= d.
struct SurfaceCount {
  std::uint32_t occupied = 0;  ///< surface voxels (a uniform occupied cell: its exposed face voxels)
  std::uint32_t within = 0;    ///< of those, observed from <= d
};

/// Sums of SurfaceCount over cells.
struct SurfaceTotals {
  std::size_t occupied = 0;
  std::size_t within = 0;
};

/// Which voxels count as surface and how far a voxel's count looks.
struct SurfaceRule {
  double d_mm = 0.0;  ///< "close by": observed from <= d_mm, whole mm (distances are stored in mm)
  /// Free margin q (1/m): with q > 0 a surface seen from d has an unknown
  /// gap of up to sqrt(3) q d^2 in front of it, which the count looks across.
  double gap_q_per_m = 0.0;
  /// Cells along one axis whose voxels a cell's count can read (the
  /// longest walk, kMaxGapSteps + 1 voxels with a margin, 1 voxel without).
  int reachCells(const BlockStore& store) const;
};

/// The longest walk across a free-margin gap, voxels: 32 x 4 cm covers sqrt(3) q d^2 for q = 0.006 up to 11 m.
constexpr int kMaxGapSteps = 32;

/// Sums countSurface over every cell (the full count).
SurfaceTotals countSurfaceAll(const BlockStore& store, const SurfaceRule& rule);

/// Counts the surface voxels of `cell`: occupied voxels with a free
/// 6-neighbour or, with a margin, free space along an axis beyond unknown
/// voxels only, as far as the voxel's own gap reaches.
SurfaceCount countSurface(const BlockStore& store, int cell, const SurfaceRule& rule);

/// Per-cell SurfaceCount of the last update() and their sums. A cell's count
/// depends on its own voxels and on voxels at most rule.reachCells() cells
/// away along one axis, so a change of occupancy marks that cross of cells
/// for counting again, and a change of distances only the cell itself.
class SurfaceCounter {
 public:
  /// Everything is counted again at the next update().
  void reset();
  /// A voxel of `cell` changed between unknown, free and occupied (or the
  /// cell changed in a way the caller does not say more precisely): marks it
  /// and the cells within reachCells() of it along each axis.
  void occupancyChanged(const BlockStore& store, int cell, const SurfaceRule& rule);
  /// Only the observed distances of `cell`'s occupied voxels changed: marks it alone.
  void distanceChanged(int cell);
  /// Counts the marked cells again (all of them after reset() or with a
  /// rule other than the last one's) and returns the sums over all cells.
  SurfaceTotals update(const BlockStore& store, const SurfaceRule& rule);
  /// Cells counted by the last update() (every cell on a full count).
  std::size_t lastCounted() const { return last_counted_; }
  std::size_t memoryBytes() const;

 private:
  void mark(int cell);

  std::vector<SurfaceCount> per_cell_;
  std::vector<std::uint8_t> stale_;  ///< per cell: to be counted again
  std::vector<int> stale_cells_;     ///< the cells with stale_ set
  bool all_stale_ = true;
  SurfaceRule last_rule_;
  SurfaceTotals sum_;
  std::size_t last_counted_ = 0;
};

}  // namespace occupancy
}  // namespace semexp

// SurfaceCounter and countSurface on hand-built cells: which voxel counts as
// surface, how far a cell's count reaches, and which changes make the cache
// count a cell again. Hand-computed answers; the flight-length comparison with
// a full count is in occupancy_surface_share_test.cpp.
#include <gtest/gtest.h>

#include "semantic_exploration/core/occupancy/surface_counter.hpp"

using semexp::Bounds;
using semexp::occupancy::BlockStore;
using semexp::occupancy::countSurface;
using semexp::occupancy::SurfaceCounter;
using semexp::occupancy::SurfaceRule;
using semexp::occupancy::SurfaceTotals;

namespace {

// Three cells of 8^3 voxels of 4 cm in a row along x, all unknown.
BlockStore threeCells() {
  Bounds b;
  b.min_m = {0.0, 0.0, 0.0};
  b.max_m = {0.96, 0.32, 0.32};
  return BlockStore(0.04, 8, b, false);
}

void refreshSummaries(BlockStore& s) {
  for (int c = 0; c < static_cast<int>(s.cellCount()); ++c) s.levels[0].s[c] = s.cellSummary(c);
}

// One occupied voxel (log-odds 3.5) on the -x face of cell 2, at map voxel (16, 3, 3), observed from d_mm.
void occupiedFaceVoxel(BlockStore& s, std::uint16_t d_mm) {
  const int b = s.cell_block[2] >= 0 ? s.cell_block[2] : s.allocateBlock(2);
  const int i = s.voxelIndex(0, 3, 3);
  s.logOdds(b)[i] = 3500;
  s.dist(s.ensureSurface(b))[i] = d_mm;
  refreshSummaries(s);
}

// q = 0.006 1/m (the default free margin) and d = 7 m: a voxel seen from 6 m looks across
// ceil(sqrt(3) 0.006 6^2 / 0.04) = ceil(9.35) = 10 unknown voxels, one seen from 4 m across ceil(4.16) = 5.
SurfaceRule marginRule() {
  SurfaceRule r;
  r.d_mm = 7000.0;
  r.gap_q_per_m = 0.006;
  return r;
}

}  // namespace

TEST(SurfaceCounter, ReachIsTheLongestWalkInCells) {
  BlockStore s = threeCells();
  SurfaceRule r;
  EXPECT_EQ(r.reachCells(s), 1);  // no margin: a direct neighbour, one voxel past the cell
  r.gap_q_per_m = 0.006;
  EXPECT_EQ(r.reachCells(s), 5);  // 32 + 1 voxels = 4.1 cells of 8
}

TEST(SurfaceCounter, AFreeVoxelTwoCellsAwayAcrossTheGapExposesTheSurface) {
  BlockStore s = threeCells();
  occupiedFaceVoxel(s, 6000);
  const SurfaceRule rule = marginRule();
  SurfaceCounter counter;
  SurfaceTotals t = counter.update(s, rule);
  EXPECT_EQ(counter.lastCounted(), 3u);  // the first count is a full one
  EXPECT_EQ(t.occupied, 0u);             // unknown all round: nothing observed in front of it
  // Cell 0 becomes free: map voxel x = 7 lies 9 steps from x = 16 along -x, across 8 unknown ones (cell 1).
  s.cell_value[0] = -2000;
  refreshSummaries(s);
  counter.occupancyChanged(s, 0, rule);
  t = counter.update(s, rule);
  EXPECT_EQ(t.occupied, 1u);
  EXPECT_EQ(t.within, 1u);  // 6 m <= 7 m
  EXPECT_EQ(countSurface(s, 2, rule).occupied, 1u);
  // Seen from 4 m the gap is 5 voxels: the walk ends in cell 1's unknown voxels.
  BlockStore near = threeCells();
  occupiedFaceVoxel(near, 4000);
  near.cell_value[0] = -2000;
  refreshSummaries(near);
  EXPECT_EQ(countSurface(near, 2, rule).occupied, 0u);
  // Without the margin only a direct neighbour counts.
  EXPECT_EQ(countSurface(s, 2, SurfaceRule{7000.0, 0.0}).occupied, 0u);
}

TEST(SurfaceCounter, OnlyMarkedCellsAreCountedAgain) {
  BlockStore s = threeCells();
  occupiedFaceVoxel(s, 8000);
  s.cell_value[1] = -2000;  // free in front of the voxel: surface, observed from 8 m
  refreshSummaries(s);
  const SurfaceRule rule = marginRule();
  SurfaceCounter counter;
  SurfaceTotals t = counter.update(s, rule);
  ASSERT_EQ(t.occupied, 1u);
  ASSERT_EQ(t.within, 0u);  // 8 m > 7 m
  // Seen again from 6 m: within 7 m now. Unmarked, the cache keeps the old count; marked, it follows.
  s.dist(s.block_surf[s.cell_block[2]])[s.voxelIndex(0, 3, 3)] = 6000;
  EXPECT_EQ(counter.update(s, rule).within, 0u);
  EXPECT_EQ(counter.lastCounted(), 0u);
  counter.distanceChanged(2);
  t = counter.update(s, rule);
  EXPECT_EQ(counter.lastCounted(), 1u);
  EXPECT_EQ(t.occupied, 1u);
  EXPECT_EQ(t.within, 1u);
  // Another rule counts everything again.
  SurfaceRule near = rule;
  near.d_mm = 5000.0;
  EXPECT_EQ(counter.update(s, near).within, 0u);
  EXPECT_EQ(counter.lastCounted(), 3u);
  // So does reset().
  counter.reset();
  counter.update(s, near);
  EXPECT_EQ(counter.lastCounted(), 3u);
}

TEST(SurfaceCounter, AUniformOccupiedCellCountsItsExposedFaceVoxels) {
  BlockStore s = threeCells();
  s.cell_value[1] = 3500;  // occupied throughout, observed from 2 m
  s.cell_dist[1] = 2000;
  s.cell_value[0] = -2000;  // free on its -x side only
  refreshSummaries(s);
  SurfaceCounter counter;
  const SurfaceTotals t = counter.update(s, SurfaceRule{3000.0, 0.0});
  EXPECT_EQ(t.occupied, 64u);  // the 8 x 8 voxels of the face towards cell 0
  EXPECT_EQ(t.within, 64u);
  EXPECT_EQ(counter.update(s, SurfaceRule{1000.0, 0.0}).within, 0u);
}

// BlockStore: geometry, slot allocation and reuse, growth policy, surface
// slots and summaries, with hand-computed answers.
#include <gtest/gtest.h>

#include "semantic_exploration/core/occupancy/block_store.hpp"

using semexp::Bounds;
using semexp::occupancy::BlockStore;
using semexp::occupancy::kNoDist;
using semexp::occupancy::kUnknown;
using semexp::occupancy::Summary;

namespace {
Bounds box(double x0, double x1, double y1, double z1) {
  Bounds b;
  b.min_m = {x0, 0.0, 0.0};
  b.max_m = {x1, y1, z1};
  return b;
}
}  // namespace

TEST(BlockStore, GeometrySnapsTheOriginAndRoundsCellsOut) {
  // x from -0.05: origin snaps down to -0.1; 0.85 m = 9 voxels -> 3 cells of 4
  BlockStore s(0.1, 4, box(-0.05, 0.75, 0.4, 0.4), true);
  EXPECT_NEAR(s.origin.x(), -0.1, 1e-12);
  EXPECT_EQ(s.nb, Eigen::Vector3i(3, 1, 1));
  EXPECT_EQ(s.bs3, 64);
  EXPECT_EQ(s.fwords, 1);
  EXPECT_EQ(s.bshift, 2);
  ASSERT_EQ(s.levels.size(), 3u);  // 3x1x1, 2x1x1, 1x1x1
  EXPECT_EQ(s.levels[1].dims, Eigen::Vector3i(2, 1, 1));
  EXPECT_EQ(s.cellCoords(2), Eigen::Vector3i(2, 0, 0));
  EXPECT_EQ(s.voxelValue(0, 0, 0), kUnknown);
  EXPECT_EQ(s.voxelValue(-1, 0, 0), kUnknown);
}

TEST(BlockStore, VoxelAndCellCentresFromCellAndVoxelIndices) {
  // origin -0.1 (as above), 0.1 m voxels, cells of 4; 3 x 2 x 1 cells.
  BlockStore s(0.1, 4, box(-0.05, 0.75, 0.8, 0.4), false);
  ASSERT_EQ(s.nb, Eigen::Vector3i(3, 2, 1));
  const int cell = s.cellIndex(2, 1, 0);  // 5
  EXPECT_EQ(s.cellCoords(cell), Eigen::Vector3i(2, 1, 0));
  // voxel (1, 2, 3) of that cell: index 1 + 4 (2 + 4 * 3) = 57; map voxel (8 + 1, 4 + 2, 0 + 3).
  EXPECT_EQ(s.mapVoxel(cell, s.voxelIndex(1, 2, 3)), Eigen::Vector3i(9, 6, 3));
  EXPECT_EQ(s.mapVoxel(cell, 57), Eigen::Vector3i(9, 6, 3));
  // centre of map voxel (9, 6, 3): origin (-0.1, 0, 0) + (9.5, 6.5, 3.5) * 0.1.
  const Eigen::Vector3d v = s.voxelCentre(Eigen::Vector3i(9, 6, 3));
  EXPECT_NEAR(v.x(), 0.85, 1e-12);
  EXPECT_NEAR(v.y(), 0.65, 1e-12);
  EXPECT_NEAR(v.z(), 0.35, 1e-12);
  // centre of the whole cell (2, 1, 0): origin + (2, 1, 0) * 0.4 + 0.2.
  const Eigen::Vector3d c = s.cellCentre(cell);
  EXPECT_NEAR(c.x(), 0.9, 1e-12);
  EXPECT_NEAR(c.y(), 0.6, 1e-12);
  EXPECT_NEAR(c.z(), 0.2, 1e-12);
  // Every voxel of every cell, x fastest, and the centres exactly equal to the formula the map's queries used.
  for (int k = 0; k < static_cast<int>(s.cellCount()); ++k) {
    const Eigen::Vector3i b = s.cellCoords(k);
    EXPECT_EQ(s.cellCentre(k),
              s.origin + (Eigen::Vector3d(b.x(), b.y(), b.z()) * s.bs + Eigen::Vector3d::Constant(0.5 * s.bs)) * s.res);
    for (int z = 0, i = 0; z < s.bs; ++z)
      for (int y = 0; y < s.bs; ++y)
        for (int x = 0; x < s.bs; ++x, ++i) {
          ASSERT_EQ(s.voxelIndex(x, y, z), i);
          ASSERT_EQ(s.voxelInCell(i), Eigen::Vector3i(x, y, z));
          const Eigen::Vector3i v = s.mapVoxel(k, i);
          ASSERT_EQ(v, b * s.bs + Eigen::Vector3i(x, y, z));
          ASSERT_EQ(s.voxelCentre(v), s.origin + (Eigen::Vector3d(b.x() * s.bs + x, b.y() * s.bs + y, b.z() * s.bs + z) +
                                                  Eigen::Vector3d::Constant(0.5)) * s.res);
        }
  }
}

TEST(BlockStore, SlotsAreReusedLastInFirstOut) {
  BlockStore s(0.1, 4, box(0.0, 1.2, 0.4, 0.4), false);
  ASSERT_EQ(s.cellCount(), 3u);
  EXPECT_EQ(s.allocateBlock(1), 0);
  EXPECT_EQ(s.allocateBlock(2), 1);
  EXPECT_EQ(s.blockCount(), 2u);
  s.releaseBlock(1);
  EXPECT_EQ(s.cell_block[1], -1);
  EXPECT_EQ(s.block_cell[0], -1);
  s.cell_value[0] = -400;
  EXPECT_EQ(s.allocateBlock(0), 0);  // the released slot, filled with the cell's value
  EXPECT_EQ(s.logOdds(0)[63], -400);
  EXPECT_EQ(s.blockCount(), 2u);
  EXPECT_EQ(s.slotCount(), 2u);
}

TEST(BlockStore, PoolsGrowByAQuarterPlus64) {
  BlockStore s(0.1, 4, box(0.0, 28.0, 0.4, 0.4), false);  // 70 cells
  ASSERT_EQ(s.cellCount(), 70u);
  s.allocateBlock(0);
  EXPECT_EQ(s.block_cell.capacity(), 64u);  // 0 + 0/4 + 64
  for (int c = 1; c < 65; ++c) s.allocateBlock(c);
  EXPECT_EQ(s.block_cell.capacity(), 144u);  // 64 + 16 + 64
  EXPECT_EQ(s.block_l.capacity(), 144u * 64u);
}

TEST(BlockStore, SurfaceSlotsStartUnobservedAndAreReused) {
  BlockStore s(0.1, 4, box(0.0, 1.2, 0.4, 0.4), true);
  const int b0 = s.allocateBlock(0), b1 = s.allocateBlock(1);
  EXPECT_EQ(s.ensureSurface(b0), 0);
  EXPECT_EQ(s.ensureSurface(b0), 0);  // already has one
  EXPECT_EQ(s.dist(0)[5], kNoDist);
  EXPECT_EQ(s.rgbw(0)[4 * 5 + 3], 0);
  s.dist(0)[5] = 1234;
  s.releaseSurface(b0);
  EXPECT_EQ(s.block_surf[b0], -1);
  EXPECT_EQ(s.ensureSurface(b1), 0);  // reused, and reset
  EXPECT_EQ(s.dist(0)[5], kNoDist);
}

TEST(BlockStore, SummariesAndTheirPropagation) {
  BlockStore s(0.1, 4, box(0.0, 1.2, 0.4, 0.4), false);
  const int b = s.allocateBlock(1);
  s.logOdds(b)[0] = 500;   // occupied
  s.logOdds(b)[1] = -400;  // free; the other 62 unknown
  const Summary sm = s.cellSummary(1);
  EXPECT_EQ(sm.min_l, -400);
  EXPECT_EQ(sm.max_l, 500);
  EXPECT_EQ(sm.known_any, 1);
  EXPECT_EQ(sm.unknown_any, 1);
  EXPECT_EQ(s.block_nfree[b], 1u);
  EXPECT_EQ(s.block_nocc[b], 1u);
  EXPECT_EQ(s.voxelValue(4, 0, 0), 500);  // cell 1 starts at voxel x = 4
  EXPECT_EQ(s.voxelValue(5, 0, 0), -400);
  s.cell_value[2] = -2000;  // a uniform free cell
  const Summary u = s.cellSummary(2);
  EXPECT_EQ(u.min_l, -2000);
  EXPECT_EQ(u.max_l, -2000);
  EXPECT_EQ(u.unknown_any, 0);
  s.levels[0].s[1] = sm;
  s.levels[0].s[2] = u;
  s.propagateSummaries({1, 2});
  // level 1: node 0 = cells 0 (unknown) and 1; node 1 = cell 2
  EXPECT_EQ(s.levels[1].at(0, 0, 0).min_l, -400);
  EXPECT_EQ(s.levels[1].at(0, 0, 0).unknown_any, 1);
  EXPECT_EQ(s.levels[1].at(1, 0, 0).max_l, -2000);
  EXPECT_EQ(s.levels[1].at(1, 0, 0).unknown_any, 0);
  EXPECT_EQ(s.levels[2].at(0, 0, 0).min_l, -2000);
  EXPECT_EQ(s.levels[2].at(0, 0, 0).max_l, 500);
}

TEST(BlockStore, BlockSizeOutsideTheIntegratorsBuffersIsRefused) {
  Bounds bounds;
  bounds.min_m = Eigen::Vector3d::Zero();
  bounds.max_m = Eigen::Vector3d::Constant(1.0);
  EXPECT_THROW(BlockStore(0.04, 128, bounds, false), std::invalid_argument);
  EXPECT_THROW(BlockStore(0.04, 6, bounds, false), std::invalid_argument);
  EXPECT_NO_THROW(BlockStore(0.04, 64, bounds, false));
}

// FrontierTracker on a hand-built store of three cells in a row (4^3 voxels
// each): which leaves are frontiers, counted by hand.
#include <gtest/gtest.h>

#include <vector>

#include "semantic_exploration/core/occupancy/block_store.hpp"
#include "semantic_exploration/core/occupancy/frontier_tracker.hpp"

using semexp::occupancy::BlockStore;
using semexp::occupancy::FrontierTracker;
using semexp::occupancy::kUnknown;

namespace {
BlockStore threeCells() {
  semexp::Bounds b;
  b.min_m = {0.0, 0.0, 0.0};
  b.max_m = {1.2, 0.4, 0.4};
  return BlockStore(0.1, 4, b, false);
}
void refresh(BlockStore& s, const std::vector<int>& cells) {
  for (int c : cells) s.levels[0].s[c] = s.cellSummary(c);
  s.propagateSummaries(cells);
}
}  // namespace

TEST(FrontierTracker, UniformFreeCellNextToUnknownIsOneFrontierLeaf) {
  BlockStore s = threeCells();
  FrontierTracker f;
  f.reset(s.cellCount(), s.fwords);
  s.cell_value[0] = -400;  // free; cells 1 and 2 unknown
  refresh(s, {0});
  f.markCandidate(0);
  f.update(s);
  EXPECT_EQ(f.count(), 1u);
  int n = 0;
  f.forEach(s, [&](const Eigen::Vector3d& c, double size) {
    ++n;
    EXPECT_TRUE(c.isApprox(Eigen::Vector3d(0.2, 0.2, 0.2)));  // centre of cell 0
    EXPECT_DOUBLE_EQ(size, 0.4);
  });
  EXPECT_EQ(n, 1);
}

TEST(FrontierTracker, BlockFrontierVoxelsAndWhatANeighbourLoses) {
  BlockStore s = threeCells();
  FrontierTracker f;
  f.reset(s.cellCount(), s.fwords);
  s.cell_value[0] = -400;
  refresh(s, {0});
  f.markCandidate(0);
  f.update(s);
  ASSERT_EQ(f.count(), 1u);
  // Cell 1 becomes a block of free voxels with one unknown voxel at (1,1,1).
  s.cell_value[1] = -400;
  const int b = s.allocateBlock(1);
  s.logOdds(b)[s.voxelIndex(1, 1, 1)] = kUnknown;
  refresh(s, {1});
  f.markCandidate(1);
  f.update(s);
  // In cell 1: the 6 face neighbours of (1,1,1), plus the 16 voxels of the
  // x = 3 face next to unknown cell 2 (y/z faces border the map's outside,
  // which counts as known). Cell 0 no longer touches unknown space.
  EXPECT_EQ(f.count(), 22u);
  EXPECT_TRUE(f.blockHasFrontier(1));
  EXPECT_FALSE(f.cellIsListedFrontier(0));
  std::vector<int> blocks, cells;
  f.liveLists(blocks, cells);
  EXPECT_EQ(blocks, std::vector<int>{1});
  EXPECT_TRUE(cells.empty());
  // Releasing the block drops its bits.
  f.onBlockReleased(s, 1);
  s.releaseBlock(1);
  EXPECT_EQ(f.count(), 0u);
  EXPECT_EQ(f.blockBits(b)[0], 0u);
}

TEST(FrontierTracker, RestoreRejectsAListNamingTheWrongKindOfCell) {
  BlockStore s = threeCells();
  FrontierTracker f;
  f.reset(s.cellCount(), s.fwords);
  s.allocateBlock(1);
  EXPECT_FALSE(f.restore(s, {0}, {}));  // cell 0 has no block
  f.reset(s.cellCount(), s.fwords);
  EXPECT_FALSE(f.restore(s, {}, {1}));  // cell 1 is not uniform
  f.reset(s.cellCount(), s.fwords);
  EXPECT_FALSE(f.restore(s, {}, {7}));  // outside
  f.reset(s.cellCount(), s.fwords);
  f.mutableBlockBits(s, s.cell_block[1])[0] = 0b101;
  EXPECT_TRUE(f.restore(s, {1}, {}));
  EXPECT_EQ(f.count(), 2u);
}

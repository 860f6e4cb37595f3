// GetMap snapshots: a compact snapshot sends each block whose voxels hold
// one value as that value, so a large free map resyncs in a few bytes per
// block, and decodes (OccupancyMap::applyBlocks, MapReplica) to exactly the
// map a full snapshot gives.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "semexp_test/test_grid.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"
#include "semantic_exploration/core/planning/map_replica.hpp"

namespace semexp {
namespace {

/// The table room seen from three level poses: free space (mostly uniform blocks), walls, a table, unknown beyond.
OccupancyMap tableRoomSeenFromThreePoses(const BackgroundMapConfig& cfg) {
  OccupancyMap map(cfg, semexp_test::tableRoomBounds());
  semexp_test::integrateTableRoomViews(map, 3, 0.6, 2.1);
  return map;
}

TEST(MapSnapshot, ALargeFreeMapResyncsInAFewBytesPerBlock) {
  // 50 x 50 x 10 m at 4 cm: 3.9e8 voxels in 763,000 blocks, 400 MB in full (100 x 100 x 10 m, four
  // times that, passed roscpp's 1 GB message limit).
  Bounds b;
  b.min_m = {0.0, 0.0, 0.0};
  b.max_m = {50.0, 50.0, 10.0};
  const BackgroundMapConfig cfg;  // 4 cm, 8^3 blocks
  OccupancyMap map(cfg, b);
  MapBlocksData all = map.snapshot(true);
  const Eigen::Vector3i nb = ((map.extentMax() - map.extentMin()) / 0.32).array().round().cast<int>();
  ASSERT_EQ(nb, Eigen::Vector3i(157, 157, 32));  // ceil(50 / 0.32), ceil(10 / 0.32)
  const int nx = nb.x(), ny = nb.y(), nz = nb.z();
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        all.uniform_coords.insert(all.uniform_coords.end(), {x, y, z});
        all.uniform_values.push_back(-20);  // free at the clamp
      }
  ASSERT_TRUE(map.applyBlocks(all));
  const std::size_t blocks = static_cast<std::size_t>(nx) * ny * nz;
  EXPECT_NEAR(map.freeVolume(), blocks * 0.32 * 0.32 * 0.32, 1.0);
  const MapBlocksData snap = map.snapshot(true);
  EXPECT_EQ(snap.blockCount(), 0u);
  EXPECT_EQ(snap.uniform_values.size(), blocks);
  EXPECT_EQ(snap.byteSize(), 13 * blocks);  // 12 bytes of coordinates and 1 value per block: 10 MB
  EXPECT_LT(snap.byteSize() * 39, blocks * 512);  // in full: 400 MB of payload alone
  // The replica keeps them as one value each too, and reads them back.
  MapReplica replica;
  ASSERT_EQ(replica.apply(snap), MapReplica::Result::kApplied);
  EXPECT_EQ(replica.blockCount(), blocks);
  EXPECT_EQ(replica.state({25.02, 25.02, 5.02}), MapReplica::State::kFree);
  EXPECT_TRUE(replica.sphereFree({25.0, 25.0, 5.0}, 2.0));
  EXPECT_FALSE(replica.sphereFree({25.0, 25.0, 0.1}, 0.2));  // below z = 0: unknown
}

TEST(MapSnapshot, CompactAndFullSnapshotsDecodeToTheSameMap) {
  // A room seen from three poses: free space (mostly uniform blocks), walls, a table, unknown beyond.
  const Bounds b = semexp_test::tableRoomBounds();
  const BackgroundMapConfig cfg;
  OccupancyMap map = tableRoomSeenFromThreePoses(cfg);
  map.markFreeSphere({2.5, 2.0, 1.6}, 0.6);  // a uniform free region as the start leaves it
  const MapBlocksData full = map.snapshot(false), compact = map.snapshot(true);
  ASSERT_GT(compact.uniform_values.size(), 50u);
  ASSERT_GT(compact.blockCount(), 50u);
  EXPECT_EQ(compact.blockCount() + compact.uniform_values.size(), full.blockCount());
  EXPECT_LT(compact.byteSize(), full.byteSize());
  // Decoded by a map: the same full snapshot, byte for byte.
  OccupancyMap copy(cfg, b);
  ASSERT_TRUE(copy.applyBlocks(compact));
  const MapBlocksData again = copy.snapshot(false);
  EXPECT_EQ(again.coords, full.coords);
  EXPECT_EQ(again.payload, full.payload);
  // Decoded by replicas: the same state at every voxel centre, the same sphere answers.
  MapReplica from_full, from_compact;
  ASSERT_EQ(from_full.apply(full), MapReplica::Result::kApplied);
  ASSERT_EQ(from_compact.apply(compact), MapReplica::Result::kApplied);
  int differ = 0, free = 0, occupied = 0;
  for (double z = 0.02; z < 2.4; z += 0.04)
    for (double y = 0.02; y < 4.0; y += 0.04)
      for (double x = 0.02; x < 5.0; x += 0.04) {
        const MapReplica::State s = from_full.state({x, y, z});
        differ += s != from_compact.state({x, y, z});
        free += s == MapReplica::State::kFree;
        occupied += s == MapReplica::State::kOccupied;
      }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(free, 100000);
  EXPECT_GT(occupied, 1000);
  for (double x = 0.3; x < 4.8; x += 0.1)
    for (double r : {0.1, 0.3, 0.6}) {
      const Eigen::Vector3d p(x, 2.0, 1.2);
      EXPECT_EQ(from_full.sphereFree(p, r), from_compact.sphereFree(p, r)) << x << " " << r;
      EXPECT_EQ(from_full.sphereNotOccupied(p, r), from_compact.sphereNotOccupied(p, r)) << x << " " << r;
    }
}

TEST(MapSnapshot, AMapRestoredFromThePlannersReplicaHasTheSameVoxelsAndFrontiers) {
  // background_map respawned mid-flight gets its map back from the planner's replica: map ->
  // compact snapshot -> replica -> replica snapshot -> a new map. Every voxel decodes to what the
  // map's own snapshot holds, and the new map finds the same frontier voxels.
  const Bounds b = semexp_test::tableRoomBounds();
  const BackgroundMapConfig cfg;
  OccupancyMap map = tableRoomSeenFromThreePoses(cfg);
  map.updateFrontiers();
  ASSERT_GT(map.frontierCount(), 1000u);
  MapReplica replica;
  ASSERT_EQ(replica.apply(map.snapshot(true)), MapReplica::Result::kApplied);
  const MapBlocksData from_replica = replica.snapshot();
  EXPECT_TRUE(from_replica.full);
  EXPECT_EQ(from_replica.blockCount() + from_replica.uniform_values.size(), replica.blockCount());
  OccupancyMap restored(cfg, b);
  ASSERT_TRUE(restored.applyBlocks(from_replica));
  const MapBlocksData want = map.snapshot(false), got = restored.snapshot(false);
  EXPECT_EQ(got.coords, want.coords);
  EXPECT_EQ(got.payload, want.payload);
  EXPECT_NEAR(restored.freeVolume(), map.freeVolume(), 1e-9);
  restored.updateFrontiers();
  EXPECT_EQ(restored.frontierCount(), map.frontierCount());
  // The same blocks, and no pool grown by cells allocated on the way (a uniform free cell becomes a block only
  // where it borders unknown space).
  EXPECT_EQ(restored.blockCount(), map.blockCount());
  EXPECT_LE(restored.memoryBytes(), map.memoryBytes());
  // The same replica twice gives the same bytes (blocks in key order).
  const MapBlocksData again = replica.snapshot();
  EXPECT_EQ(again.coords, from_replica.coords);
  EXPECT_EQ(again.uniform_coords, from_replica.uniform_coords);
}

TEST(MapSnapshot, FrontiersFollowBlocksWrittenOverAKnownMap) {
  // A full map overwritten by a smaller one: frontiers where the new map's known space ends, and none
  // left in the blocks that went back to unknown.
  const Bounds b = semexp_test::tableRoomBounds();
  const BackgroundMapConfig cfg;
  OccupancyMap small(cfg, b), big(cfg, b);
  small.markFreeSphere({2.5, 2.0, 1.2}, 0.5);
  big.markFreeSphere({2.5, 2.0, 1.2}, 1.0);
  small.updateFrontiers();
  big.updateFrontiers();
  ASSERT_GT(small.frontierCount(), 0u);
  ASSERT_TRUE(big.applyBlocks(small.snapshot(true)));
  big.updateFrontiers();
  EXPECT_EQ(big.frontierCount(), small.frontierCount());
}

TEST(MapSnapshot, MismatchedUniformListsAreRefused) {
  MapBlocksData m;
  m.full = true;
  m.sequence = 1;
  m.resolution_m = 0.04;
  m.block_size = 8;
  m.uniform_coords = {0, 0, 0, 1, 0, 0};
  m.uniform_values = {-20};  // two blocks, one value
  MapReplica replica;
  EXPECT_EQ(replica.apply(m), MapReplica::Result::kBadInput);
  OccupancyMap map{BackgroundMapConfig(), Bounds()};
  m.origin_m = map.extentMin();
  EXPECT_FALSE(map.applyBlocks(m));
}

}  // namespace
}  // namespace semexp

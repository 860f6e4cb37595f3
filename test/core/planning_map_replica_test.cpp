// Map replica: MapBlocks decoding, sequence handling and sphere queries
// against hand-placed voxels.
#include <gtest/gtest.h>

#include "semantic_exploration/core/planning/map_replica.hpp"

namespace semexp {
namespace {

// 8^3-voxel blocks at 0.1 m, origin at (0, 0, 0); free voxels hold
// log-odds -0.4 -> -4, occupied ones 2.0 -> 20.
struct ReplicaTest : ::testing::Test {
  std::vector<std::int32_t> coords;
  std::vector<std::uint8_t> payload;
  MapReplica::Update update(std::uint64_t seq, bool full) const {
    MapReplica::Update u;
    u.sequence = seq;
    u.full = full;
    u.resolution_m = 0.1;
    u.block_size = 8;
    u.coords = coords.data();
    u.coord_count = coords.size();
    u.payload = payload.data();
    u.payload_size = payload.size();
    return u;
  }
  void add_block(int bx, int by, int bz, std::int8_t fill) {
    coords.insert(coords.end(), {bx, by, bz});
    payload.insert(payload.end(), 512, static_cast<std::uint8_t>(fill));
  }
  void set_voxel(std::size_t block, int x, int y, int z, std::int8_t v) {
    payload[block * 512 + static_cast<std::size_t>((z * 8 + y) * 8 + x)] = static_cast<std::uint8_t>(v);
  }
};

TEST_F(ReplicaTest, SphereQueriesAndStates) {
  // Blocks (0,0,0) and (1,0,0) free; voxel (3, 4, 4) of block 0 occupied:
  // box [0.3, 0.4] x [0.4, 0.5] x [0.4, 0.5]. x >= 1.6 m is unknown (no block).
  add_block(0, 0, 0, -4);
  add_block(1, 0, 0, -4);
  set_voxel(0, 3, 4, 4, 20);
  MapReplica m;
  ASSERT_EQ(m.apply(update(1, true)), MapReplica::Result::kApplied);
  EXPECT_EQ(m.state({0.35, 0.45, 0.45}), MapReplica::State::kOccupied);
  EXPECT_EQ(m.state({0.95, 0.45, 0.45}), MapReplica::State::kFree);
  EXPECT_EQ(m.state({1.65, 0.45, 0.45}), MapReplica::State::kUnknown);
  EXPECT_EQ(m.state({-0.05, 0.45, 0.45}), MapReplica::State::kUnknown);
  // Centre (0.7, 0.45, 0.45): 0.3 m from the occupied box's face at x = 0.4.
  EXPECT_TRUE(m.sphere_free({0.7, 0.45, 0.45}, 0.25));
  EXPECT_FALSE(m.sphere_free({0.7, 0.45, 0.45}, 0.31));
  EXPECT_FALSE(m.sphere_not_occupied({0.7, 0.45, 0.45}, 0.31));
  // Near the unknown at x = 1.6: free only if the sphere stays below it.
  EXPECT_TRUE(m.sphere_free({1.4, 0.4, 0.4}, 0.19));
  EXPECT_FALSE(m.sphere_free({1.4, 0.4, 0.4}, 0.21));
  EXPECT_TRUE(m.sphere_not_occupied({1.4, 0.4, 0.4}, 0.21));  // unknown allowed
  // Below the origin (negative block coordinates): unknown.
  EXPECT_FALSE(m.sphere_free({0.3, 0.3, 0.1}, 0.15));
  // (0.3, 0.3, 0.25) is sqrt(0.1^2 + 0.15^2) = 0.180 m from the occupied box.
  EXPECT_TRUE(m.sphere_free({0.3, 0.3, 0.25}, 0.15));
  EXPECT_FALSE(m.sphere_free({0.3, 0.3, 0.25}, 0.19));
}

TEST_F(ReplicaTest, SequenceHandling) {
  add_block(0, 0, 0, -4);
  MapReplica m;
  EXPECT_EQ(m.apply(update(3, false)), MapReplica::Result::kGap);  // first update incremental, not 1
  EXPECT_TRUE(m.empty());
  EXPECT_EQ(m.apply(update(3, true)), MapReplica::Result::kApplied);
  EXPECT_EQ(m.apply(update(4, false)), MapReplica::Result::kApplied);
  EXPECT_EQ(m.apply(update(4, false)), MapReplica::Result::kStale);
  EXPECT_EQ(m.apply(update(6, false)), MapReplica::Result::kGap);
  EXPECT_EQ(m.sequence(), 4u);
  // A full map replaces everything.
  coords.clear();
  payload.clear();
  add_block(5, 5, 5, -4);
  EXPECT_EQ(m.apply(update(9, true)), MapReplica::Result::kApplied);
  EXPECT_EQ(m.block_count(), 1u);
  EXPECT_EQ(m.state({0.1, 0.1, 0.1}), MapReplica::State::kUnknown);
  EXPECT_EQ(m.state({4.05, 4.05, 4.05}), MapReplica::State::kFree);
  payload.pop_back();
  EXPECT_EQ(m.apply(update(10, false)), MapReplica::Result::kBadInput);
}

}  // namespace
}  // namespace semexp

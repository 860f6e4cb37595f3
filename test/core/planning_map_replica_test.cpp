// Map replica: MapBlocks decoding, sequence handling and sphere queries
// against hand-placed voxels.
#include <gtest/gtest.h>

#include <random>

#include <opencv2/core.hpp>

#include "semexp_test/test_grid.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"
#include "semantic_exploration/core/planning/map_replica.hpp"

namespace semexp {
namespace {

// 8^3-voxel blocks at 0.1 m, origin at (0, 0, 0); free voxels hold
// log-odds -0.4 -> -4, occupied ones 2.0 -> 20.
struct ReplicaTest : ::testing::Test {
  std::vector<std::int32_t> coords;
  std::vector<std::int8_t> payload;
  MapBlocksData update(std::uint64_t seq, bool full) const {
    MapBlocksData u;
    u.sequence = seq;
    u.full = full;
    u.resolution_m = 0.1;
    u.block_size = 8;
    u.coords = coords;
    u.payload = payload;
    return u;
  }
  void add_block(int bx, int by, int bz, std::int8_t fill) {
    coords.insert(coords.end(), {bx, by, bz});
    payload.insert(payload.end(), 512, fill);
  }
  void set_voxel(std::size_t block, int x, int y, int z, std::int8_t v) {
    payload[block * 512 + static_cast<std::size_t>((z * 8 + y) * 8 + x)] = v;
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
  EXPECT_TRUE(m.sphereFree({0.7, 0.45, 0.45}, 0.25));
  EXPECT_FALSE(m.sphereFree({0.7, 0.45, 0.45}, 0.31));
  EXPECT_FALSE(m.sphereNotOccupied({0.7, 0.45, 0.45}, 0.31));
  // Near the unknown at x = 1.6: free only if the sphere stays below it.
  EXPECT_TRUE(m.sphereFree({1.4, 0.4, 0.4}, 0.19));
  EXPECT_FALSE(m.sphereFree({1.4, 0.4, 0.4}, 0.21));
  EXPECT_TRUE(m.sphereNotOccupied({1.4, 0.4, 0.4}, 0.21));  // unknown allowed
  // Below the origin (negative block coordinates): unknown.
  EXPECT_FALSE(m.sphereFree({0.3, 0.3, 0.1}, 0.15));
  // (0.3, 0.3, 0.25) is sqrt(0.1^2 + 0.15^2) = 0.180 m from the occupied box.
  EXPECT_TRUE(m.sphereFree({0.3, 0.3, 0.25}, 0.15));
  EXPECT_FALSE(m.sphereFree({0.3, 0.3, 0.25}, 0.19));
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
  EXPECT_EQ(m.blockCount(), 1u);
  EXPECT_EQ(m.state({0.1, 0.1, 0.1}), MapReplica::State::kUnknown);
  EXPECT_EQ(m.state({4.05, 4.05, 4.05}), MapReplica::State::kFree);
  payload.pop_back();
  EXPECT_EQ(m.apply(update(10, false)), MapReplica::Result::kBadInput);
}

// The contract with the background map: a replica fed by OccupancyMap's
// incremental updates (and, after a gap, its snapshot) agrees with the map on
// voxel states and sphere queries. Frames are rendered from a box room.
TEST(ReplicaOfOccupancyMap, AgreesWithTheMap) {
  const Bounds b = semexp_test::tableRoomBounds();
  const semexp_test::TestGrid room = semexp_test::tableRoom();
  const PinholeCamera cam = semexp_test::halfSizeCamera();
  BackgroundMapConfig cfg;
  OccupancyMap map(cfg, b);
  MapReplica replica, late;
  auto frame = [&](const Eigen::Vector3d& p, double yaw) {
    const Eigen::Isometry3d T = semexp_test::levelCameraPose(p, yaw);
    map.integrate(semexp_test::renderDepth(room, cam, T), cv::Mat(), cam, T);
    return map.takeUpdate();
  };
  for (int k = 0; k < 6; ++k) {
    const MapBlocksData up = frame({1.2 + 0.3 * k, 2.0, 1.2}, 0.9 * k);
    ASSERT_EQ(replica.apply(up), MapReplica::Result::kApplied) << "update " << k;
    if (k == 0) continue;  // `late` misses the first update: gap, then the snapshot
    if (late.sequence() == 0) {
      EXPECT_EQ(late.apply(up), MapReplica::Result::kGap);
      ASSERT_EQ(late.apply(map.snapshot()), MapReplica::Result::kApplied);
    } else {
      ASSERT_EQ(late.apply(up), MapReplica::Result::kApplied);
    }
  }
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(0.0, 5.0), uy(0.0, 4.0), uz(0.0, 2.4);
  int same = 0, same_late = 0, free_agree = 0, map_free = 0, unsafe = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p(ux(rng), uy(rng), uz(rng));
    const VoxelState s = map.state(p);
    const MapReplica::State t = replica.state(p);
    same += static_cast<int>(s) == static_cast<int>(t);  // same enum order: unknown, free, occupied
    same_late += late.state(p) == t;
    const bool mf = map.isSphereFree(p, 0.125), rf = replica.sphereFree(p, 0.125);
    map_free += mf;
    free_agree += mf == rf;
    unsafe += rf && !mf;  // the replica must never call free what the map does not
  }
  EXPECT_GT(map_free, 1000);
  EXPECT_GE(same, n - n / 1000) << "voxel states agree at " << same << " of " << n << " points";
  EXPECT_EQ(same_late, n);
  EXPECT_GE(free_agree, n - n / 100);
  EXPECT_EQ(unsafe, 0);
}

// lineNotOccupied is a faster way of asking sphereNotOccupied(p, 0) at each
// point of a line: the same answer on every line, on a replica of a map with
// dense, uniform and missing blocks (a rendered room), for lines through
// free space, walls, the table and unknown space, at steps of one voxel and
// of less.
TEST(ReplicaOfOccupancyMap, LinesOfSightAgreeWithPointQueries) {
  OccupancyMap map(BackgroundMapConfig(), semexp_test::tableRoomBounds());
  semexp_test::integrateTableRoomViews(map, 6, 0.3, 0.9);
  MapReplica replica;
  ASSERT_EQ(replica.apply(map.snapshot()), MapReplica::Result::kApplied);
  const double res = replica.resolution_m();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> ux(-0.5, 5.5), uy(-0.5, 4.5), uz(-0.3, 2.7), ulen(0.0, 4.0);
  int blocked = 0, clear = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d from(ux(rng), uy(rng), uz(rng));
    const Eigen::Vector3d u = (Eigen::Vector3d(ux(rng), uy(rng), uz(rng)) - from).normalized();
    const double len = ulen(rng), step = i % 2 ? res : 0.37 * res;
    bool points = true;
    for (double t = 0.0; t <= len && points; t += step) points = replica.sphereNotOccupied(from + t * u, 0.0);
    ASSERT_EQ(replica.lineNotOccupied(from, u, len, step), points)
        << "line " << i << " from " << from.transpose() << " along " << u.transpose() << ", " << len << " m";
    (points ? clear : blocked) += 1;
  }
  // Both answers are common, so the comparison means something.
  EXPECT_GT(blocked, n / 10);
  EXPECT_GT(clear, n / 10);
  // Lines on the voxel grid's faces: vertical lines down to the floor from
  // points whose x and y are multiples of 0.2 m (each one a face of the
  // 0.04 m grid), so that points land on borders and on the floor's face.
  int face_blocked = 0;
  for (double x = 0.2; x < 4.9; x += 0.2)
    for (double y = 0.2; y < 3.9; y += 0.2) {
      const Eigen::Vector3d top(std::round(x / 0.2) * 0.2, std::round(y / 0.2) * 0.2, 2.0);
      bool points = true;
      for (double t = 0.0; t <= 2.0 && points; t += res) points = replica.sphereNotOccupied(top - t * Eigen::Vector3d::UnitZ(), 0.0);
      ASSERT_EQ(replica.lineNotOccupied(top, -Eigen::Vector3d::UnitZ(), 2.0, res), points) << top.transpose();
      face_blocked += !points;
    }
  EXPECT_GT(face_blocked, 20);  // the floor (and the table) where the frames saw them
  const Eigen::Vector3d on_face(0.0, 2.0, 1.2);
  EXPECT_THROW(replica.lineNotOccupied(on_face, Eigen::Vector3d::UnitX(), 1.0, 0.0), std::invalid_argument);
  EXPECT_TRUE(MapReplica().lineNotOccupied(on_face, Eigen::Vector3d::UnitX(), 1.0, res));  // empty: all unknown
}

}  // namespace
}  // namespace semexp

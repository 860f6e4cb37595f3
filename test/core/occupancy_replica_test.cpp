// The replica applies MapBlocks updates in order, detects a lost message,
// resyncs from a full map and then equals the source.
#include <gtest/gtest.h>

#include <random>

#include "occupancy_test_scene.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"
#include "semantic_exploration/core/occupancy_replica.hpp"

using namespace semexp;

namespace {

void expectSame(const OccupancyMap& src, const OccupancyReplica& rep) {
  const MapBlocksData a = src.snapshot(), b = rep.map().snapshot();
  ASSERT_EQ(a.coords, b.coords);
  EXPECT_TRUE(a.payload == b.payload);
  // Every voxel classifies identically.
  const double r = src.resolution();
  const Eigen::Vector3d lo = src.extentMin();
  const Eigen::Vector3i n = ((src.extentMax() - lo) / r).array().round().cast<int>();
  std::size_t diff = 0, known = 0;
  for (int z = 0; z < n.z(); ++z)
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) {
        const Eigen::Vector3d c = lo + (Eigen::Vector3d(x, y, z) + Eigen::Vector3d::Constant(0.5)) * r;
        const VoxelState s = src.state(c);
        known += s != VoxelState::kUnknown;
        diff += s != rep.state(c);
      }
  EXPECT_EQ(diff, 0u);
  EXPECT_GT(known, 10000u);
  // Same sphere and ray answers at random places.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(lo.x(), src.extentMax().x()), uy(lo.y(), src.extentMax().y()),
      uz(lo.z(), src.extentMax().z()), ur(0.05, 0.6);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d p(ux(rng), uy(rng), uz(rng));
    const double rad = ur(rng);
    EXPECT_EQ(src.isSphereFree(p, rad), rep.isSphereFree(p, rad));
    const Eigen::Vector3d d(ux(rng), uy(rng), uz(rng));
    const RaycastHit h1 = src.raycast(p, d, 6.0), h2 = rep.raycast(p, d, 6.0);
    EXPECT_EQ(h1.hit, h2.hit);
    EXPECT_NEAR(h1.distance_m, h2.distance_m, 1e-9);
  }
}

}  // namespace

TEST(OccupancyReplica, EqualsSourceAfterRandomUpdatesWithADroppedMessageAndResync) {
  const semexp_test::BoxRoom scene = semexp_test::standardRoom();
  BackgroundMapConfig cfg;
  PinholeCamera cam;
  Bounds b;
  b.min_m = scene.room.lo - Eigen::Vector3d::Constant(0.2);
  b.max_m = scene.room.hi + Eigen::Vector3d::Constant(0.2);
  OccupancyMap src(cfg, b);
  OccupancyReplica rep(cfg, b);
  EXPECT_TRUE(rep.needsResync());
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> px(-2.0, 2.0), py(-1.5, 1.8), pz(0.5, 2.0), yaw(-M_PI, M_PI), tilt(-0.3, 0.5);
  auto frame = [&] {
    const Eigen::Isometry3d T = semexp_test::lookPose({px(rng), py(rng), pz(rng)}, yaw(rng), tilt(rng));
    src.integrate(scene.render(cam, T).data(), nullptr, cam, T);
    return src.takeUpdate();
  };
  // Start from a full map (empty), then in-order updates.
  EXPECT_EQ(rep.apply(src.snapshot()), OccupancyReplica::Result::kApplied);
  EXPECT_FALSE(rep.needsResync());
  for (int i = 0; i < 3; ++i) {
    const MapBlocksData m = frame();
    EXPECT_EQ(m.sequence, static_cast<std::uint64_t>(i + 1));
    EXPECT_EQ(rep.apply(m), OccupancyReplica::Result::kApplied);
  }
  expectSame(src, rep);
  // A repeated (stale) message is ignored.
  MapBlocksData old = frame();
  EXPECT_EQ(rep.apply(old), OccupancyReplica::Result::kApplied);
  EXPECT_EQ(rep.apply(old), OccupancyReplica::Result::kStale);
  // Drop one message: the next one reports the gap.
  (void)frame();
  EXPECT_EQ(rep.apply(frame()), OccupancyReplica::Result::kGap);
  EXPECT_TRUE(rep.needsResync());
  // More frames arrive while resyncing; the full map answers with the last sequence.
  const MapBlocksData pending = frame();
  const MapBlocksData full = src.snapshot();
  EXPECT_EQ(full.sequence, pending.sequence);
  EXPECT_EQ(rep.apply(full), OccupancyReplica::Result::kApplied);
  EXPECT_FALSE(rep.needsResync());
  EXPECT_EQ(rep.apply(pending), OccupancyReplica::Result::kStale);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(rep.apply(frame()), OccupancyReplica::Result::kApplied);
  expectSame(src, rep);
}

TEST(OccupancyReplica, FullMapRebuildsAMismatchedGeometry) {
  BackgroundMapConfig cfg;
  Bounds b;
  OccupancyMap src(cfg, b);
  BackgroundMapConfig other = cfg;
  other.resolution_m = 0.1;
  OccupancyReplica rep(other, b);
  const semexp_test::BoxRoom scene = semexp_test::standardRoom();
  PinholeCamera cam;
  const Eigen::Isometry3d T = semexp_test::lookPose({0.0, 0.0, 1.2}, 0.3, 0.1);
  src.integrate(scene.render(cam, T).data(), nullptr, cam, T);
  const MapBlocksData upd = src.takeUpdate();
  EXPECT_EQ(rep.apply(upd), OccupancyReplica::Result::kGap);  // cannot place it: resync
  EXPECT_EQ(rep.apply(src.snapshot()), OccupancyReplica::Result::kApplied);
  EXPECT_NEAR(rep.map().resolution(), 0.04, 1e-12);
  EXPECT_EQ(rep.state({1.0, 0.3, 1.2}), src.state({1.0, 0.3, 1.2}));
  MapBlocksData bad = upd;
  bad.payload.pop_back();
  EXPECT_EQ(rep.apply(bad), OccupancyReplica::Result::kRejected);
}

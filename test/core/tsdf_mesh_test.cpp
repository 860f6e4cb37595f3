// What an object's mesh is extracted over (MeshGate, TsdfMapT::extractMesh):
// the minimum weight, the SDF error gate by the depth noise and the
// foreground bound, on analytic scenes and hand-made maps.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "semantic_exploration/core/tsdf.hpp"
#include "semexp_test/cameras.hpp"
#include "semexp_test/object_scenes.hpp"
#include "semexp_test/rendering.hpp"

using namespace semexp;
using namespace semexp_test;

namespace {

TsdfParams params() { return objectTsdfParams(); }

// object_map/mesh_min_weight on a wall seen 3 times from one pose, exact depth: each view adds weight 1 to
// every voxel from the truncation in front of the wall to one voxel behind it (deeper voxels get less, falling
// to 0 at behind_surface_m). The cubes the surface crosses reach slightly more than one voxel behind where
// rays run oblique, so their voxels gain between 5/6 and 1 per view: after 3 views a minimum of 2.5 keeps the
// whole mesh (so does 2) and 3.5 leaves nothing; a fourth view brings it back at 3.5, and 4
// meshes all of it from the fifth view (5 x 5/6 > 4).
TEST(TsdfMesh, MeshLeavesOutCubesBelowTheMinimumWeight) {
  const WallAhead view;
  TsdfMap map(params());
  for (int k = 0; k < 3; ++k) view.into(map, 255, true);
  const std::size_t all = map.extractMesh().triangles.size();
  ASSERT_GT(all, 20u);
  EXPECT_EQ(map.extractMesh(2.5f).triangles.size(), all);
  EXPECT_EQ(map.extractMesh(2.f).triangles.size(), all);
  EXPECT_TRUE(map.extractMesh(3.5f).empty());
  view.into(map, 255, true);
  EXPECT_EQ(map.extractMesh().triangles.size(), all);
  EXPECT_EQ(map.extractMesh(3.5f).triangles.size(), all);
  EXPECT_TRUE(map.extractMesh(4.5f).empty());
  view.into(map, 255, true);
  EXPECT_EQ(map.extractMesh(4.f).triangles.size(), all);
}

// The depth noise model of Table I: sigma(d) = max(sigma_min, min(s d^2, sigma_max)).
TEST(TsdfMesh, DepthNoiseFollowsTableI) {
  const semexp::DepthNoise n;  // 0.005 m, 0.002 1/m, 0.2 m
  EXPECT_DOUBLE_EQ(n.sigma(0.5), 0.005);   // s d^2 = 0.0005: the floor
  EXPECT_DOUBLE_EQ(n.sigma(2.0), 0.008);   // 0.002 * 4
  EXPECT_DOUBLE_EQ(n.sigma(3.0), 0.018);   // 0.002 * 9
  EXPECT_DOUBLE_EQ(n.sigma(20.0), 0.2);    // 0.8, capped
  EXPECT_DOUBLE_EQ(n.sigma(std::numeric_limits<double>::infinity()), 0.2);  // never observed: the cap
}

// MeshGate::passes, hand-computed: a voxel passes max_sdf_std_m = e when w >= (sigma(d) / e)^2.
TEST(TsdfMesh, MeshGateAsksWeightByTheNoiseOfTheNearestView) {
  semexp::MeshGate g;  // off: every observed voxel
  EXPECT_TRUE(g.passes(0.0625f, 3.0f));
  EXPECT_FALSE(g.passes(0.f, 1.0f));
  g.min_weight = 2.f;
  EXPECT_FALSE(g.passes(1.9375f, 1.0f));
  EXPECT_TRUE(g.passes(2.f, 1.0f));
  g.min_weight = 0.f;
  g.max_sdf_std_m = 0.005;
  // From 1.2 m the noise is the floor, 5 mm: w >= 1, one full view, passes on the bound.
  EXPECT_TRUE(g.passes(1.f, 1.2f));
  EXPECT_FALSE(g.passes(0.9375f, 1.2f));
  // Seen from 2 m at best: sigma 8 mm needs w >= (8 / 5)^2 = 2.56.
  EXPECT_FALSE(g.passes(2.5f, 2.0f));
  EXPECT_TRUE(g.passes(2.5625f, 2.0f));
  // From 3 m: sigma 18 mm needs w >= 12.96.
  EXPECT_FALSE(g.passes(12.9375f, 3.0f));
  EXPECT_TRUE(g.passes(13.f, 3.0f));
  EXPECT_FALSE(g.passes(50.f, std::numeric_limits<float>::infinity()));  // sigma_max, 0.2 m: needs w >= 1600
  // A sensor twice as noisy needs four times the weight: at the floor w >= 4, from 2 m w >= 10.24.
  g.noise.sigma_min_m = 0.01;
  g.noise.s_per_m = 0.004;
  EXPECT_TRUE(g.passes(4.f, 1.0f));
  EXPECT_FALSE(g.passes(3.9375f, 1.0f));
  EXPECT_FALSE(g.passes(10.1875f, 2.0f));
  EXPECT_TRUE(g.passes(10.25f, 2.0f));
}

// The gate on the wall of MeshLeavesOutCubesBelowTheMinimumWeight, seen from about 1 m, where the noise is
// the floor sigma_min for every voxel (s d^2 < sigma_min up to 1.58 m): the surface's cubes hold between 5/6
// and 1 per view (13/16 with the weight's 1/16 steps). After 3 views (w >= 2.4375) a gate asking w >= 2.4
// keeps the whole mesh and one asking w >= 3.2 leaves nothing; with the noise doubled the first asks
// w >= 9.6: nothing after 9 views (w <= 9), all of it after 12 (w >= 9.75).
TEST(TsdfMesh, MeshGateAsksFourTimesTheViewsOfASensorTwiceAsNoisy) {
  const WallAhead view;
  TsdfMap map(params());
  for (int k = 0; k < 3; ++k) view.into(map, 255, true);
  const std::size_t all = map.extractMesh().triangles.size();
  ASSERT_GT(all, 20u);
  semexp::MeshGate g;
  g.max_sdf_std_m = 0.005 / std::sqrt(2.4);
  EXPECT_EQ(map.extractMesh(g).triangles.size(), all);
  semexp::MeshGate tight = g;
  tight.max_sdf_std_m = 0.005 / std::sqrt(3.2);
  EXPECT_TRUE(map.extractMesh(tight).empty());
  semexp::MeshGate noisy = g;
  noisy.noise.sigma_min_m = 0.01;
  noisy.noise.s_per_m = 0.004;
  EXPECT_TRUE(map.extractMesh(noisy).empty());
  for (int k = 3; k < 9; ++k) view.into(map, 255, true);
  EXPECT_TRUE(map.extractMesh(noisy).empty());
  EXPECT_EQ(map.extractMesh(g).triangles.size(), all);
  for (int k = 9; k < 12; ++k) view.into(map, 255, true);
  EXPECT_EQ(map.extractMesh(noisy).triangles.size(), all);
}

// The gate reads each voxel's nearest observation distance: the same three views of a wall 3 m away (voxels
// seen from 3 to 3.7 m, sigma = s d^2 >= 18 mm, needing w >= 12.96 at e = 5 mm) leave nothing, where the
// wall 1 m away (w >= 1 needed) keeps its whole mesh; with a noise model flat at the floor (s = 0) the far
// wall keeps all of it too.
TEST(TsdfMesh, MeshGateAsksMoreOfASurfaceSeenOnlyFromFar) {
  const WallAhead near_view(1.0), far_view(3.0);
  TsdfMap near_map(params()), far_map(params());
  for (int k = 0; k < 3; ++k) {
    near_view.into(near_map, 255, true);
    far_view.into(far_map, 255, true);
  }
  const std::size_t near_all = near_map.extractMesh().triangles.size(), far_all = far_map.extractMesh().triangles.size();
  ASSERT_GT(near_all, 20u);
  ASSERT_GT(far_all, 20u);
  semexp::MeshGate g;
  g.max_sdf_std_m = 0.005;
  EXPECT_EQ(near_map.extractMesh(g).triangles.size(), near_all);
  EXPECT_TRUE(far_map.extractMesh(g).empty());
  semexp::MeshGate flat = g;
  flat.noise.s_per_m = 0.0;
  EXPECT_EQ(far_map.extractMesh(flat).triangles.size(), far_all);
}

// The mesh's foreground bound (MeshGate::min_foreground) on a hand-made map: one 8^3 block holding a
// horizontal plane between voxel layers z 3 and 4 (sdf (z + 0.5 - 4) voxels), foreground 140/254 = 0.551 for
// x < 4 and 203/254 = 0.799 for x >= 4, weight 1. The cubes inside the block are x, y in 0-6 (x 7 needs the
// absent +x block), 49 of them cross the plane, 2 triangles each; their mean foreground is 0.551 for x 0-2,
// 0.675 for x 3 (four voxels of each) and 0.799 for x 4-6.
TEST(TsdfMesh, TheMeshKeepsCubesOverTheForegroundBound) {
  const TsdfParams params = objectTsdfParams();
  TsdfMap map(params);
  TsdfMap::SavedBlock block;
  block.index = Eigen::Vector3i::Zero();
  block.voxels.resize(512);
  block.has_negative = true;
  for (int z = 0, i = 0; z < 8; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x, ++i) {
        TsdfVoxel& v = block.voxels[i];
        v.setSdf((z + 0.5f - 4.f) * static_cast<float>(params.resolution_m), static_cast<float>(params.truncation_m));
        v.setWeight(1.f);
        v.foreground_q = x < 4 ? 140 : 203;
      }
  map.loadBlocks({block});
  const auto triangles = [&](float min_foreground) {
    MeshGate gate;
    gate.min_foreground = min_foreground;
    return map.extractMesh(gate).triangles.size();
  };
  EXPECT_EQ(map.extractMesh().triangles.size(), 98u);  // the paper's 0.5: 7 x 7 cubes
  EXPECT_EQ(triangles(0.5f), 98u);
  EXPECT_EQ(triangles(0.55f), 98u);   // 0.551 > 0.55
  EXPECT_EQ(triangles(0.56f), 56u);   // x 3-6
  EXPECT_EQ(triangles(0.7f), 42u);    // x 4-6
  EXPECT_EQ(triangles(0.8f), 0u);     // 0.799 is not over 0.8
  // Every vertex lies on the plane z = 4 voxels.
  for (const auto& p : map.extractMesh().vertices_W) EXPECT_NEAR(p.z(), 4 * params.resolution_m, 1e-6);
}

}  // namespace

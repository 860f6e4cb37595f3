// ObjectSummaryCache: after every frame of two objects being found, seen,
// seen past each other, merged and dropped, each cached summary equals a fresh
// ObjectMap::summarize, and objects not integrated in a frame are not
// summarised again.
#include <gtest/gtest.h>

#include "semantic_exploration/core/object_summary_cache.hpp"
#include "semexp_test/cameras.hpp"
#include "semexp_test/object_scenes.hpp"
#include "semexp_test/rendering.hpp"

using namespace semexp;
using namespace semexp_test;

namespace {

constexpr double kDObj = 1.0;  // m

void expectSameSummary(const TsdfSummary& a, const TsdfSummary& b) {
  EXPECT_EQ(a.voxel_count, b.voxel_count);
  EXPECT_EQ(a.observed_fraction, b.observed_fraction);
  EXPECT_EQ(a.weight_sum, b.weight_sum);
  EXPECT_EQ(a.bbox_min_W, b.bbox_min_W);
  EXPECT_EQ(a.bbox_max_W, b.bbox_max_W);
  EXPECT_EQ(a.centroid_W, b.centroid_W);
}

// Every object's cached summary against a fresh one, as the node publishes them after a frame.
void checkAll(ObjectSummaryCache& cache, const ObjectMap& map) {
  cache.prune(map);
  for (const auto& kv : map.objects()) {
    SCOPED_TRACE(kv.first);
    expectSameSummary(cache.get(map, *kv.second), map.summarize(*kv.second, kDObj));
  }
  EXPECT_EQ(cache.size(), map.objects().size());
}

}  // namespace

TEST(ObjectSummaryCache, EqualsAFreshSummaryAfterEveryFrame) {
  // Two chairs (class 1 of the default table), 1.6 m apart: a ring of views 0.7 m around one misses the other.
  const Sphere kA(Eigen::Vector3d(0.0, 0.0, 1.0), 0.25), kB(Eigen::Vector3d(0.0, 1.6, 1.0), 0.2);
  const int kChair = 1;
  PinholeCamera cam;
  ObjectMap map(objectMapConfigWithPrior(), ClassTable());
  ObjectSummaryCache cache(kDObj);
  cv::Mat depth, labels;
  std::size_t frames = 0;
  // A and B found and seen all round, each from a ring of its own (the other out of view).
  for (int k = 0; k < 2; ++k) {
    const Sphere& s = k == 0 ? kA : kB;
    bool first = true;
    for (const auto& T_WC : ring(s.centre, 0.7, 0.3, 8)) {
      renderShapes(cam, T_WC, {&s}, depth, labels);
      const std::uint32_t id = first ? 0u : static_cast<std::uint32_t>(k + 1);
      map.integrateFrame(cam, T_WC, depth, cv::Mat(), labels, {{1, id, kChair}});
      first = false;
      ++frames;
      checkAll(cache, map);
    }
  }
  ASSERT_EQ(map.objects().size(), 2u);
  // At most one summary per object and frame; fewer, since each ring keeps the other object out of view
  // (A is not integrated during B's ring, 8 frames).
  EXPECT_LE(cache.computed(), 2 * frames - 8);
  // A piece of A detected as a new object, then tracked as that object until it is merged into A.
  const auto poses = ring(kA.centre, 0.7, 0.0, 6);
  const std::size_t before = map.objects().size();
  bool merged = false;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    renderShapes(cam, poses[i], {&kA}, depth, labels);
    const std::uint32_t id = i == 0 ? 0u : static_cast<std::uint32_t>(before + 1);
    const FrameIntegration r = map.integrateFrame(cam, poses[i], depth, cv::Mat(), labels, {{1, id, kChair}});
    merged = merged || !r.merged.empty();
    checkAll(cache, map);
  }
  EXPECT_TRUE(merged);
  EXPECT_EQ(cache.size(), map.objects().size());
}

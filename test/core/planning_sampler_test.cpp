// Candidate sampling: P_fr over many draws (fixed seed), without replacement,
// source fallback, object view points.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "semantic_exploration/core/planning/sampler.hpp"

namespace semexp {
namespace {

struct SamplerTest : ::testing::Test {
  PlannerConfig planner;
  ExplorationConfig exploration;
  Bounds bounds;
  std::vector<Eigen::Vector3d> frontiers;
  std::vector<ObjectSummary> objects;
  SamplerTest() {
    for (int i = 0; i < 400; ++i) frontiers.emplace_back(-5.0 + 0.025 * i, 1.0, 1.0);
    for (int i = 0; i < 400; ++i) {
      ObjectSummary o;
      o.id = static_cast<std::uint32_t>(i + 1);
      o.centroid_W = {-5.0 + 0.025 * i, -3.0, 0.5};
      o.bbox_min_W = o.centroid_W - Eigen::Vector3d(0.25, 0.25, 0.5);
      o.bbox_max_W = o.centroid_W + Eigen::Vector3d(0.25, 0.25, 0.5);
      objects.push_back(o);
    }
  }
  // Centroid (0, 0, 0.5), box +-0.25 m wide, 0-1 m high.
  static ObjectSummary unitBoxObject(std::uint32_t id) {
    ObjectSummary o;
    o.id = id;
    o.centroid_W = {0, 0, 0.5};
    o.bbox_min_W = {-0.25, -0.25, 0.0};
    o.bbox_max_W = {0.25, 0.25, 1.0};
    return o;
  }
  // Horizontal distance of unitBoxObject's view point in the direction of q from the centroid: the box is square,
  // so a direction leaving through a side face does so 0.25 / max(|cos|, |sin|) from it, plus the 0.5 m standoff.
  static double ringRadius(const Eigen::Vector3d& q) {
    const double yaw = std::atan2(q.y(), q.x());
    return 0.25 / std::max(std::abs(std::cos(yaw)), std::abs(std::sin(yaw))) + 0.5;
  }
  static int count_frontier(const std::vector<CandidateSample>& s) {
    int n = 0;
    for (const auto& c : s) n += c.source == CandidateSource::kFrontier;
    return n;
  }
};

// Both sources are far from exhausted, so every draw is a Bernoulli(P_fr)
// trial: over N draws the frontier share must lie within 4 standard
// deviations sqrt(P (1 - P) / N) of P_fr.
TEST_F(SamplerTest, FrontierProbabilityRespected) {
  for (double p : {0.5, 0.2, 0.8}) {
    planner.p_frontier = p;
    planner.n_candidates = 20;
    CandidateSampler sampler(planner, exploration, bounds);
    int fr = 0, total = 0;
    for (int it = 0; it < 1000; ++it) {
      const auto s = sampler.sample(frontiers, objects, {});
      ASSERT_EQ(s.size(), 20u);
      fr += count_frontier(s);
      total += static_cast<int>(s.size());
    }
    const double share = static_cast<double>(fr) / total;
    EXPECT_NEAR(share, p, 4.0 * std::sqrt(p * (1 - p) / total)) << "P_fr = " << p;
  }
}

TEST_F(SamplerTest, FixedSeedIsReproducible) {
  CandidateSampler a(planner, exploration, bounds), b(planner, exploration, bounds);
  for (int it = 0; it < 5; ++it) {
    const auto sa = a.sample(frontiers, objects, {});
    const auto sb = b.sample(frontiers, objects, {});
    ASSERT_EQ(sa.size(), sb.size());
    for (std::size_t i = 0; i < sa.size(); ++i) EXPECT_TRUE(sa[i].position_W == sb[i].position_W);
  }
}

TEST_F(SamplerTest, WithoutReplacementAndFallback) {
  // 3 frontiers, 2 unobserved objects, 1 observed object, n = 20: all five
  // usable ones exactly once, whatever P_fr.
  std::vector<Eigen::Vector3d> f = {{0, 0, 1}, {1, 0, 1}, {2, 0, 1}};
  std::vector<ObjectSummary> o(objects.begin(), objects.begin() + 3);
  o[1].observed_fraction = 0.95;  // >= object_observed_fraction 0.9: done
  planner.p_frontier = 0.5;
  CandidateSampler sampler(planner, exploration, bounds);
  const auto s = sampler.sample(f, o, {});
  ASSERT_EQ(s.size(), 5u);
  std::set<double> fx;
  std::set<std::uint32_t> ids;
  for (const auto& c : s) {
    if (c.source == CandidateSource::kFrontier)
      fx.insert(c.position_W.x());
    else
      ids.insert(c.object_id);
  }
  EXPECT_EQ(fx, (std::set<double>{0.0, 1.0, 2.0}));
  EXPECT_EQ(ids, (std::set<std::uint32_t>{o[0].id, o[2].id}));
}

TEST_F(SamplerTest, ClassicModeNeverSamplesObjects) {
  planner.p_frontier = 1.0;
  planner.a_ent = 1.0;
  planner.a_bg = planner.a_obj = 0.0;
  CandidateSampler sampler(planner, exploration, bounds);
  EXPECT_EQ(count_frontier(sampler.sample(frontiers, objects, {})), 20);
  EXPECT_TRUE(sampler.sample({}, objects, {}).empty());
  planner.p_frontier = 0.0;
  CandidateSampler objects_only(planner, exploration, bounds);
  EXPECT_EQ(count_frontier(objects_only.sample(frontiers, objects, {})), 0);
}

// Object (centroid (0, 0, 0.5), box +-0.25 m): looking from +x the box is
// left at x = 0.25, plus the standoff 0.5 * d_obj = 0.5 m -> (0.75, 0, 0.5).
// Diagonal (45 deg): the ray leaves through the corner at 0.25 sqrt(2).
TEST_F(SamplerTest, ObjectViewPoints) {
  CandidateSampler sampler(planner, exploration, bounds);
  const ObjectSummary o = unitBoxObject(7);
  EXPECT_TRUE(sampler.objectViewPoint(o, 0.0).isApprox(Eigen::Vector3d(0.75, 0.0, 0.5)));
  const double d = 0.25 * std::sqrt(2.0) + 0.5;
  EXPECT_TRUE(sampler.objectViewPoint(o, M_PI / 4).isApprox(Eigen::Vector3d(d / std::sqrt(2.0), d / std::sqrt(2.0), 0.5)));
  // Only x < 0 is free: the sampler must pick a view point there.
  CollisionQuery left_free = [](const Eigen::Vector3d& p, double r) { return p.x() + r < 0.0; };
  double z_lo = 1e9, z_hi = -1e9;
  for (int it = 0; it < 20; ++it) {
    const auto s = sampler.sample({}, {o}, left_free);
    ASSERT_EQ(s.size(), 1u);
    EXPECT_EQ(s[0].object_id, 7u);
    EXPECT_TRUE(left_free(s[0].position_W, planner.mav_radius_m)) << s[0].position_W.transpose();
    // On the ring round the box, between two clearance radii above the box bottom (2 x (0.125 + 0.04) m) and
    // the box top.
    const Eigen::Vector3d q = s[0].position_W;
    EXPECT_NEAR(std::hypot(q.x(), q.y()), ringRadius(q), 1e-9) << q.transpose();
    EXPECT_GE(q.z(), 2.0 * planner.clearance_radius_m());
    EXPECT_LE(q.z(), 1.0);
    z_lo = std::min(z_lo, q.z());
    z_hi = std::max(z_hi, q.z());
  }
  // Heights spread over the box, below the centroid too (legs under a seat need a low camera).
  EXPECT_LT(z_lo, 0.45);
  EXPECT_GT(z_hi, 0.7);
}

// The ring: 8 view points 45 deg apart from a random start, each where its
// direction leaves the box plus the 0.5 m standoff, heights as for sample();
// points whose clearance sphere is not free are left out.
TEST_F(SamplerTest, ObjectViewRing) {
  planner.object_view_samples = 8;
  CandidateSampler sampler(planner, exploration, bounds);
  const ObjectSummary o = unitBoxObject(3);
  const auto ring = sampler.objectViewRing(o, {});
  ASSERT_EQ(ring.size(), 8u);
  std::vector<double> yaws;
  for (const auto& q : ring) {
    yaws.push_back(std::atan2(q.y(), q.x()));
    EXPECT_NEAR(std::hypot(q.x(), q.y()), ringRadius(q), 1e-9) << q.transpose();
    EXPECT_GE(q.z(), 2.0 * planner.clearance_radius_m());
    EXPECT_LE(q.z(), 1.0);
  }
  for (std::size_t k = 1; k < yaws.size(); ++k)
    EXPECT_NEAR(std::remainder(yaws[k] - yaws[k - 1], 2.0 * M_PI), M_PI / 4, 1e-9);
  // Only x < -r free (r = 0.165 m, the clearance radius): the points on the other side are left out.
  CollisionQuery left_free = [](const Eigen::Vector3d& p, double r) { return p.x() + r < 0.0; };
  const auto left = sampler.objectViewRing(o, left_free);
  EXPECT_GE(left.size(), 3u);
  EXPECT_LE(left.size(), 4u);
  for (const auto& q : left) EXPECT_TRUE(left_free(q, planner.clearance_radius_m())) << q.transpose();
}

}  // namespace
}  // namespace semexp

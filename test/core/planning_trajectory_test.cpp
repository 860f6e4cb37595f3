// Time parameterisation of the winning path (trajectory.hpp): hand-computed
// durations of trapezoid and triangle profiles, limits at every sample
// (checked on finite differences of the positions, not only on the reported
// velocities), exact start and end, and yaw continuity across +-pi.
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

#include "semantic_exploration/core/planning/candidate_evaluation.hpp"
#include "semantic_exploration/core/planning/trajectory.hpp"

using semexp::SampledTrajectory;
using Samples = std::vector<semexp::SampledTrajectory::Sample>;
using semexp::Trajectory;
using semexp::TrajectoryConfig;

namespace {

constexpr double kV = 1.5, kOmega = 0.75;  // the planner's Table I limits
TrajectoryConfig limits(double a = 1.0, double alpha = 1.0) {
  TrajectoryConfig c;
  c.a_max_mps2 = a;
  c.alpha_max_radps2 = alpha;
  return c;
}

// Every limit on finite differences of samples `dt` apart (a difference
// quotient of a function never exceeds the bound of its derivative; the mean
// velocities of two neighbouring intervals lie half their lengths apart).
void expectWithinLimits(const Trajectory& tr, double dt, const TrajectoryConfig& c) {
  const double eps = 1e-9;
  semexp::TrajectoryState prev = tr.at(0.0);
  Eigen::Vector3d prev_v = (tr.at(dt).position_W - prev.position_W) / dt;
  double prev_h = dt;
  for (double t = dt; t <= tr.duration_s() + dt; t += dt) {
    const auto s = tr.at(t);
    const double h = s.t_s - prev.t_s;
    if (h <= 0) break;
    const Eigen::Vector3d v = (s.position_W - prev.position_W) / h;
    ASSERT_LE(v.norm(), kV + eps) << "speed at t = " << t;
    ASSERT_LE(std::abs(s.yaw_rad - prev.yaw_rad) / h, kOmega + eps) << "yaw rate at t = " << t;
    // The reported derivatives too.
    ASSERT_LE(s.velocity_W.norm(), kV + eps) << t;
    ASSERT_LE(s.acceleration_W.norm(), c.a_max_mps2 + eps) << t;
    ASSERT_LE(std::abs(s.yaw_rate_radps), kOmega + eps) << t;
    ASSERT_LE((v - prev_v).norm() / (0.5 * (h + prev_h)), c.a_max_mps2 + 1e-6) << "acceleration at t = " << t;
    prev_v = v;
    prev_h = h;
    prev = s;
  }
}

}  // namespace

TEST(Trajectory, StraightSegmentIsATrapezoidOfHandComputedDuration) {
  // 6 m at v 1.5, a 1: 1.5 s up (1.125 m), 3.75 m at 1.5 m/s (2.5 s), 1.5 s down: 5.5 s.
  const Trajectory tr({{0, 0, 1}, {6, 0, 1}}, {0.0, 0.0}, kV, kOmega, limits());
  EXPECT_NEAR(tr.duration_s(), 5.5, 1e-12);
  EXPECT_NEAR(tr.at(1.5).position_W.x(), 1.125, 1e-12);
  EXPECT_NEAR(tr.at(1.5).velocity_W.x(), 1.5, 1e-12);
  EXPECT_NEAR(tr.at(0.5).acceleration_W.x(), 1.0, 1e-12);
  EXPECT_NEAR(tr.at(2.75).position_W.x(), 3.0, 1e-12);   // the middle at half time
  EXPECT_NEAR(tr.at(2.75).acceleration_W.x(), 0.0, 1e-12);
  EXPECT_NEAR(tr.at(5.0).position_W.x(), 6.0 - 0.125, 1e-12);  // 0.5 s before the end: 0.5 a 0.5^2 left
  EXPECT_NEAR(tr.at(5.0).acceleration_W.x(), -1.0, 1e-12);
  EXPECT_NEAR(semexp::trapezoidDuration_s(6.0, 1.5, 1.0), 5.5, 1e-12);
}

TEST(Trajectory, ShortSegmentIsATriangleOfHandComputedDuration) {
  // 1 m at a 1 cannot reach 1.5 m/s (needs 2.25 m): 2 sqrt(1 / 1) = 2 s, peak 1 m/s at 0.5 m.
  const Trajectory tr({{0, 0, 1}, {0, 1, 1}}, {0.0, 0.0}, kV, kOmega, limits());
  EXPECT_NEAR(tr.duration_s(), 2.0, 1e-12);
  EXPECT_NEAR(tr.at(1.0).position_W.y(), 0.5, 1e-12);
  EXPECT_NEAR(tr.at(1.0).velocity_W.norm(), 1.0, 1e-12);
  EXPECT_NEAR(tr.at(0.5).position_W.y(), 0.125, 1e-12);
  // A stronger acceleration limit makes it shorter: a 2 -> 2 sqrt(1 / 2) s, still a triangle (needs 1.125 m);
  // a 4 reaches cruise in 0.28 m: 1 / 1.5 + 1.5 / 4 s.
  EXPECT_NEAR(Trajectory({{0, 0, 1}, {0, 1, 1}}, {0.0, 0.0}, kV, kOmega, limits(2.0)).duration_s(), std::sqrt(2.0),
              1e-12);
  EXPECT_NEAR(Trajectory({{0, 0, 1}, {0, 1, 1}}, {0.0, 0.0}, kV, kOmega, limits(4.0)).duration_s(),
              1.0 / 1.5 + 1.5 / 4.0, 1e-12);
}

TEST(Trajectory, TurnOnTheSpotAndCombinedMotionUseTheTighterLimit) {
  // pi/2 on the spot at omega 0.75, alpha 1: cruise reached (0.5625 rad of ramps < pi/2):
  // pi/2 / 0.75 + 0.75 / 1 s.
  const Trajectory turn({{1, 1, 1}, {1, 1, 1}}, {0.0, M_PI / 2}, kV, kOmega, limits());
  EXPECT_NEAR(turn.duration_s(), M_PI / 2 / 0.75 + 0.75, 1e-12);
  EXPECT_TRUE(turn.at(1.0).velocity_W.isZero());
  // 1 m while turning 1.5 rad: the yaw limits are tighter (progress rate min(1.5, 0.5) = 0.5 1/s,
  // acceleration min(1, 1/1.5) 1/s^2): 1 / 0.5 + 0.5 / (2/3) = 2.75 s.
  const Trajectory both({{0, 0, 1}, {1, 0, 1}}, {0.0, 1.5}, kV, kOmega, limits());
  EXPECT_NEAR(both.duration_s(), 2.75, 1e-12);
  // Position and yaw progress together: half way in both at half time.
  EXPECT_NEAR(both.at(1.375).position_W.x(), 0.5, 1e-12);
  EXPECT_NEAR(both.at(1.375).yaw_rad, 0.75, 1e-12);
}

TEST(Trajectory, LimitsHoldAtEverySampleAndNoFasterThanThePlannersEstimate) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-4.0, 4.0), yaw(-M_PI, M_PI);
  for (int run = 0; run < 20; ++run) {
    const TrajectoryConfig c = limits(0.5 + 0.1 * run, 0.3 + 0.2 * run);
    std::vector<Eigen::Vector3d> path;
    std::vector<double> yaws;
    for (int k = 0; k < 2 + run % 6; ++k) {
      path.emplace_back(pos(rng), pos(rng), 1.0 + 0.1 * pos(rng));
      yaws.push_back(yaw(rng));
    }
    if (run % 3 == 0) path.push_back(path.back()), yaws.push_back(yaws.back());  // a repeated vertex
    const Trajectory tr(path, yaws, kV, kOmega, c);
    expectWithinLimits(tr, 0.01, c);
    // Never faster than the utility's t = max(length / v_max, |dyaw| / omega_max) per segment.
    double t_min = 0;
    for (std::size_t i = 0; i + 1 < path.size(); ++i)
      t_min += semexp::pathTime_s({path[i], path[i + 1]}, yaws[i], yaws[i + 1], kV, kOmega);
    EXPECT_GE(tr.duration_s(), t_min - 1e-9) << "run " << run;
  }
}

TEST(Trajectory, StartsAndEndsExactlyAtRest) {
  const std::vector<Eigen::Vector3d> path{{0.3, -1.2, 1.1}, {2.0, 0.5, 1.4}, {2.5, 2.5, 1.0}};
  const std::vector<double> yaws{0.4, -2.9, 3.0};
  const Trajectory tr(path, yaws, kV, kOmega, limits());
  const auto s = tr.sample(0.1);
  ASSERT_GE(s.size(), 2u);
  EXPECT_EQ(s.front().t_s, 0.0);
  EXPECT_EQ(s.front().position_W, path.front());
  EXPECT_EQ(s.front().yaw_rad, yaws.front());
  EXPECT_TRUE(s.front().velocity_W.isZero());
  EXPECT_EQ(s.back().t_s, tr.duration_s());
  EXPECT_EQ(s.back().position_W, path.back());
  EXPECT_NEAR(std::remainder(s.back().yaw_rad - yaws.back(), 2 * M_PI), 0.0, 1e-12);
  EXPECT_TRUE(s.back().velocity_W.isZero());
  EXPECT_EQ(s.back().yaw_rate_radps, 0.0);
  for (std::size_t i = 1; i + 1 < s.size(); ++i) EXPECT_NEAR(s[i].t_s - s[i - 1].t_s, 0.1, 1e-9);
  EXPECT_LE(s.back().t_s - s[s.size() - 2].t_s, 0.1 + 1e-9);
  // Past the end (and before the start) it holds the end (start).
  EXPECT_EQ(tr.at(tr.duration_s() + 5).position_W, path.back());
  EXPECT_EQ(tr.at(-1).position_W, path.front());
  // The middle vertex is passed at rest.
  double closest = 1e9;
  for (const auto& x : tr.sample(0.001)) closest = std::min(closest, (x.position_W - path[1]).norm());
  EXPECT_LT(closest, 1e-5);
}

TEST(Trajectory, YawTurnsTheShortWayAcrossPlusMinusPiWithoutAJump) {
  // 3.0 -> -3.0 rad is +0.283 rad through pi, not -6.0 rad the long way.
  const Trajectory tr({{0, 0, 1}, {1, 0, 1}}, {3.0, -3.0}, kV, kOmega, limits());
  const double turn = 2 * M_PI - 6.0;
  const auto s = tr.sample(0.01);
  for (std::size_t i = 1; i < s.size(); ++i) {
    const double dy = s[i].yaw_rad - s[i - 1].yaw_rad;
    EXPECT_GE(dy, -1e-12) << "yaw went backwards at t = " << s[i].t_s;
    EXPECT_LE(dy, kOmega * (s[i].t_s - s[i - 1].t_s) + 1e-12) << "yaw jumped at t = " << s[i].t_s;
  }
  EXPECT_NEAR(s.back().yaw_rad, 3.0 + turn, 1e-12);  // continuous: just past pi, not wrapped to -3
  EXPECT_NEAR(std::remainder(s.back().yaw_rad, 2 * M_PI), -3.0, 1e-12);
  // The duration is the translation's (1 m triangle, 2 s): the yaw turn is small.
  EXPECT_NEAR(tr.duration_s(), 2.0, 1e-12);
}

TEST(Trajectory, RefusesBadInput) {
  EXPECT_THROW(Trajectory({}, {}, kV, kOmega, limits()), std::invalid_argument);
  EXPECT_THROW(Trajectory({{0, 0, 0}}, {0.0, 1.0}, kV, kOmega, limits()), std::invalid_argument);
  EXPECT_THROW(Trajectory({{0, 0, 0}, {NAN, 0, 0}}, {0.0, 1.0}, kV, kOmega, limits()), std::invalid_argument);
  EXPECT_THROW(Trajectory({{0, 0, 0}, {1, 0, 0}}, {0.0, 1.0}, kV, 0.0, limits()), std::invalid_argument);
  // A single vertex is a trajectory of duration 0 at that pose.
  const Trajectory one({{1, 2, 3}}, {0.5}, kV, kOmega, limits());
  EXPECT_EQ(one.duration_s(), 0.0);
  ASSERT_EQ(one.sample(0.1).size(), 1u);
  EXPECT_EQ(one.sample(0.1)[0].position_W, Eigen::Vector3d(1, 2, 3));
}

TEST(TrajectoryConfig, ValidateNamesTheParameter) {
  TrajectoryConfig c;
  EXPECT_NO_THROW(c.validate());
  c.a_max_mps2 = 0;
  try {
    c.validate();
    FAIL() << "a_max_mps2 = 0 accepted";
  } catch (const semexp::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("planner/a_max_mps2"), std::string::npos) << e.what();
  }
  c = TrajectoryConfig();
  c.alpha_max_radps2 = NAN;
  EXPECT_THROW(c.validate(), semexp::ConfigError);
  c = TrajectoryConfig();
  c.trajectory_sample_period_s = 0;
  EXPECT_THROW(c.validate(), semexp::ConfigError);
}

TEST(SampledTrajectory, InterpolatesPositionAndYawTheShortWay) {
  SampledTrajectory tr(Samples{{0.0, {0, 0, 1}, 3.1}, {1.0, {1, 2, 1}, -3.1}, {3.0, {1, 2, 3}, -3.1}});
  EXPECT_EQ(tr.duration_s(), 3.0);
  const auto m = tr.at(0.5);
  EXPECT_TRUE(m.position_W.isApprox(Eigen::Vector3d(0.5, 1, 1)));
  EXPECT_NEAR(std::abs(m.yaw_rad), M_PI, 1e-12);  // through pi, not through 0
  EXPECT_NEAR(tr.at(0.25).yaw_rad, std::remainder(3.1 + 0.25 * (2 * M_PI - 6.2), 2 * M_PI), 1e-12);
  EXPECT_TRUE(tr.at(2.0).position_W.isApprox(Eigen::Vector3d(1, 2, 2)));
  EXPECT_EQ(tr.at(-1.0).position_W, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(tr.at(10.0).position_W, Eigen::Vector3d(1, 2, 3));
}

TEST(SampledTrajectory, FollowsTheExactTrajectoryWithinTheInterpolationError) {
  const Trajectory exact({{0, 0, 1}, {4, 1, 1}, {4, 3, 1.5}}, {0.0, 2.0, -2.5}, kV, kOmega, limits());
  Samples s;
  for (const auto& x : exact.sample(0.1)) s.push_back({x.t_s, x.position_W, x.yaw_rad});
  const SampledTrajectory table(s);
  EXPECT_EQ(table.duration_s(), exact.duration_s());
  for (double t = 0; t <= exact.duration_s(); t += 0.013) {
    const auto e = exact.at(t);
    const auto a = table.at(t);
    EXPECT_LE((a.position_W - e.position_W).norm(), 1.0 * 0.01 / 8 + 1e-9) << t;  // a dt^2 / 8
    EXPECT_LE(std::abs(std::remainder(a.yaw_rad - e.yaw_rad, 2 * M_PI)), 1.0 * 0.01 / 8 + 1e-9) << t;
  }
}

TEST(SampledTrajectory, RefusesBadSamplesNamingThePoint) {
  EXPECT_THROW(SampledTrajectory(Samples{}), std::invalid_argument);
  try {
    SampledTrajectory(Samples{{0.0, {0, 0, 0}, 0}, {1.0, {0, 0, 0}, 0}, {1.0, {1, 0, 0}, 0}});
    FAIL() << "repeated time accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("point 2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SampledTrajectory(Samples{{0.0, {0, 0, 0}, NAN}}), std::invalid_argument);
}

// The paper's termination conditions (termination.hpp) on hand-built inputs.
#include <gtest/gtest.h>

#include <cmath>

#include "semantic_exploration/core/planning/termination.hpp"

using namespace semexp;

namespace {

PlannerConfig semantic() {
  PlannerConfig c;  // a_ent/a_bg/a_obj 0.34/0.33/0.33
  c.stall_iterations = 3;
  c.stall_volume_m3 = 0.1;
  c.time_limit_s = 600.0;
  return c;
}

PlannerConfig classic() {
  PlannerConfig c = semantic();
  c.a_ent = 1.0;
  c.a_bg = c.a_obj = 0.0;
  c.p_frontier = 1.0;
  return c;
}

ObjectSummary object(std::uint32_t id, double share) {
  ObjectSummary o;
  o.id = id;
  o.observed_fraction = share;
  return o;
}

}  // namespace

TEST(Termination, ExploredNeedsAllThreeAndNamesTheLastToHold) {
  TerminationCheck t(TerminationConfig(), semantic());  // 0 frontiers, background >= 0.9, objects >= 0.9
  TerminationInputs in;
  in.active_frontiers = 0;
  in.background_share = 0.5;
  in.objects = {object(1, 0.95), object(2, 0.5)};
  TerminationDecision d = t.check(in);
  EXPECT_FALSE(d.finished);
  EXPECT_TRUE(d.frontiers_done);
  EXPECT_FALSE(d.background_done);
  EXPECT_FALSE(d.objects_done);
  in.objects[1].observed_fraction = 0.9;  // objects hold from the second check on
  d = t.check(in);
  EXPECT_FALSE(d.finished);
  EXPECT_TRUE(d.objects_done);
  in.background_share = 0.9;  // the background holds last
  d = t.check(in);
  EXPECT_TRUE(d.finished);
  EXPECT_EQ(d.reason, "explored");
  EXPECT_EQ(d.last_condition, "background");
  EXPECT_NE(d.message.find("the last condition to hold: background"), std::string::npos) << d.message;
}

TEST(Termination, AFrontierLeftOrAnUnmeasuredBackgroundKeepsItGoing) {
  TerminationCheck t(TerminationConfig(), semantic());
  TerminationInputs in;
  in.active_frontiers = 1;
  in.background_share = 1.0;
  EXPECT_FALSE(t.check(in).finished);
  in.active_frontiers = 0;
  in.background_share = -1.0;  // not measured
  EXPECT_FALSE(t.check(in).finished);
  TerminationConfig some;
  some.max_active_frontiers = 20;
  TerminationCheck lenient(some, semantic());
  in.active_frontiers = 20;
  in.background_share = 0.95;
  EXPECT_EQ(lenient.check(in).reason, "explored");
}

TEST(Termination, ClassicStopsOnFrontiersAlone) {
  TerminationCheck t(TerminationConfig(), classic());
  TerminationInputs in;
  in.active_frontiers = 0;
  in.background_share = 0.1;                // not pursued
  in.objects = {object(1, 0.0)};            // not pursued
  const TerminationDecision d = t.check(in);
  EXPECT_TRUE(d.finished);
  EXPECT_EQ(d.reason, "explored");
  EXPECT_TRUE(d.background_done && d.objects_done);
}

TEST(Termination, NoProgressLooksAtAllThreeGains) {
  // Volume flat at 100 m^3 and frontiers flat at 50 voxels, stall window 3
  // iterations; one object's share grows 0.30, 0.35, 0.40, 0.45, 0.50, then
  // stays: growth over each window is 0.15 >= 0.01 until the share stops.
  TerminationCheck t(TerminationConfig(), semantic());
  TerminationInputs in;
  in.explored_volume_m3 = 100.0;
  in.active_frontiers = 50;
  in.background_share = 0.5;
  const double shares[] = {0.30, 0.35, 0.40, 0.45, 0.50, 0.50, 0.50, 0.50};
  for (int it = 0; it < 8; ++it) {
    in.objects = {object(7, shares[it])};
    const TerminationDecision d = t.check(in);
    // Windows (3 iterations back): it 3: 0.30 -> 0.45, it 4: 0.35 -> 0.50, it 5: 0.40 -> 0.50,
    // it 6: 0.45 -> 0.50 (0.05 >= 0.01) go on; it 7: 0.50 -> 0.50 stops.
    EXPECT_EQ(d.finished, it == 7) << it << ": " << d.message;
    if (it == 7) {
      EXPECT_EQ(d.reason, "no_progress");
    }
  }
}

TEST(Termination, ClassicNoProgressIsVolumeAndFrontiersOnly) {
  TerminationCheck t(TerminationConfig(), classic());
  TerminationInputs in;
  in.explored_volume_m3 = 100.0;
  in.active_frontiers = 50;
  const double shares[] = {0.1, 0.3, 0.5, 0.7};  // an object's share grows: not pursued in classic mode
  for (int it = 0; it < 4; ++it) {
    in.objects = {object(1, shares[it])};
    EXPECT_EQ(t.check(in).finished, it == 3) << it;
  }
}

TEST(Termination, FewerActiveFrontiersIsProgress) {
  TerminationCheck t(TerminationConfig(), classic());
  TerminationInputs in;
  in.explored_volume_m3 = 100.0;
  for (int it = 0; it < 6; ++it) {
    in.active_frontiers = 60 - 10 * it;  // retired clusters leave the count
    EXPECT_FALSE(t.check(in).finished) << it;
  }
}

TEST(Termination, AFrontierClusterRetiredByEvidenceIsProgressThoughNewVoxelsHideIt) {
  // Volume flat, stall window 3 (classic: the object shares do not count). The
  // active count rises 13, 20, 24, 24, 24, ... as flights add frontier
  // voxels, while clusters are retired by evidence at iterations 1 and 3
  // (running count 0, 1, 1, 2, 2, ...). Windows of 3 iterations back, in
  // retirements: it 3: 0 -> 2, it 4: 1 -> 2, it 5: 1 -> 2 go on; it 6:
  // 2 -> 2 with 24 -> 24 voxels stops.
  TerminationCheck t(TerminationConfig(), classic());
  TerminationInputs in;
  in.explored_volume_m3 = 100.0;
  const std::size_t active[] = {13, 20, 24, 24, 24, 24, 24};
  const std::size_t retired[] = {0, 1, 1, 2, 2, 2, 2};
  for (int it = 0; it < 7; ++it) {
    in.active_frontiers = active[it];
    in.frontier_clusters_retired = retired[it];
    const TerminationDecision d = t.check(in);
    EXPECT_EQ(d.finished, it == 6) << it << ": " << d.message;
    if (it == 6) {
      EXPECT_EQ(d.reason, "no_progress");
      EXPECT_NE(d.message.find("no frontier cluster was retired by evidence for the first time"), std::string::npos) << d.message;
    }
  }
}

TEST(Termination, RetiredObjectsBelowTheShareDoNotHoldExploredOpen) {
  TerminationCheck t(TerminationConfig(), semantic());
  TerminationInputs in;
  in.active_frontiers = 0;
  in.background_share = 0.95;
  in.objects = {object(1, 0.95), object(2, 0.87), object(3, 0.6)};
  in.retired_object_ids = {2};  // 3 is below the share and not retired
  TerminationDecision d = t.check(in);
  EXPECT_FALSE(d.objects_done);
  EXPECT_FALSE(d.finished);
  in.retired_object_ids = {2, 3};
  d = t.check(in);
  EXPECT_TRUE(d.objects_done);
  EXPECT_EQ(d.objects_retired, 2u);
  EXPECT_EQ(d.reason, "explored");
  EXPECT_NE(d.message.find("1 seen from <= d_obj at >= 0.90, 2 retired below it"), std::string::npos) << d.message;
  EXPECT_NE(d.message.find("lowest 0.600"), std::string::npos) << d.message;
}

// run_mission.py sets planner/time_limit_s to 0 and stops the run itself at --sim-limit-s:
// 0 must mean no limit, not "stop at once".
TEST(Termination, ATimeLimitStopsAtItsSimTimeAndZeroMeansNone) {
  TerminationInputs in;
  in.active_frontiers = 50;  // far from explored
  in.background_share = 0.5;
  in.elapsed_s = 599.9;
  EXPECT_FALSE(TerminationCheck(TerminationConfig(), semantic()).check(in).finished);
  in.elapsed_s = 600.0;
  const TerminationDecision d = TerminationCheck(TerminationConfig(), semantic()).check(in);
  EXPECT_TRUE(d.finished);
  EXPECT_EQ(d.reason, "time_limit");
  PlannerConfig none = semantic();
  none.time_limit_s = 0.0;
  in.elapsed_s = 1.0e6;
  const TerminationDecision n = TerminationCheck(TerminationConfig(), none).check(in);
  EXPECT_FALSE(n.finished) << n.reason;
}

// Drop counting in the ROS shell: FrameGapCounter (frames missing from a
// constant-rate stream, from the stamps that arrive) and DropCounter without a
// running node (counts only, nothing published).
#include <gtest/gtest.h>

#include "semantic_exploration/ros/node_common.hpp"

using semexp_ros::DropCounter;
using semexp_ros::FrameGapCounter;

namespace {

ros::Time at(double t_s) { return ros::Time(t_s); }

}  // namespace

TEST(FrameGapCounter, CountsFramesMissingFromA10HzStream) {
  FrameGapCounter g;
  EXPECT_EQ(g.add(at(1.0)), 0u);  // first frame: nothing to compare with
  EXPECT_EQ(g.add(at(1.1)), 0u);
  EXPECT_NEAR(g.period_s(), 0.1, 1e-6);
  EXPECT_EQ(g.add(at(1.3)), 1u);  // 1.2 missing
  EXPECT_EQ(g.add(at(1.7)), 3u);  // 1.4, 1.5, 1.6 missing
  EXPECT_EQ(g.add(at(1.8)), 0u);
  EXPECT_NEAR(g.period_s(), 0.1, 1e-6);
}

TEST(FrameGapCounter, JitterRepeatsAndOlderStampsCountNothing) {
  FrameGapCounter g;
  for (int k = 0; k <= 5; ++k) g.add(at(2.0 + 0.1 * k));  // 2.0 .. 2.5
  EXPECT_EQ(g.add(at(2.6 + 0.04)), 0u);  // 0.14 s: a late frame, not a lost one
  EXPECT_EQ(g.add(at(2.7)), 0u);         // 0.06 s: the next one on time
  EXPECT_EQ(g.add(at(2.7)), 0u);         // the same frame again
  EXPECT_EQ(g.add(at(2.0)), 0u);         // an older frame (e.g. a bag replayed twice)
  EXPECT_EQ(g.add(at(2.8)), 0u);         // counting goes on from the newest stamp
  EXPECT_EQ(g.add(at(3.0)), 1u);
  EXPECT_NEAR(g.period_s(), 0.1, 1e-6);
}

TEST(FrameGapCounter, ThePeriodSurvivesManyDrops) {
  FrameGapCounter g;
  // 10 Hz with every third frame lost: two of three intervals are one period
  uint64_t missing = 0;
  for (int k = 0; k < 60; ++k)
    if (k % 3 != 2) missing += g.add(at(1.0 + 0.1 * k));
  EXPECT_EQ(missing, 19u);  // frames 2, 5, ..., 56 (59 lies after the last stamp)
  EXPECT_NEAR(g.period_s(), 0.1, 1e-6);
}

TEST(DropCounter, CountsPerReasonWithoutANode) {
  DropCounter d(1000.0);
  d.drop("no_tf", "frame 1");
  d.drop("no_tf", "frame 2");
  d.drop("frame_gap", "3 frames missing", 3);
  d.drop("frame_gap", "nothing", 0);
  EXPECT_EQ(d.count("no_tf"), 2u);
  EXPECT_EQ(d.count("frame_gap"), 3u);
  EXPECT_EQ(d.count("size_mismatch"), 0u);
  EXPECT_EQ(d.total(), 5u);
  EXPECT_EQ(d.counts().size(), 2u);
}

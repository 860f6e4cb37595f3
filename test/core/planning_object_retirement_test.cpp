// Object retirement by evidence (object_retirement.hpp) on hand-built share
// sequences: K = 3 flights aimed at an object, min_share_change 0.01, done at 0.9.
#include <gtest/gtest.h>

#include "semantic_exploration/core/planning/object_retirement.hpp"

using namespace semexp;

namespace {

ObjectSummary object(std::uint32_t id, double share) {
  ObjectSummary o;
  o.id = id;
  o.observed_fraction = share;
  return o;
}

/// One iteration: the planner reads `objects`, then flies to observe `aimed`.
void iterate(ObjectRetirement& r, const std::vector<ObjectSummary>& objects, std::uint32_t aimed) {
  r.update(objects);
  for (const ObjectSummary& o : objects)
    if (o.id == aimed) r.recordView(o.id, o.observed_fraction);
}

}  // namespace

TEST(ObjectRetirement, RetiredAfterKFlightsThatDidNotRaiseItsShare) {
  ObjectRetirement r(ObjectRetirementConfig(), 0.9);
  iterate(r, {object(1, 0.85), object(2, 0.5)}, 1);  // flight 1 aimed at object 1
  iterate(r, {object(1, 0.855), object(2, 0.5)}, 1);  // +0.005 < 0.01: failed 1; flight 2
  EXPECT_FALSE(r.retired(1));
  iterate(r, {object(1, 0.86), object(2, 0.5)}, 1);  // +0.005: failed 2; flight 3
  EXPECT_FALSE(r.retired(1));
  iterate(r, {object(1, 0.86), object(2, 0.5)}, 2);  // +0: failed 3, retired; the next flight goes to object 2
  EXPECT_TRUE(r.retired(1));
  EXPECT_FALSE(r.retired(2));
  EXPECT_EQ(r.retiredIds(), std::vector<std::uint32_t>{1});
  const std::vector<ObjectSummary> active = r.active({object(1, 0.86), object(2, 0.5)});
  ASSERT_EQ(active.size(), 1u);
  EXPECT_EQ(active[0].id, 2u);
}

TEST(ObjectRetirement, AFlightThatRaisesTheShareClearsTheCount) {
  ObjectRetirement r(ObjectRetirementConfig(), 0.9);
  iterate(r, {object(1, 0.80)}, 1);
  iterate(r, {object(1, 0.80)}, 1);  // failed 1
  iterate(r, {object(1, 0.80)}, 1);  // failed 2
  iterate(r, {object(1, 0.81)}, 1);  // +0.01 >= 0.01: cleared
  iterate(r, {object(1, 0.81)}, 1);  // failed 1
  iterate(r, {object(1, 0.81)}, 1);  // failed 2
  EXPECT_FALSE(r.retired(1));
  r.update({object(1, 0.81)});  // failed 3
  EXPECT_TRUE(r.retired(1));
}

TEST(ObjectRetirement, AFlightThatLowersTheShareFoundNewSurfaceAndClearsTheCount) {
  ObjectRetirement r(ObjectRetirementConfig(), 0.9);
  iterate(r, {object(1, 0.80)}, 1);
  iterate(r, {object(1, 0.80)}, 1);  // failed 1
  iterate(r, {object(1, 0.80)}, 1);  // failed 2
  iterate(r, {object(1, 0.79)}, 1);  // -0.01: new surface seen from afar, cleared
  iterate(r, {object(1, 0.79)}, 1);  // failed 1
  r.update({object(1, 0.795)});      // failed 2 (moved by 0.005 only)
  EXPECT_FALSE(r.retired(1));
}

TEST(ObjectRetirement, AViewThatWasNotFlownIsNotJudged) {
  ObjectRetirement r(ObjectRetirementConfig(), 0.9);
  iterate(r, {object(1, 0.5)}, 1);
  iterate(r, {object(1, 0.5)}, 1);  // failed 1
  iterate(r, {object(1, 0.5)}, 1);  // failed 2
  r.discardView();                  // the third path was dropped before it was flown
  r.update({object(1, 0.5)});
  EXPECT_FALSE(r.retired(1));
  r.recordView(1, 0.5);
  r.update({object(1, 0.5)});  // failed 3
  EXPECT_TRUE(r.retired(1));
}

TEST(ObjectRetirement, ARetiredObjectThatReachesTheDoneShareIsNoLongerRetired) {
  ObjectRetirement r(ObjectRetirementConfig(), 0.9);
  for (int i = 0; i < 4; ++i) iterate(r, {object(1, 0.895)}, i < 3 ? 1 : 0);
  ASSERT_TRUE(r.retired(1));
  r.update({object(1, 0.9)});  // moved by 0.005 only, but done
  EXPECT_FALSE(r.retired(1));
}

TEST(ObjectRetirement, OnlyFlightsAimedAtTheObjectCount) {
  ObjectRetirement r(ObjectRetirementConfig(), 0.9);
  for (int i = 0; i < 10; ++i) iterate(r, {object(1, 0.5), object(2, 0.5)}, 2);  // always aimed at 2
  EXPECT_FALSE(r.retired(1));
  EXPECT_TRUE(r.retired(2));
}

TEST(ObjectRetirement, ComesBackWhenItsShareMovesEitherWay) {
  ObjectRetirement r(ObjectRetirementConfig(), 0.9);
  for (int i = 0; i < 3; ++i) iterate(r, {object(1, 0.87), object(2, 0.6)}, 1);
  // The third failed flight retires object 1, and update() says so once.
  std::vector<ObjectRetirementChange> changes = r.update({object(1, 0.87), object(2, 0.6)});
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].id, 1u);
  EXPECT_TRUE(changes[0].retired);
  EXPECT_DOUBLE_EQ(changes[0].share, 0.87);
  for (int i = 0; i < 4; ++i) iterate(r, {object(1, 0.87), object(2, 0.6)}, i < 3 ? 2 : 0);
  ASSERT_TRUE(r.retired(1));
  ASSERT_TRUE(r.retired(2));
  EXPECT_TRUE(r.update({object(1, 0.875), object(2, 0.595)}).empty());  // moved by 0.005: both stay retired
  EXPECT_TRUE(r.retired(1) && r.retired(2));
  changes = r.update({object(1, 0.88), object(2, 0.59)});  // a passing look raised 1, new far surface lowered 2
  EXPECT_FALSE(r.retired(1));
  EXPECT_FALSE(r.retired(2));
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[0].id, 1u);
  EXPECT_FALSE(changes[0].retired);
  EXPECT_DOUBLE_EQ(changes[0].share, 0.88);
  EXPECT_EQ(changes[1].id, 2u);
  EXPECT_FALSE(changes[1].retired);
  EXPECT_DOUBLE_EQ(changes[1].share, 0.59);
  // Back with a clean count: K more failed flights retire it again.
  iterate(r, {object(1, 0.88)}, 1);
  iterate(r, {object(1, 0.88)}, 1);
  iterate(r, {object(1, 0.88)}, 1);
  EXPECT_FALSE(r.retired(1));
  r.update({object(1, 0.88)});
  EXPECT_TRUE(r.retired(1));
}

TEST(ObjectRetirement, DoneObjectsAndVanishedObjectsAreNotRetired) {
  ObjectRetirement r(ObjectRetirementConfig(), 0.9);
  for (int i = 0; i < 5; ++i) iterate(r, {object(1, 0.9)}, 1);  // at the share already: never a failed flight
  EXPECT_FALSE(r.retired(1));
  for (int i = 0; i < 4; ++i) iterate(r, {object(3, 0.2)}, i < 3 ? 3 : 0);
  ASSERT_TRUE(r.retired(3));
  r.update({});  // merged into another object: forgotten
  EXPECT_TRUE(r.retiredIds().empty());
}

TEST(ObjectRetirement, DisabledNeverRetires) {
  ObjectRetirementConfig c;
  c.enabled = false;
  ObjectRetirement r(c, 0.9);
  for (int i = 0; i < 10; ++i) iterate(r, {object(1, 0.5)}, 1);
  EXPECT_FALSE(r.retired(1));
}

TEST(ObjectRetirement, InvalidConfigNamesTheParameter) {
  ObjectRetirementConfig c;
  c.max_failed_views = 0;
  try {
    ObjectRetirement r(c, 0.9);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("object_retirement/max_failed_views"), std::string::npos) << e.what();
  }
  c = ObjectRetirementConfig();
  c.min_share_change = 0.0;
  try {
    ObjectRetirement r(c, 0.9);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("object_retirement/min_share_change"), std::string::npos) << e.what();
  }
  try {
    ObjectRetirement r(ObjectRetirementConfig(), 1.5);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("planner/object_observed_fraction"), std::string::npos) << e.what();
  }
}

// planner/candidate_markers: the boxes of the objects retired by evidence.
#include <gtest/gtest.h>

#include "semantic_exploration/ros/planner_markers.hpp"

namespace {

semexp::ObjectSummary box(std::uint32_t id, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  semexp::ObjectSummary o;
  o.id = id;
  o.bbox_min_W = lo;
  o.bbox_max_W = hi;
  return o;
}

const visualization_msgs::Marker* find(const visualization_msgs::MarkerArray& a, const std::string& ns) {
  for (const auto& m : a.markers)
    if (m.ns == ns) return &m;
  return nullptr;
}

}  // namespace

TEST(PlannerMarkers, RetiredObjectsAreDrawnAsTheTwelveEdgesOfTheirBoxes) {
  semexp::IterationResult r;
  r.retired_object_ids = {5};
  std_msgs::Header h;
  h.frame_id = "world";
  const std::vector<semexp::ObjectSummary> objects = {box(3, {0, 0, 0}, {1, 1, 1}),
                                                      box(5, {2, 3, 0}, {2.5, 3.4, 0.9})};
  const visualization_msgs::MarkerArray a = semexp_ros::candidateMarkers(r, h, 0.04, objects);
  const visualization_msgs::Marker* m = find(a, "retired_objects");
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->type, visualization_msgs::Marker::LINE_LIST);
  EXPECT_EQ(m->header.frame_id, "world");
  ASSERT_EQ(m->points.size(), 24u);  // 12 edges of object 5 only
  double length = 0.0;
  for (std::size_t i = 0; i < m->points.size(); i += 2) {
    const auto& p = m->points[i];
    const auto& q = m->points[i + 1];
    EXPECT_TRUE(p.x >= 2.0 && p.x <= 2.5 && p.y >= 3.0 && p.y <= 3.4 && p.z >= 0.0 && p.z <= 0.9);
    length += std::sqrt((p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) + (p.z - q.z) * (p.z - q.z));
  }
  EXPECT_NEAR(length, 4 * (0.5 + 0.4 + 0.9), 1e-9);
  r.retired_object_ids.clear();
  EXPECT_EQ(find(semexp_ros::candidateMarkers(r, h, 0.04, objects), "retired_objects"), nullptr);
}

#include "semantic_exploration/ros/planner_markers.hpp"

#include <algorithm>
#include <cstdio>

#include "semantic_exploration/ros/conversions.hpp"

namespace semexp_ros {

namespace {

std_msgs::ColorRGBA colour(float r, float g, float b, float a) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

/// A marker of `type` at the identity pose, every scale component `scale`.
visualization_msgs::Marker marker(const std_msgs::Header& header, const char* ns, int id, int type, double scale,
                                  const std_msgs::ColorRGBA& c) {
  visualization_msgs::Marker m;
  m.header = header;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.pose.orientation.w = 1.0;
  m.scale.x = m.scale.y = m.scale.z = scale;
  m.color = c;
  return m;
}

}  // namespace

visualization_msgs::MarkerArray candidateMarkers(const semexp::IterationResult& r, const std_msgs::Header& header,
                                                 double voxel_size_m,
                                                 const std::vector<semexp::ObjectSummary>& objects) {
  double max_u = 0.0;
  for (const auto& c : r.candidates) max_u = std::max(max_u, c.utility);
  visualization_msgs::MarkerArray markers;
  visualization_msgs::Marker clear;
  clear.header = header;
  clear.action = visualization_msgs::Marker::DELETEALL;
  markers.markers.push_back(clear);
  int id = 0;
  for (std::size_t i = 0; i < r.candidates.size(); ++i) {
    const auto& c = r.candidates[i];
    const float f = max_u > 0 ? static_cast<float>(c.utility / max_u) : 0.f;
    visualization_msgs::Marker m;
    m.header = header;
    m.ns = "candidates";
    m.id = id++;
    m.type = visualization_msgs::Marker::SPHERE;
    m.pose.position = toPoint(c.position_W);
    m.pose.orientation.w = 1.0;
    m.scale.x = m.scale.y = m.scale.z = static_cast<int>(i) == r.winner ? 0.3 : 0.15;
    m.color = c.reachable ? colour(1.f - f, f, 0.f, 0.9f) : colour(0.5f, 0.5f, 0.5f, 0.5f);
    markers.markers.push_back(m);
    if (!c.reachable) continue;
    visualization_msgs::Marker a = m;
    a.ns = "candidate_yaw";
    a.id = id++;
    a.type = visualization_msgs::Marker::ARROW;
    a.pose.orientation = yawQuaternion(c.yaw_rad);
    a.scale.x = 0.4;
    a.scale.y = a.scale.z = 0.04;
    markers.markers.push_back(a);
    visualization_msgs::Marker t = m;
    t.ns = "candidate_utility";
    t.id = id++;
    t.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
    t.pose.position.z += 0.25;
    t.scale.x = t.scale.y = t.scale.z = 0.15;
    t.color = colour(1.f, 1.f, 1.f, 1.f);
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.3f", c.utility);
    t.text = buf;
    markers.markers.push_back(t);
  }
  if (r.winner >= 0) {
    visualization_msgs::Marker line = marker(header, "winner_path", id++, visualization_msgs::Marker::LINE_STRIP,
                                             0.04, colour(0.2f, 0.4f, 1.f, 1.f));
    for (const auto& p : r.path_W) line.points.push_back(toPoint(p));
    markers.markers.push_back(line);
  }
  if (!r.retired_frontiers_W.empty()) {
    visualization_msgs::Marker cubes = marker(header, "retired_frontiers", id++, visualization_msgs::Marker::CUBE_LIST,
                                              voxel_size_m, colour(0.6f, 0.2f, 0.8f, 0.6f));
    for (const auto& p : r.retired_frontiers_W) cubes.points.push_back(toPoint(p));
    markers.markers.push_back(cubes);
  }
  visualization_msgs::Marker boxes = marker(header, "retired_objects", id++, visualization_msgs::Marker::LINE_LIST,
                                            0.02, colour(0.6f, 0.2f, 0.8f, 1.f));
  for (const semexp::ObjectSummary& o : objects) {
    if (!std::binary_search(r.retired_object_ids.begin(), r.retired_object_ids.end(), o.id)) continue;
    // The 12 edges of the box: between corners that differ in one coordinate.
    for (int a = 0; a < 8; ++a)
      for (int axis = 0; axis < 3; ++axis) {
        if (a & (1 << axis)) continue;
        const int b = a | (1 << axis);
        for (const int c : {a, b})
          boxes.points.push_back(toPoint(Eigen::Vector3d((c & 1) ? o.bbox_max_W.x() : o.bbox_min_W.x(),
                                                         (c & 2) ? o.bbox_max_W.y() : o.bbox_min_W.y(),
                                                         (c & 4) ? o.bbox_max_W.z() : o.bbox_min_W.z())));
      }
  }
  if (!boxes.points.empty()) markers.markers.push_back(boxes);
  return markers;
}

std::string winnerSummary(const semexp::IterationResult& r, double background_share, std::size_t map_retired) {
  if (r.winner < 0) return "no winner";
  const auto& w = r.candidates[static_cast<std::size_t>(r.winner)];
  const bool object = w.sample.source == semexp::CandidateSource::kObject;
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "%s candidate%s%s (%d of %zu planned, %d reachable) at (%.2f, %.2f, %.2f) yaw %.2f: gain %.3f "
                "(entropy %.3f, bg %.3f, obj %.3f), %s path %.1f s, utility %.4f; %zu active frontier voxels "
                "(%zu retired here, %zu by the map's evidence), background seen from <= d_bg %.3f",
                semexp::candidateSourceName(w.sample.source), object ? " of object " : "",
                object ? std::to_string(w.sample.object_id).c_str() : "", r.candidates_planned, r.candidates.size(),
                r.candidates_reachable, w.position_W.x(), w.position_W.y(), w.position_W.z(), w.yaw_rad, w.gain,
                w.gain_entropy, w.gain_bg, w.gain_obj, semexp::PlannedPath::name(w.plan.status), w.path_time_s,
                w.utility, r.active_frontiers, r.retired_frontiers_W.size(), map_retired, background_share);
  return buf;
}

}  // namespace semexp_ros

#include "semantic_exploration/ros/conversions.hpp"

#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace semexp_ros {

static_assert(static_cast<uint8_t>(semexp::CandidateSource::kFrontier) ==
                  semantic_exploration::CandidateView::SOURCE_FRONTIER &&
                  static_cast<uint8_t>(semexp::CandidateSource::kObject) ==
                      semantic_exploration::CandidateView::SOURCE_OBJECT &&
                  static_cast<uint8_t>(semexp::CandidateSource::kFreeSpace) ==
                      semantic_exploration::CandidateView::SOURCE_FREE_SPACE,
              "CandidateSource and CandidateView.msg's SOURCE_* disagree");

geometry_msgs::Point toPoint(const Eigen::Vector3d& p) {
  geometry_msgs::Point m;
  m.x = p.x();
  m.y = p.y();
  m.z = p.z();
  return m;
}

geometry_msgs::Quaternion yawQuaternion(double yaw_rad) {
  geometry_msgs::Quaternion q;
  q.w = std::cos(0.5 * yaw_rad);
  q.z = std::sin(0.5 * yaw_rad);
  return q;
}

nav_msgs::Path toPath(const std::vector<Eigen::Vector3d>& path_W, const std::vector<double>& yaw_rad,
                      const std::string& frame, const ros::Time& stamp) {
  nav_msgs::Path out;
  out.header.frame_id = frame;
  out.header.stamp = stamp;
  for (std::size_t i = 0; i < path_W.size(); ++i) {
    geometry_msgs::PoseStamped ps;
    ps.header = out.header;
    ps.pose.position = toPoint(path_W[i]);
    ps.pose.orientation = yawQuaternion(i < yaw_rad.size() ? yaw_rad[i] : (yaw_rad.empty() ? 0.0 : yaw_rad.back()));
    out.poses.push_back(ps);
  }
  return out;
}

semexp::GainImage toGainImage(const sensor_msgs::Image& img, int w, int h, const char* what) {
  if (img.width == 0 && img.height == 0) return semexp::GainImage();
  if (img.encoding != sensor_msgs::image_encodings::TYPE_32FC1 || static_cast<int>(img.width) != w ||
      static_cast<int>(img.height) != h || img.step < img.width * 4 ||
      img.data.size() < static_cast<std::size_t>(img.step) * img.height || img.is_bigendian)
    throw std::runtime_error(std::string(what) + " image is not a " + std::to_string(w) + "x" + std::to_string(h) +
                             " 32FC1 image (got " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                             " " + img.encoding + ")");
  semexp::GainImage out(w, h);
  for (int v = 0; v < h; ++v)
    std::memcpy(&out.values[static_cast<std::size_t>(v) * w], &img.data[static_cast<std::size_t>(v) * img.step],
                static_cast<std::size_t>(w) * sizeof(float));
  return out;
}

std::vector<semexp::GainSet> toBackgroundGains(const semantic_exploration::ComputeGains::Response& r,
                                               std::size_t positions, int w, int h) {
  if (r.entropy_gain.size() != positions || r.distance_gain.size() != positions)
    throw std::runtime_error("background_map/compute_gains returned " + std::to_string(r.entropy_gain.size()) +
                             " images for " + std::to_string(positions) + " positions");
  std::vector<semexp::GainSet> out(positions);
  for (std::size_t i = 0; i < positions; ++i) {
    out[i].entropy = toGainImage(r.entropy_gain[i], w, h, "entropy gain");
    out[i].background = toGainImage(r.distance_gain[i], w, h, "background gain");
  }
  return out;
}

std::vector<std::vector<std::uint8_t>> toHistoryMasks(const std::vector<sensor_msgs::Image>& masks, int w, int h,
                                                      std::size_t& bad) {
  bad = 0;
  std::vector<std::vector<std::uint8_t>> out(masks.size());
  for (std::size_t i = 0; i < masks.size(); ++i) {
    const auto& m = masks[i];
    if (static_cast<int>(m.width) != w || static_cast<int>(m.height) != h || m.step < m.width ||
        m.data.size() < static_cast<std::size_t>(m.step) * m.height) {
      ++bad;
      continue;
    }
    out[i].resize(static_cast<std::size_t>(w) * h);
    for (int v = 0; v < h; ++v)
      std::memcpy(&out[i][static_cast<std::size_t>(v) * w], &m.data[static_cast<std::size_t>(v) * m.step],
                  static_cast<std::size_t>(w));
  }
  return out;
}

namespace {
/// Copies the bytes of one vector of 1-byte values into another of another 1-byte type (uint8 <-> int8:
/// the map's log-odds codes travel as the message's bytes, same bits).
template <class To, class From>
void copyBytes(const std::vector<From>& from, std::vector<To>& to) {
  static_assert(sizeof(To) == 1 && sizeof(From) == 1, "1-byte values only");
  to.resize(from.size());
  if (!from.empty()) std::memcpy(to.data(), from.data(), from.size());
}
}  // namespace

std::string fromMapBlocksMsg(const semantic_exploration::MapBlocks& msg, semexp::MapBlocksData& d) {
  if (msg.encoding != semantic_exploration::MapBlocks::ENCODING_LOG_ODDS_I8)
    return "MapBlocks encoding " + std::to_string(msg.encoding) + " unsupported";
  d.sequence = msg.sequence;
  d.full = msg.full;
  d.resolution_m = msg.resolution_m;
  d.block_size = msg.block_size;
  d.origin_m = fromPoint(msg.origin);
  d.encoding = msg.encoding;
  d.coords = msg.coords;
  copyBytes(msg.payload, d.payload);
  d.uniform_coords = msg.uniform_coords;
  copyBytes(msg.uniform_values, d.uniform_values);
  return "";
}

std::vector<semexp::ObjectSummary> toObjectSummaries(const semantic_exploration::ObjectArray& msg,
                                                     std::size_t& dropped) {
  std::vector<semexp::ObjectSummary> out;
  dropped = 0;
  for (const auto& o : msg.objects) {
    semexp::ObjectSummary s;
    s.id = o.id;
    s.bbox_min_W = {o.bbox_min.x, o.bbox_min.y, o.bbox_min.z};
    s.bbox_max_W = {o.bbox_max.x, o.bbox_max.y, o.bbox_max.z};
    s.centroid_W = {o.centroid.x, o.centroid.y, o.centroid.z};
    s.observed_fraction = o.observed_fraction;
    const bool share_ok = std::isfinite(s.observed_fraction) && s.observed_fraction >= 0 && s.observed_fraction <= 1;
    if (s.bbox_min_W.allFinite() && s.bbox_max_W.allFinite() && s.centroid_W.allFinite() && share_ok)
      out.push_back(s);
    else
      ++dropped;
  }
  return out;
}

std::string frontiersFromCloud(const sensor_msgs::PointCloud2& msg, std::vector<Eigen::Vector3d>& points_W) {
  // Offsets of float32 x, y, z; -1 where missing.
  long offset[3] = {-1, -1, -1};
  const char* names[3] = {"x", "y", "z"};
  for (const auto& f : msg.fields)
    for (int k = 0; k < 3; ++k)
      if (f.name == names[k] && f.datatype == sensor_msgs::PointField::FLOAT32) offset[k] = f.offset;
  if (offset[0] < 0 || offset[1] < 0 || offset[2] < 0) return "frontier cloud without float32 x, y and z fields";
  if (msg.is_bigendian) return "frontier cloud is big-endian";
  const std::size_t step = msg.point_step;
  for (long o : offset)
    if (static_cast<std::size_t>(o) + sizeof(float) > step)
      return "frontier cloud point_step " + std::to_string(step) + " does not hold its x, y, z fields";
  const std::size_t row = static_cast<std::size_t>(msg.width) * step;
  if (msg.row_step < row)
    return "frontier cloud row_step " + std::to_string(msg.row_step) + " < width x point_step " + std::to_string(row);
  // PointCloud2 defines data as exactly row_step x height bytes; anything
  // else is a message cut short or padded by a broken publisher.
  const std::size_t needed = static_cast<std::size_t>(msg.row_step) * msg.height;
  if (msg.data.size() != needed)
    return "frontier cloud data holds " + std::to_string(msg.data.size()) + " bytes, not row_step x height = " +
           std::to_string(needed);
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<std::size_t>(msg.width) * msg.height);
  for (std::size_t r = 0; r < msg.height; ++r)
    for (std::size_t i = 0; i < msg.width; ++i) {
      const std::uint8_t* pt = &msg.data[r * msg.row_step + i * step];
      float xyz[3];
      for (int k = 0; k < 3; ++k) std::memcpy(&xyz[k], pt + offset[k], sizeof(float));
      const Eigen::Vector3d p(xyz[0], xyz[1], xyz[2]);
      if (p.allFinite()) out.push_back(p);
    }
  points_W = std::move(out);
  return "";
}

semantic_exploration::CandidateViewArray toCandidateViewArray(const semexp::IterationResult& r,
                                                              const std::string& frame, const ros::Time& stamp,
                                                              double current_yaw_rad) {
  semantic_exploration::CandidateViewArray arr;
  arr.header.stamp = stamp;
  arr.header.frame_id = frame;
  arr.winner = r.winner;
  for (std::size_t i = 0; i < r.candidates.size(); ++i) {
    const auto& c = r.candidates[i];
    semantic_exploration::CandidateView v;
    v.position = toPoint(c.position_W);
    v.yaw_rad = static_cast<float>(c.yaw_rad);
    v.gain_entropy = static_cast<float>(c.gain_entropy);
    v.gain_bg = static_cast<float>(c.gain_bg);
    v.gain_obj = static_cast<float>(c.gain_obj);
    v.gain = static_cast<float>(c.gain);
    v.path_time_s = static_cast<float>(c.path_time_s);
    v.utility = static_cast<float>(c.utility);
    v.source = static_cast<uint8_t>(c.sample.source);  // CandidateSource values are CandidateView's SOURCE_*
    v.object_id = c.sample.object_id;
    v.reachable = c.reachable;
    std::vector<double> yaws(c.plan.path_W.size(), c.yaw_rad);
    if (!yaws.empty()) yaws.front() = current_yaw_rad;
    if (static_cast<int>(i) == r.winner) yaws = r.path_yaw_rad;
    v.path = toPath(c.plan.path_W, yaws, frame, stamp);
    arr.candidates.push_back(v);
  }
  return arr;
}

semantic_exploration::ExplorationStatus toExplorationStatus(const semexp::IterationResult& r, uint8_t state,
                                                            uint32_t iteration, const std::string& frame,
                                                            const ros::Time& stamp,
                                                            const std::vector<semexp::ObjectSummary>& objects,
                                                            double background_share) {
  semantic_exploration::ExplorationStatus s;
  s.header.stamp = stamp;
  s.header.frame_id = frame;
  s.state = state;
  s.iteration = iteration;
  s.termination_reason = r.termination_reason;
  s.message = r.message;
  s.candidates_sampled = static_cast<uint32_t>(r.candidates.size());
  s.candidates_reachable = static_cast<uint32_t>(r.candidates_reachable);
  s.planning_time_s = static_cast<float>(r.total_s);
  s.sampling_time_s = static_cast<float>(r.sampling_s);
  s.path_planning_time_s = static_cast<float>(r.path_planning_s);
  s.gains_time_s = static_cast<float>(r.gains_s);
  s.yaw_time_s = static_cast<float>(r.yaw_s);
  s.active_frontiers = static_cast<uint32_t>(r.active_frontiers);
  s.retired_frontiers = static_cast<uint32_t>(r.retired_frontiers_W.size());
  s.frontier_clusters = static_cast<uint32_t>(r.frontier_clusters);
  s.retired_clusters_geometry = static_cast<uint32_t>(r.retired_clusters_geometry);
  s.retired_clusters_evidence = static_cast<uint32_t>(r.retired_clusters_evidence);
  s.frontiers_done = r.termination.frontiers_done;
  s.background_done = r.termination.background_done;
  s.objects_done = r.termination.objects_done;
  s.last_condition = r.termination.last_condition;
  s.background_observed_share = static_cast<float>(background_share);
  for (const auto& o : objects) {
    s.object_ids.push_back(o.id);
    s.object_observed_shares.push_back(static_cast<float>(o.observed_fraction));
  }
  for (const std::uint32_t id : r.retired_object_ids) s.retired_object_ids.push_back(id);
  return s;
}

std::string fromMapStats(const semantic_exploration::MapStats& msg, double& explored_volume_m3,
                         double& background_share) {
  const double share = msg.surface_observed_share;
  if (!std::isfinite(msg.explored_volume_m3) || msg.explored_volume_m3 < 0 ||
      !(share == -1 || (std::isfinite(share) && share >= 0 && share <= 1)))
    return "map stats with a negative or non-finite explored volume or a share outside [0, 1]";
  explored_volume_m3 = msg.explored_volume_m3;
  if (share >= 0) background_share = share;
  return "";
}

sensor_msgs::PointCloud2 toPointCloud(const std::vector<Eigen::Vector3d>& points_W, const ros::Time& stamp,
                                      const std::string& frame) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header.stamp = stamp;
  cloud.header.frame_id = frame;
  sensor_msgs::PointCloud2Modifier mod(cloud);
  mod.setPointCloud2FieldsByString(1, "xyz");
  mod.resize(points_W.size());
  sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  for (const auto& p : points_W) {
    *x = static_cast<float>(p.x());
    *y = static_cast<float>(p.y());
    *z = static_cast<float>(p.z());
    ++x, ++y, ++z;
  }
  return cloud;
}

trajectory_msgs::MultiDOFJointTrajectory toTrajectoryMsg(const std::vector<semexp::TrajectoryState>& samples,
                                                         const std::string& frame, const std::string& joint,
                                                         const ros::Time& stamp) {
  trajectory_msgs::MultiDOFJointTrajectory out;
  out.header.frame_id = frame;
  out.header.stamp = stamp;
  out.joint_names.push_back(joint);
  out.points.reserve(samples.size());
  for (const auto& s : samples) {
    trajectory_msgs::MultiDOFJointTrajectoryPoint p;
    geometry_msgs::Transform tf;
    tf.translation.x = s.position_W.x();
    tf.translation.y = s.position_W.y();
    tf.translation.z = s.position_W.z();
    tf.rotation = yawQuaternion(s.yaw_rad);
    p.transforms.push_back(tf);
    geometry_msgs::Twist v;
    v.linear.x = s.velocity_W.x();
    v.linear.y = s.velocity_W.y();
    v.linear.z = s.velocity_W.z();
    v.angular.z = s.yaw_rate_radps;
    p.velocities.push_back(v);
    geometry_msgs::Twist a;
    a.linear.x = s.acceleration_W.x();
    a.linear.y = s.acceleration_W.y();
    a.linear.z = s.acceleration_W.z();
    p.accelerations.push_back(a);
    p.time_from_start = ros::Duration(s.t_s);
    out.points.push_back(p);
  }
  return out;
}

std::string fromTrajectoryMsg(const trajectory_msgs::MultiDOFJointTrajectory& msg, const std::string& frame,
                              semexp::SampledTrajectory& out) {
  const std::string got = msg.header.frame_id.empty() || msg.header.frame_id[0] != '/'
                              ? msg.header.frame_id : msg.header.frame_id.substr(1);
  if (!got.empty() && got != frame) return "trajectory in frame '" + got + "' (expected '" + frame + "')";
  if (msg.points.empty()) {
    out = semexp::SampledTrajectory();
    return "";
  }
  if (msg.joint_names.size() > 1) return std::to_string(msg.joint_names.size()) + " joints (expected 1, the body)";
  std::vector<semexp::SampledTrajectory::Sample> samples;
  samples.reserve(msg.points.size());
  for (std::size_t i = 0; i < msg.points.size(); ++i) {
    const auto& p = msg.points[i];
    const std::string at = "point " + std::to_string(i);
    if (p.transforms.size() != 1)
      return at + " has " + std::to_string(p.transforms.size()) + " transforms (expected 1)";
    const auto& t = p.transforms[0];
    const auto& q = t.rotation;
    const double n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    if (!std::isfinite(n) || n < 1e-6) return at + " has a zero or non-finite quaternion";
    const double t_s = p.time_from_start.toSec();
    if (t_s < 0) return at + " has a negative time_from_start";
    semexp::SampledTrajectory::Sample s;
    s.t_s = t_s;
    s.position_W = Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z);
    // Yaw of the rotation (z-y-x Euler), robust to an unnormalised quaternion.
    s.yaw_rad = std::atan2(2.0 * (q.w * q.z + q.x * q.y), q.w * q.w + q.x * q.x - q.y * q.y - q.z * q.z);
    samples.push_back(s);
  }
  try {
    out = semexp::SampledTrajectory(std::move(samples));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

std::string cutCloudAboveZ(const sensor_msgs::PointCloud2& in, double max_z_m, sensor_msgs::PointCloud2& out) {
  const sensor_msgs::PointField* z = nullptr;
  for (const auto& f : in.fields)
    if (f.name == "z") z = &f;
  if (!z || z->datatype != sensor_msgs::PointField::FLOAT32 || z->offset + 4 > in.point_step)
    return "the cloud has no FLOAT32 field z within its point_step";
  const std::size_t n = static_cast<std::size_t>(in.width) * in.height;
  if (in.row_step < static_cast<std::size_t>(in.width) * in.point_step ||
      in.data.size() < static_cast<std::size_t>(in.row_step) * in.height)
    return "the cloud's data is shorter than its width x height x point_step";
  out.header = in.header;
  out.fields = in.fields;
  out.is_bigendian = in.is_bigendian;
  out.point_step = in.point_step;
  out.is_dense = in.is_dense;
  out.height = 1;
  out.data.clear();
  out.data.reserve(n * in.point_step);
  std::size_t kept = 0;
  for (std::uint32_t row = 0; row < in.height; ++row) {
    for (std::uint32_t col = 0; col < in.width; ++col) {
      const std::uint8_t* p = &in.data[static_cast<std::size_t>(row) * in.row_step +
                                       static_cast<std::size_t>(col) * in.point_step];
      std::uint8_t b[4];
      std::memcpy(b, p + z->offset, 4);
      if (static_cast<bool>(in.is_bigendian) != (__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__)) {
        std::swap(b[0], b[3]);
        std::swap(b[1], b[2]);
      }
      float v;
      std::memcpy(&v, b, 4);
      if (!std::isfinite(v) || v > max_z_m) continue;
      out.data.insert(out.data.end(), p, p + in.point_step);
      ++kept;
    }
  }
  out.width = static_cast<std::uint32_t>(kept);
  out.row_step = out.width * out.point_step;
  return "";
}

// ---------------------------------------------------------------- map nodes

Eigen::Vector3d fromPoint(const geometry_msgs::Point& p) { return {p.x, p.y, p.z}; }

std::vector<Eigen::Vector3d> fromPoints(const std::vector<geometry_msgs::Point>& points) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const auto& p : points) out.push_back(fromPoint(p));
  return out;
}

geometry_msgs::Pose toPose(const Eigen::Isometry3d& T) {
  geometry_msgs::Pose m;
  m.position = toPoint(T.translation());
  const Eigen::Quaterniond q(T.linear());
  m.orientation.w = q.w();
  m.orientation.x = q.x();
  m.orientation.y = q.y();
  m.orientation.z = q.z();
  return m;
}

std::string fromPose(const geometry_msgs::Pose& pose, Eigen::Isometry3d& T) {
  const auto& q = pose.orientation;
  const Eigen::Quaterniond quat(q.w, q.x, q.y, q.z);
  const Eigen::Vector3d t = fromPoint(pose.position);
  if (!(quat.norm() > 0.5) || !t.allFinite()) return "pose is not a valid rigid transform";
  T = Eigen::Isometry3d::Identity();
  T.linear() = quat.normalized().toRotationMatrix();
  T.translation() = t;
  return "";
}

Eigen::Isometry3d fromTransform(const geometry_msgs::Transform& t) {
  const auto& q = t.rotation;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z);
  return T;
}

semantic_exploration::MapBlocks toMapBlocksMsg(const semexp::MapBlocksData& d, const ros::Time& stamp,
                                               const std::string& frame) {
  static_assert(semexp::MapBlocksData::kEncodingLogOddsI8 == semantic_exploration::MapBlocks::ENCODING_LOG_ODDS_I8,
                "MapBlocksData and MapBlocks.msg disagree on the encoding");
  semantic_exploration::MapBlocks m;
  m.header.stamp = stamp;
  m.header.frame_id = frame;
  m.sequence = d.sequence;
  m.full = d.full;
  m.resolution_m = static_cast<float>(d.resolution_m);
  m.block_size = static_cast<std::uint8_t>(d.block_size);
  m.origin = toPoint(d.origin_m);
  m.encoding = d.encoding;
  m.coords = d.coords;
  copyBytes(d.payload, m.payload);
  m.uniform_coords = d.uniform_coords;
  copyBytes(d.uniform_values, m.uniform_values);
  return m;
}

semantic_exploration::ObjectInfo toObjectInfo(const semexp::MappedObject& o, const semexp::TsdfSummary& s) {
  semantic_exploration::ObjectInfo info;
  info.id = o.id;
  info.class_id = static_cast<uint16_t>(o.class_id);
  info.class_name = o.class_name;
  info.resolution_m = static_cast<float>(o.resolution_m);
  info.bbox_min = toPoint(s.bbox_min_W);
  info.bbox_max = toPoint(s.bbox_max_W);
  info.centroid = toPoint(s.centroid_W);
  info.voxel_count = static_cast<uint32_t>(s.voxel_count);
  info.observed_fraction = static_cast<float>(s.observed_fraction);
  info.detection_count = o.detection_count;
  info.undetected_count = o.undetected_count;
  info.weight_sum = static_cast<float>(s.weight_sum);
  return info;
}

}  // namespace semexp_ros

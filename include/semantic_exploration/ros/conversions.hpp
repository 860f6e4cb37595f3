#pragma once
/// @file conversions.hpp
/// Message <-> core conversions: points, poses and paths for every node, and
/// what the planner reads and sends (gain images, MapBlocks for the map
/// replica, object summaries, the frontier cloud, history masks, candidates,
/// status), and what the map nodes send (MapBlocks, ObjectInfo). Each function that reads a message validates it and says why it
/// refused it, so a node can count the drop and go on.

#include <geometry_msgs/Point.h>
#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Transform.h>
#include <geometry_msgs/Quaternion.h>
#include <nav_msgs/Path.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <trajectory_msgs/MultiDOFJointTrajectory.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "semantic_exploration/CandidateViewArray.h"
#include "semantic_exploration/ComputeGains.h"
#include "semantic_exploration/ExplorationStatus.h"
#include "semantic_exploration/MapBlocks.h"
#include "semantic_exploration/MapStats.h"
#include "semantic_exploration/ObjectArray.h"
#include "semantic_exploration/core/object_map.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"
#include "semantic_exploration/core/planning/exploration_planner.hpp"
#include "semantic_exploration/core/planning/interfaces.hpp"
#include "semantic_exploration/core/planning/map_replica.hpp"
#include "semantic_exploration/core/planning/trajectory.hpp"

namespace semexp_ros {

geometry_msgs::Point toPoint(const Eigen::Vector3d& p);
/// Rotation about z by yaw_rad.
geometry_msgs::Quaternion yawQuaternion(double yaw_rad);

/// Path with one pose per vertex; vertex i gets yaw_rad[i], or the last yaw
/// where yaw_rad is shorter (0 if it is empty).
nav_msgs::Path toPath(const std::vector<Eigen::Vector3d>& path_W, const std::vector<double>& yaw_rad,
                      const std::string& frame, const ros::Time& stamp);

/// 32FC1 image -> GainImage of w x h. A 0 x 0 image is "no such gain" (an
/// empty GainImage). Throws std::runtime_error naming `what` on any other
/// size, encoding or a short buffer.
semexp::GainImage toGainImage(const sensor_msgs::Image& img, int w, int h, const char* what);

/// The entropy and background gain images of a background_map/compute_gains
/// answer, one GainSet per position (object images left empty). Throws
/// std::runtime_error if it holds another number of images than `positions`
/// or an image is not w x h 32FC1.
std::vector<semexp::GainSet> toBackgroundGains(const semantic_exploration::ComputeGains::Response& r,
                                               std::size_t positions, int w, int h);

/// History masks (mono8/8UC1, 1 = valid) as w x h row-major bytes; a mask of
/// the wrong size becomes an empty one (all valid) and is counted in `bad`.
std::vector<std::vector<std::uint8_t>> toHistoryMasks(const std::vector<sensor_msgs::Image>& masks, int w, int h,
                                                      std::size_t& bad);

/// A MapBlocks message as the codec's data (the inverse of toMapBlocksMsg;
/// the payload's uint8 carry the int8 codes' bits). Returns "" or why the
/// message cannot be read (an unknown encoding), `blocks` untouched then.
std::string fromMapBlocksMsg(const semantic_exploration::MapBlocks& msg, semexp::MapBlocksData& blocks);

/// The objects of the object map as the planner sees them; objects with a
/// non-finite box or centroid, or an observed fraction outside [0, 1] (a NaN
/// would pass as observed), are left out and counted in `dropped`.
std::vector<semexp::ObjectSummary> toObjectSummaries(const semantic_exploration::ObjectArray& msg,
                                                     std::size_t& dropped);

/// The finite points of a frontier cloud (float32 x, y, z). Returns "" or why
/// the cloud is malformed (missing fields, a point_step that does not hold
/// them, 0 included, row_step < width x point_step, or data other than
/// row_step x height bytes), in which case `points_W` is untouched.
std::string frontiersFromCloud(const sensor_msgs::PointCloud2& msg, std::vector<Eigen::Vector3d>& points_W);
/// A float32 x, y, z cloud of `points_W` (m) in `frame` (the inverse of frontiersFromCloud).
sensor_msgs::PointCloud2 toPointCloud(const std::vector<Eigen::Vector3d>& points_W, const ros::Time& stamp,
                                      const std::string& frame);

/// The candidates of an iteration, with their paths; the winner's path
/// carries the winner's per-vertex yaws, the others start at current_yaw_rad
/// and keep their candidate's yaw.
semantic_exploration::CandidateViewArray toCandidateViewArray(const semexp::IterationResult& r,
                                                              const std::string& frame, const ros::Time& stamp,
                                                              double current_yaw_rad);

/// The status of a finished iteration (the planner's state and iteration count come from the node), with
/// the objects' shares seen from <= d_obj and the background share seen from <= d_bg ([0, 1], -1 unknown)
/// the iteration used.
semantic_exploration::ExplorationStatus toExplorationStatus(const semexp::IterationResult& r, uint8_t state,
                                                            uint32_t iteration, const std::string& frame,
                                                            const ros::Time& stamp,
                                                            const std::vector<semexp::ObjectSummary>& objects,
                                                            double background_share);

/// The explored volume (m^3) and the background share seen from <= d_bg of a MapStats message. Returns ""
/// or why the message is unusable (a negative or non-finite volume, a share outside [0, 1] other than -1),
/// in which case nothing is written. A share of -1 (not measured yet) leaves `background_share` as it is.
std::string fromMapStats(const semantic_exploration::MapStats& msg, double& explored_volume_m3,
                         double& background_share);

/// Trajectory samples -> MultiDOFJointTrajectory with one joint, `joint`
/// (the body frame): per point the pose (translation, yaw quaternion), the
/// velocity (linear, angular z = yaw rate) and the acceleration (linear), in
/// `frame`; time_from_start from the samples, header.stamp = `stamp`.
trajectory_msgs::MultiDOFJointTrajectory toTrajectoryMsg(const std::vector<semexp::TrajectoryState>& samples,
                                                         const std::string& frame, const std::string& joint,
                                                         const ros::Time& stamp);

/// MultiDOFJointTrajectory -> timed positions and yaws. Refuses (returns
/// why, leaving `out` unchanged) a frame other than `frame` (an empty
/// frame_id is taken as `frame`), other than one joint, a point without a
/// transform, non-finite values, a zero quaternion, or time_from_start that
/// is negative or does not increase. No points is valid: `out` becomes empty.
std::string fromTrajectoryMsg(const trajectory_msgs::MultiDOFJointTrajectory& msg, const std::string& frame,
                              semexp::SampledTrajectory& out);

/// The display cut (display_cut node): copies the points of `in` whose z
/// (a FLOAT32 field "z") is finite and <= max_z_m into `out`, with the same
/// fields, header and endianness, as one row. Returns "" or why it cannot
/// (no FLOAT32 z, data shorter than width x height x point_step).
std::string cutCloudAboveZ(const sensor_msgs::PointCloud2& in, double max_z_m, sensor_msgs::PointCloud2& out);

// ---------------------------------------------------------------- map nodes

/// geometry_msgs::Point -> vector, m.
Eigen::Vector3d fromPoint(const geometry_msgs::Point& p);
/// The positions of a gain request.
std::vector<Eigen::Vector3d> fromPoints(const std::vector<geometry_msgs::Point>& points);

/// Pose message of T (translation and unit quaternion).
geometry_msgs::Pose toPose(const Eigen::Isometry3d& T);
/// T of a pose message. Returns "" or why it is not a rigid transform (a
/// quaternion of norm <= 0.5 or non-finite values); the quaternion is
/// normalised. `T` is untouched on failure.
std::string fromPose(const geometry_msgs::Pose& pose, Eigen::Isometry3d& T);
/// T of a tf transform; the quaternion is normalised (not checked: tf2 has).
Eigen::Isometry3d fromTransform(const geometry_msgs::Transform& t);

/// The MapBlocks message of a map update or snapshot (background_map's
/// ~map_update and ~get_map); fromMapBlocksMsg() reads it back.
semantic_exploration::MapBlocks toMapBlocksMsg(const semexp::MapBlocksData& blocks, const ros::Time& stamp,
                                               const std::string& frame);

/// The ObjectInfo of an object with the summary of its surface (object_map's
/// ~objects); toObjectSummaries() reads what the planner needs back.
semantic_exploration::ObjectInfo toObjectInfo(const semexp::MappedObject& object, const semexp::TsdfSummary& surface);

}  // namespace semexp_ros

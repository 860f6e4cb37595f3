#pragma once
/// @file planner_node.hpp
/// ROS shell of the next-best-view planner (paper Section IV-D).
///
/// Subscribes `background_map/map_update` (MapBlocks, kept in a replica;
/// a sequence gap triggers a `background_map/get_map` resync),
/// `background_map/frontiers` (PointCloud2 xyz), `background_map/stats`
/// (explored volume, for the no-progress stop), `object_map/objects`,
/// `mav/goal_reached`, `mav/path_rejected` (std_msgs/String: the
/// executor refused the path; replan after retry_period_s); pose from tf2 (world <- body, latest). Calls
/// `background_map/compute_gains`, `object_map/compute_gains` (with the
/// background hit depths for occlusion) and `depth_history/get_masks`, one
/// batched call each per iteration. Publishes `~path` (nav_msgs/Path, yaw in
/// orientation) and the same path time-parameterised as `~trajectory`
/// (trajectory_msgs/MultiDOFJointTrajectory, core/planning/trajectory.hpp), `~candidates` (CandidateViewArray), `~candidate_markers`,
/// `~gain_images/{entropy,background,object,combined}` (32FC1, the winner's)
/// and `~status` (ExplorationStatus); serves `~plan_once` (PlanOnce) and
/// `~get_map` (GetMap: the replica, for a respawned background_map to take
/// back the map it lost; refused while the replica is empty).
///
/// `~plan_once` with a frame_stamp (a lockstep simulator's call in
/// deterministic runs) plans only once that frame's inputs are here:
/// background_map/stats of the frame, the map update and frontier cloud
/// those stats say were published before them, and object_map/objects of the
/// frame (while object_map publishes); else it answers pending, naming what
/// is missing, and the caller asks again. Topics from different publishers
/// arrive in no fixed order, so a node's frame report does not mean its
/// other outputs of that frame have reached this node.
///
/// An iteration runs when the MAV reports its goal reached, on `~plan_once`,
/// and (while no path is being flown) every `planner/retry_period_s` once the
/// map has arrived. Object gains and history masks are optional: if their
/// services are missing the iteration goes on without them (logged);
/// background gains are required. Node parameters besides the core's
/// PlannerConfig: `planner/service_timeout_s` (the longest a service call may
/// take, finding the service included), `planner/retry_period_s`,
/// `planner/goal_timeout_factor` (replan if the goal is not reached within
/// factor * estimated path time + 10 s).
///
/// Service calls are bounded in time (PlannerServices, ServiceCaller): a call given up after
/// service_timeout_s is reported in the iteration's status (and counted in
/// ExplorationStatus::service_timeouts), the iteration goes on without an
/// optional service or ends without a path if background gains are missing,
/// and the next iteration calls again. Message conversions live in
/// conversions.hpp, the markers in planner_markers.hpp, the final path check
/// in the core (path_check.hpp).

#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/String.h>

#include <memory>
#include <string>
#include <vector>

#include "semantic_exploration/GetMap.h"
#include "semantic_exploration/MapBlocks.h"
#include "semantic_exploration/MapStats.h"
#include "semantic_exploration/ObjectArray.h"
#include "semantic_exploration/PlanOnce.h"
#include "semantic_exploration/core/planning/exploration_planner.hpp"
#include "semantic_exploration/core/planning/map_replica.hpp"
#include "semantic_exploration/ros/node_common.hpp"
#include "semantic_exploration/ros/params.hpp"
#include "semantic_exploration/ros/planner_services.hpp"

namespace semexp_ros {

class PlannerNode {
 public:
  PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  void mapUpdateCallback(const semantic_exploration::MapBlocksConstPtr& msg);
  void frontiersCallback(const sensor_msgs::PointCloud2ConstPtr& msg);
  void objectsCallback(const semantic_exploration::ObjectArrayConstPtr& msg);
  void statsCallback(const semantic_exploration::MapStatsConstPtr& msg);
  void goalReachedCallback(const geometry_msgs::PoseStampedConstPtr& msg);
  void pathRejectedCallback(const std_msgs::StringConstPtr& msg);
  void timerCallback(const ros::TimerEvent& ev);
  bool planOnce(semantic_exploration::PlanOnce::Request& req, semantic_exploration::PlanOnce::Response& res);
  bool getReplica(semantic_exploration::GetMap::Request& req, semantic_exploration::GetMap::Response& res);
  /// What of frame_stamp's inputs has not arrived yet ("" when all are here; see the file comment).
  std::string missingInputs(const ros::Time& frame_stamp) const;
  void publishStatus(uint8_t state, const std::string& message);

  /// Applies one MapBlocks message to the replica; `gap` is set when a resync is needed: a
  /// sequence skipped, or (background_map restarted) sequence 1 after a later one or any older
  /// sequence with a newer stamp than the last update applied.
  bool applyBlocks(const semantic_exploration::MapBlocks& msg, bool& gap);
  bool resync();
  /// One planning iteration; true if a path was published. `message` says what happened. `stamp`:
  /// the iteration's sim time (zero: now); `pose_stamp`: the MAV pose's stamp (zero: the latest).
  bool iterate(std::string& message, const ros::Time& stamp = ros::Time(), const ros::Time& pose_stamp = ros::Time());
  /// Publishes the path of a winner that passed the final clearance check and logs why it won.
  void publishWinner(const semexp::IterationResult& r, const ros::Time& now);
  void publishResult(const semexp::IterationResult& r, const ros::Time& stamp, double current_yaw);

  semexp::PlannerConfig config_;
  semexp::ExplorationConfig exploration_;
  semexp::PinholeCamera camera_;
  semexp::Bounds bounds_;
  FrameNames frames_;
  PlannerNodeConfig node_config_;
  semexp::TrajectoryConfig trajectory_;  ///< limits of ~trajectory besides config_'s v_max, omega_max
  std::unique_ptr<PoseSource> poses_;  ///< the MAV pose (tf2, latest)
  DropCounter drops_;
  std::unique_ptr<PlannerServices> services_;

  semexp::MapReplica replica_;
  /// Stamp of the last update applied to the replica (of the full map after a resync).
  ros::Time replica_stamp_;
  std::unique_ptr<semexp::ExplorationPlanner> planner_;
  double planner_resolution_m_ = 0.0;
  std::vector<Eigen::Vector3d> frontiers_W_;
  std::vector<semexp::ObjectSummary> objects_;
  bool have_frontiers_ = false;
  double explored_volume_m3_ = -1.0;  ///< from background_map/stats; negative until received
  double background_share_ = -1.0;    ///< surface share seen from <= d_bg, from background_map/stats; negative until received
  std::size_t map_retired_frontiers_ = 0;  ///< frontier voxels the background map retired by evidence (its stats)
  // Stamps of the inputs received, for plan_once's frame_stamp (missingInputs()).
  ros::Time stats_stamp_, frontiers_stamp_, objects_stamp_;
  ros::Time stats_frontiers_stamp_;         ///< MapStats::frontiers_stamp of the newest stats
  std::uint64_t stats_update_sequence_ = 0;  ///< MapStats::map_update_sequence of the newest stats
  semexp::TerminationConfig termination_;
  semexp::FrontierRetirementConfig retirement_;
  semexp::ObjectRetirementConfig object_retirement_;

  uint8_t state_ = 0;
  bool finished_ = false;
  std::string finish_summary_;  ///< "<termination_reason> (<why>)" once finished_, for plan_once's answer
  bool started_ = false;
  ros::Time start_time_;
  ros::Time executing_since_;
  double expected_duration_s_ = 0.0;
  ros::WallTime last_attempt_;

  ros::Subscriber update_sub_, frontiers_sub_, objects_sub_, goal_sub_, stats_sub_, rejected_sub_;
  ros::Publisher path_pub_, candidates_pub_, markers_pub_, status_pub_;
  ros::Publisher trajectory_pub_;  ///< ~trajectory (MultiDOFJointTrajectory) of each published path
  ros::Publisher gain_pubs_[4];
  ros::ServiceServer plan_srv_;
  ros::ServiceServer replica_srv_;
  ros::Timer timer_;
  uint32_t iteration_ = 0;
};

}  // namespace semexp_ros

#pragma once
/// @file frontier_retirement.hpp
/// Frontiers that no reachable camera pose can observe stop holding the
/// exploration open (paper Section IV-D ends it at F = {}; a level camera
/// with a 49 deg vertical field of view cannot look into every corner, and
/// the unknown inside of a wall behind a surface voxel that noise carved free
/// is a frontier no view resolves).
///
/// Frontier voxels are grouped into clusters, the cubes of cluster_size_m
/// holding them. A cluster is retired
///  - by geometry, when none of a fixed set of view points around it is a
///    possible camera centre (in the bounds, no occupied voxel in its
///    clearance sphere: unknown space may yet turn out free)
///    that sees it inside the vertical field of view minus fov_margin_rad,
///    within view_range_m, with no occupied voxel on the line of sight; the
///    view points lie at the reachable heights nearest the cluster's (steps
///    of 0.3 m, 5 heights), at horizontal distances from the cluster that the
///    field of view needs (steps of 0.5 m) and 12 azimuths;
///  - by evidence, after max_failed_views views that were meant to observe
///    it (the winner was a frontier candidate in it) or that had it inside the
///    field of view within view_range_m with nothing occupied between the
///    camera and the cluster's cube (poses every 0.5 m along each winning
///    path) and after which it was not at least shrink_fraction smaller than
///    at the first of those views (not than at the view before: the counts of
///    small clusters go up and down with depth noise, and each dip would
///    restart the run). A cluster that grows during a run and shrinks back,
///    but not below where the run started, has not shrunk either.
/// A cluster's "view" is one iteration whose path it was seen from, or one
/// without a winner in which no candidate had a gain at its view position and
/// a frontier candidate was drawn in it (ExplorationPlanner: the planner's own
/// gains found nothing to see there).
/// Every cluster is judged by geometry again every recheck_iterations
/// iterations (surface found since can hide it): one retired by geometry
/// comes back once a view point is possible, one retired by evidence once
/// more view points are possible than when it was retired (new free space
/// around it), at most max_evidence_returns times. Retired frontiers are not sampled and
/// do not count towards termination.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "semantic_exploration/core/bounds.hpp"
#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/config_error.hpp"
#include "semantic_exploration/core/planning/interfaces.hpp"

namespace semexp {

struct FrontierRetirementConfig {
  bool enabled = true;              ///< false: every frontier stays active
  double cluster_size_m = 0.5;      ///< edge of the cubes that group frontier voxels, m
  int max_failed_views = 3;         ///< views that did not shrink a cluster before it is retired (K)
  double shrink_fraction = 0.2;     ///< a view shrinks a cluster when its voxel count drops by this fraction, (0, 1]
  double view_range_m = 3.0;        ///< farthest view point / view that counts, m (the paper's d_bg)
  double min_view_distance_m = 0.3; ///< nearest horizontal standoff of a view point, m
  double fov_margin_rad = 0.05;     ///< a cluster must lie this far inside the vertical field of view, rad
  int recheck_iterations = 5;       ///< clusters are judged by geometry again this often, iterations
  /// Times a cluster retired by evidence may come back when more view points
  /// become possible; after that it stays retired by evidence (-1 = no limit).
  /// Depth noise carving free space in front of a window grows the view
  /// points one by one, and each return costs K more views.
  int max_evidence_returns = -1;

  void validate(const std::string& ns = "frontier_retirement/") const {
    require(std::isfinite(cluster_size_m) && cluster_size_m > 0, ns + "cluster_size_m", "must be > 0 m");
    require(max_failed_views > 0, ns + "max_failed_views", "must be > 0");
    require(std::isfinite(shrink_fraction) && shrink_fraction > 0 && shrink_fraction <= 1, ns + "shrink_fraction",
            "must be in (0, 1]");
    require(std::isfinite(view_range_m) && view_range_m > 0, ns + "view_range_m", "must be > 0 m");
    require(std::isfinite(min_view_distance_m) && min_view_distance_m >= 0, ns + "min_view_distance_m",
            "must be >= 0 m");
    require(std::isfinite(fov_margin_rad) && fov_margin_rad >= 0, ns + "fov_margin_rad", "must be >= 0 rad");
    require(recheck_iterations > 0, ns + "recheck_iterations", "must be > 0");
    require(max_evidence_returns >= -1, ns + "max_evidence_returns", "must be >= 0, or -1 for no limit");
    // Otherwise no view point exists anywhere and every frontier would be retired at once.
    require(min_view_distance_m < view_range_m, ns + "min_view_distance_m", "must be < view_range_m");
    require(view_range_m <= 20.0, ns + "view_range_m", "must be <= 20 m (view points per cluster grow with it)");
  }
};

/// A camera pose a view was taken from: position and yaw (level camera).
struct ViewPose {
  Eigen::Vector3d position_W = Eigen::Vector3d::Zero();  ///< m
  double yaw_rad = 0.0;                                  ///< rad
};

class FrontierRetirement {
 public:
  /// Where a camera centre can be: inside `bounds`, with no occupied voxel
  /// within clearance_radius_m (m). The camera gives the fields of view. Throws
  /// ConfigError on an invalid config, a fov_margin_rad that leaves no
  /// vertical field of view or bounds too low for a camera centre.
  FrontierRetirement(const FrontierRetirementConfig& config, const PinholeCamera& camera, const Bounds& bounds,
                     double clearance_radius_m, double map_resolution_m);

  /// The frontier voxels of one iteration, split.
  struct Split {
    std::vector<Eigen::Vector3d> active_W;
    std::vector<Eigen::Vector3d> retired_W;
    std::size_t clusters = 0;             ///< clusters holding frontier voxels
    std::size_t retired_by_geometry = 0;  ///< of those, retired clusters
    std::size_t retired_by_evidence = 0;
  };

  /// Judges this iteration's frontiers. The views recorded since the last
  /// call (recordViews) count as evidence now. not_occupied: sphere queries
  /// with unknown space allowed (radius 0 = the voxel at the point).
  /// line_not_occupied (optional): the lines of sight asked at once, with the
  /// same answers as not_occupied point by point.
  Split update(const std::vector<Eigen::Vector3d>& frontiers_W, const CollisionQuery& not_occupied,
               const LineQuery& line_not_occupied = {});

  /// The poses the camera will look from while the published path is flown,
  /// and the frontier voxels the path was chosen to observe (a frontier
  /// candidate's goal): the clusters of the targets and every active cluster
  /// a pose sees count as viewed; whether they shrank is judged at the next
  /// update(). Without poses: an iteration without a winner whose frontier
  /// candidates (the targets) had nothing to see (ExplorationPlanner).
  void recordViews(const std::vector<ViewPose>& poses, const CollisionQuery& not_occupied,
                   const std::vector<Eigen::Vector3d>& targets_W = {}, const LineQuery& line_not_occupied = {});

  /// The views recorded last were not flown (the path was dropped or rejected): not judged.
  void discardViews();

  /// Possible view points of a cluster at `centre_W` (0 = not observable).
  /// `stop_at` > 0 stops counting there.
  int viewPoints(const Eigen::Vector3d& centre_W, const CollisionQuery& not_occupied, int stop_at = 0,
                 const LineQuery& line_not_occupied = {}) const;

  /// Whether `pose` sees `p_W` inside both fields of view, within view_range_m, with a clear line of sight.
  bool sees(const ViewPose& pose, const Eigen::Vector3d& p_W, const CollisionQuery& not_occupied,
            const LineQuery& line_not_occupied = {}) const;

  const FrontierRetirementConfig& config() const { return config_; }
  /// Distinct clusters (cubes) retired by evidence so far, each counted once:
  /// one that comes back and is retired again is no new progress, so the
  /// count is bounded by the cubes the bounds hold.
  std::size_t evidenceRetirements() const { return ever_retired_by_evidence_.size(); }

 private:
  struct Cluster {
    int voxels = 0;               ///< frontier voxels now
    int failed_views = 0;
    int viewpoints_at_retirement = 0;  ///< possible view points when retired by evidence
    /// Per view point (viewPointPositions order around centre_at_retirement_W): possible at retirement.
    std::vector<bool> possible_at_retirement;
    Eigen::Vector3d centre_at_retirement_W = Eigen::Vector3d::Zero();
    long judged_at = -1;          ///< iteration of the last geometry judgement
    bool by_geometry = false;
    bool by_evidence = false;
    int voxels_at_view = -1;      ///< voxel count when a view of it was recorded (-1 none)
    /// Voxel count at the first view of the current run of failed views (-1
    /// none): a view shrank the cluster only if it fell shrink_fraction below
    /// this, so a count that noise moves up and down does not restart the run.
    int voxels_at_first_view = -1;
    Eigen::Vector3d centre_W = Eigen::Vector3d::Zero();  ///< mean of its frontier voxels, m
  };
  /// Whether more view points are possible now than before, and any at all.
  struct Recount {
    bool any = false;
    bool more = false;
  };
  std::uint64_t key(const Eigen::Vector3d& p_W) const;
  /// The view points tried around a cluster at c_W, in a fixed order (heights, distances, azimuths), m.
  std::vector<Eigen::Vector3d> viewPointPositions(const Eigen::Vector3d& c_W) const;
  /// p_W is a possible camera centre that sees c_W.
  bool possibleViewPoint(const Eigen::Vector3d& p_W, const Eigen::Vector3d& c_W, const CollisionQuery& not_occupied,
                         const LineQuery& line) const;
  /// Per view point of viewPointPositions(c_W): possible.
  std::vector<bool> possibleViewPoints(const Eigen::Vector3d& c_W, const CollisionQuery& not_occupied,
                                       const LineQuery& line) const;
  /// The same answer as comparing viewPoints(c_W) with the count of `before`
  /// (the possible view points around the same c_W earlier), judging only
  /// as many view points as the comparison needs.
  Recount recount(const Eigen::Vector3d& c_W, const std::vector<bool>& before, const CollisionQuery& not_occupied,
                  const LineQuery& line) const;
  /// Whether the cluster of `cube`, retired by evidence, may come back now
  /// (max_evidence_returns); counts the return when it may.
  bool takeEvidenceReturn(std::uint64_t cube);
  /// No occupied voxel on the segment from `from_W` up to short_m (m) before
  /// `to_W`, at points one map resolution apart: asked of `line` at once when
  /// there is one, else of not_occupied point by point.
  bool lineOfSight(const Eigen::Vector3d& from_W, const Eigen::Vector3d& to_W, double short_m,
                   const CollisionQuery& not_occupied, const LineQuery& line) const;

  FrontierRetirementConfig config_;
  PinholeCamera camera_;
  Bounds bounds_;
  double clearance_radius_m_;
  double resolution_m_;
  std::unordered_map<std::uint64_t, Cluster> clusters_;
  long iteration_ = 0;
  std::unordered_set<std::uint64_t> ever_retired_by_evidence_;  ///< keys of the clusters evidenceRetirements() counts
  /// Per cube: times its cluster came back from retirement by evidence. Kept
  /// by key, not in the Cluster, which is dropped while its cube holds no
  /// frontier voxel: noise that empties a cube for an iteration must not
  /// reset the count max_evidence_returns limits.
  std::unordered_map<std::uint64_t, int> evidence_returns_;
};

}  // namespace semexp

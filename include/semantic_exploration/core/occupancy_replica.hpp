#pragma once
/// @file occupancy_replica.hpp
/// A copy of the background map fed by MapBlocks updates (DESIGN Section 3,
/// "Why a map replica"): what the planner collision-checks against.

#include <memory>

#include "semantic_exploration/core/occupancy_map.hpp"

namespace semexp {

/// Applies sequence-numbered MapBlocks updates in order and answers the
/// same occupancy queries as OccupancyMap (log-odds quantised to 0.1; colour
/// and observed distance are not replicated).
class OccupancyReplica {
 public:
  enum class Result {
    kApplied,  ///< in order (or a full map): applied
    kStale,    ///< sequence already seen: ignored
    kGap,      ///< a message was lost: applied anyway, but call for a full map (needsResync())
    kRejected  ///< unsupported encoding or malformed message: ignored
  };

  /// `config` supplies resolution and block size defaults; the geometry of the
  /// first message wins if it differs. `bounds` should be the source's bounds.
  OccupancyReplica(const BackgroundMapConfig& config, const Bounds& bounds);

  Result apply(const MapBlocksData& msg);
  /// True from the start until a full map arrives, and after every gap.
  bool needsResync() const { return needs_resync_; }
  /// Sequence of the last applied message (0 before any).
  std::uint64_t sequence() const { return sequence_; }

  const OccupancyMap& map() const { return *map_; }
  VoxelState state(const Eigen::Vector3d& p_W) const { return map_->state(p_W); }
  bool isSphereFree(const Eigen::Vector3d& centre_W, double radius_m) const {
    return map_->isSphereFree(centre_W, radius_m);
  }
  RaycastHit raycast(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& dir_W, double max_range_m,
                     bool stop_at_unknown = false) const {
    return map_->raycast(origin_W, dir_W, max_range_m, stop_at_unknown);
  }

 private:
  bool matches(const MapBlocksData& msg) const;

  BackgroundMapConfig config_;
  Bounds bounds_;
  std::unique_ptr<OccupancyMap> map_;
  std::uint64_t sequence_ = 0;
  bool needs_resync_ = true;
};

}  // namespace semexp

#pragma once
/// @file map_replica.hpp
/// The planner's copy of the background map, fed by MapBlocks updates
/// (DESIGN Section 3 "Why a map replica"), answering the sphere queries of
/// path planning without a service round trip.
///
/// Payload encoding: core/map_blocks.hpp. A voxel is free when its value is
/// < free_below (default 0, i.e. log-odds < 0), else occupied. Missing blocks are unknown. A block whose voxels all hold one
/// value may come as that value alone (MapBlocksData::uniform_*, a compact
/// GetMap snapshot) and is kept as one value.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "semantic_exploration/core/map_blocks.hpp"

namespace semexp {

class MapReplica {
 public:
  using State = VoxelState;  ///< the codec's one state enum
  enum class Result {
    kApplied,   ///< the update was applied
    kGap,       ///< a sequence number was skipped (or the first update is incremental): resync with a full map
    kStale,     ///< an old or repeated sequence number: ignored
    kBadInput,  ///< inconsistent sizes or geometry: ignored (see lastError())
  };

  explicit MapReplica(int free_below = 0) : free_below_(free_below) {}

  /// Applies one MapBlocks update (the codec's data type: the map's
  /// takeUpdate() or snapshot(), or a message through the ROS converter). A
  /// full update always applies (it replaces everything); an incremental one
  /// only if its sequence follows the last. Uniform blocks apply after the others.
  Result apply(const MapBlocksData& u);

  /// The replica as a full map (full = true, the last applied sequence),
  /// blocks in key order; a block kept as one value goes out as that value
  /// (uniform_*). OccupancyMap::applyBlocks reads it back: how a restarted
  /// background map gets the map it lost from the planner's copy.
  MapBlocksData snapshot() const;

  std::uint64_t sequence() const { return sequence_; }
  bool empty() const { return blocks_.empty(); }
  std::size_t blockCount() const { return blocks_.size(); }
  double resolution_m() const { return resolution_m_; }
  const std::string& lastError() const { return last_error_; }

  State state(const Eigen::Vector3d& p_W) const;
  /// Every voxel meeting the sphere is free (unknown is not free).
  bool sphereFree(const Eigen::Vector3d& p_W, double radius_m) const { return sphereCheck(p_W, radius_m, false); }
  /// No voxel meeting the sphere is occupied (unknown allowed).
  bool sphereNotOccupied(const Eigen::Vector3d& p_W, double radius_m) const {
    return sphereCheck(p_W, radius_m, true);
  }
  /// No occupied voxel at the points from_W + t u_W, t = 0, step_m, ... <= length_m
  /// (t summed step by step): exactly sphereNotOccupied(point, 0) at each,
  /// with one block look-up per block the points cross instead of one per
  /// point, and none of a block's voxels read when it holds nothing occupied
  /// (a LineQuery). m; step_m > 0.
  bool lineNotOccupied(const Eigen::Vector3d& from_W, const Eigen::Vector3d& u_W, double length_m,
                       double step_m) const;

 private:
  struct Block {
    std::vector<std::int8_t> values;  ///< block_size^3, or empty: every voxel holds `uniform`
    std::int8_t uniform = 0;
    int unknown = 0;   ///< voxels with -128
    int occupied = 0;  ///< voxels >= free_below
    std::int8_t at(std::size_t i) const { return values.empty() ? uniform : values[i]; }
  };
  static std::uint64_t key(const Eigen::Vector3i& b);
  static Eigen::Vector3i blockOf(std::uint64_t key);  ///< the inverse of key()
  bool sphereCheck(const Eigen::Vector3d& p, double r, bool allow_unknown) const;
  /// The voxel of global index v comes within sqrt(r2) of p (m^2; 0: p lies in it, borders included).
  bool voxelWithin(const Eigen::Vector3d& p, const Eigen::Vector3i& v, double r2) const;

  int free_below_;
  std::uint64_t sequence_ = 0;
  double resolution_m_ = 0.0;
  int block_size_ = 0;
  Eigen::Vector3d origin_W_ = Eigen::Vector3d::Zero();
  std::unordered_map<std::uint64_t, Block> blocks_;
  std::string last_error_;
};

}  // namespace semexp

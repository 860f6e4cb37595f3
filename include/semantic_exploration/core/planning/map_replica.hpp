#pragma once
/// @file map_replica.hpp
/// The planner's copy of the background map, fed by MapBlocks updates
/// (DESIGN Section 3 "Why a map replica"), answering the sphere queries of
/// path planning without a service round trip.
///
/// Payload encoding: core/map_blocks.hpp. A voxel is free when its value is
/// < free_below (default 0, i.e. log-odds < 0), else occupied. Missing blocks are unknown. A block whose voxels all hold one
/// value may come as that value alone (Update::uniform_*, a compact GetMap
/// snapshot) and is kept as one value.

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

  /// One MapBlocks message, without ROS types.
  struct Update {
    std::uint64_t sequence = 0;
    bool full = false;
    double resolution_m = 0.0;
    int block_size = 8;
    Eigen::Vector3d origin_W = Eigen::Vector3d::Zero();  ///< minimum corner of voxel (0, 0, 0), m
    const std::int32_t* coords = nullptr;                ///< 3 per block
    std::size_t coord_count = 0;                         ///< number of int32 values in coords
    const std::uint8_t* payload = nullptr;               ///< block_size^3 per block
    std::size_t payload_size = 0;
    /// Uniform blocks (MapBlocks uniform_coords / uniform_values): 3 coordinates and one value each,
    /// applied after the blocks above.
    const std::int32_t* uniform_coords = nullptr;
    std::size_t uniform_coord_count = 0;  ///< number of int32 values in uniform_coords
    const std::uint8_t* uniform_values = nullptr;
    std::size_t uniform_value_count = 0;
  };

  explicit MapReplica(int free_below = 0) : free_below_(free_below) {}

  /// Applies an update. A full update always applies (it replaces
  /// everything); an incremental one only if its sequence follows the last.
  Result apply(const Update& u);

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

 private:
  struct Block {
    std::vector<std::int8_t> values;  ///< block_size^3, or empty: every voxel holds `uniform`
    std::int8_t uniform = 0;
    int unknown = 0;   ///< voxels with -128
    int occupied = 0;  ///< voxels >= free_below
    std::int8_t at(std::size_t i) const { return values.empty() ? uniform : values[i]; }
  };
  static std::uint64_t key(const Eigen::Vector3i& b);
  bool sphereCheck(const Eigen::Vector3d& p, double r, bool allow_unknown) const;

  int free_below_;
  std::uint64_t sequence_ = 0;
  double resolution_m_ = 0.0;
  int block_size_ = 0;
  Eigen::Vector3d origin_W_ = Eigen::Vector3d::Zero();
  std::unordered_map<std::uint64_t, Block> blocks_;
  std::string last_error_;
};

}  // namespace semexp

#pragma once
/// @file map_blocks.hpp
/// The map-block codec: the one voxel state enum, the one ROS-free form of
/// msg/MapBlocks.msg and its int8 log-odds encoding, shared by the background
/// map (takeUpdate, snapshot, applyBlocks), the planner's MapReplica and the
/// ROS conversion.
///
/// Encoding (MapBlocks ENCODING_LOG_ODDS_I8): one int8 per voxel, x fastest,
/// then y, then z; log-odds x 10 rounded and clamped to [-127, 127]; -128 =
/// unknown. Negative log-odds stay negative (-0.04 -> -1, not 0), so a
/// replica classifies every voxel as the source does: free below 0, occupied
/// from 0 on.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace semexp {

enum class VoxelState : std::uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

/// ROS-free twin of msg/MapBlocks.msg (see there for the field meanings).
struct MapBlocksData {
  static constexpr std::uint8_t kEncodingLogOddsI8 = 0;  ///< the int8 encoding of map_blocks below
  static constexpr std::int8_t kUnknownI8 = -128;         ///< an unknown voxel

  std::uint64_t sequence = 0;  ///< 1 for the first update; a full map carries the last published sequence
  bool full = false;           ///< true: the blocks are the whole map
  double resolution_m = 0.0;   ///< finest voxel edge, m
  int block_size = 0;          ///< voxels per block edge
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();  ///< minimum corner of voxel (0,0,0), world, m
  std::uint8_t encoding = kEncodingLogOddsI8;
  std::vector<std::int32_t> coords;  ///< 3 per block (x, y, z) block coordinates
  std::vector<std::int8_t> payload;  ///< block_size^3 per block, x fastest, then y, then z
  /// Blocks whose voxels all hold one value (a compact snapshot): 3 coordinates and one value each.
  std::vector<std::int32_t> uniform_coords;
  std::vector<std::int8_t> uniform_values;

  std::size_t blockCount() const { return coords.size() / 3; }
  /// Bytes of coordinates and values: what the message carries besides its header.
  std::size_t byteSize() const {
    return 4 * (coords.size() + uniform_coords.size()) + payload.size() + uniform_values.size();
  }
};

namespace map_blocks {

constexpr std::int8_t kUnknownI8 = MapBlocksData::kUnknownI8;
constexpr int kI8PerLogOdds = 10;  ///< encoded steps per unit log-odds
constexpr int kMilliPerI8 = 1000 / kI8PerLogOdds;  ///< the map's stored thousandths per encoded step

/// Encodes log-odds held in thousandths (the map's fixed point; INT16_MIN = unknown).
inline std::int8_t encodeMilli(std::int16_t l_milli) {
  if (l_milli == INT16_MIN) return kUnknownI8;
  long q = std::lround(l_milli / static_cast<double>(kMilliPerI8));
  q = std::clamp(q, -127L, 127L);
  if (l_milli < 0 && q >= 0) q = -1;
  return static_cast<std::int8_t>(q);
}
/// Decodes to thousandths (INT16_MIN = unknown).
inline std::int16_t decodeMilli(std::int8_t q) {
  return q == kUnknownI8 ? static_cast<std::int16_t>(INT16_MIN) : static_cast<std::int16_t>(q * kMilliPerI8);
}
/// State of an encoded voxel; free when below `free_below` (0: log-odds < 0).
inline VoxelState stateOf(std::int8_t q, int free_below = 0) {
  if (q == kUnknownI8) return VoxelState::kUnknown;
  return q < free_below ? VoxelState::kFree : VoxelState::kOccupied;
}

}  // namespace map_blocks
}  // namespace semexp

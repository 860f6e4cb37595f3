#include "semantic_exploration/core/planning/map_replica.hpp"

#include "semantic_exploration/core/int_math.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace semexp {

namespace {
constexpr std::int8_t kUnknownValue = map_blocks::kUnknownI8;
// Block coordinates are packed 21 bits each (+-1M blocks per axis).
constexpr std::int64_t kOffset = 1 << 20;
}  // namespace

std::uint64_t MapReplica::key(const Eigen::Vector3i& b) {
  return (static_cast<std::uint64_t>(b.x() + kOffset) << 42) | (static_cast<std::uint64_t>(b.y() + kOffset) << 21) |
         static_cast<std::uint64_t>(b.z() + kOffset);
}

Eigen::Vector3i MapReplica::blockOf(std::uint64_t k) {
  constexpr std::uint64_t kMask = (std::uint64_t{1} << 21) - 1;
  return Eigen::Vector3i(static_cast<int>(static_cast<std::int64_t>((k >> 42) & kMask) - kOffset),
                         static_cast<int>(static_cast<std::int64_t>((k >> 21) & kMask) - kOffset),
                         static_cast<int>(static_cast<std::int64_t>(k & kMask) - kOffset));
}

MapBlocksData MapReplica::snapshot() const {
  MapBlocksData out;
  out.sequence = sequence_;
  out.full = true;
  out.resolution_m = resolution_m_;
  out.block_size = block_size_;
  out.origin_m = origin_W_;
  std::vector<std::uint64_t> keys;
  keys.reserve(blocks_.size());
  for (const auto& kv : blocks_) keys.push_back(kv.first);
  std::sort(keys.begin(), keys.end());  // the same replica gives the same bytes
  for (const std::uint64_t k : keys) {
    const Block& blk = blocks_.at(k);
    const Eigen::Vector3i c = blockOf(k);
    if (blk.values.empty()) {
      out.uniform_coords.insert(out.uniform_coords.end(), {c.x(), c.y(), c.z()});
      out.uniform_values.push_back(blk.uniform);
    } else {
      out.coords.insert(out.coords.end(), {c.x(), c.y(), c.z()});
      out.payload.insert(out.payload.end(), blk.values.begin(), blk.values.end());
    }
  }
  return out;
}

MapReplica::Result MapReplica::apply(const MapBlocksData& u) {
  if (!(std::isfinite(u.resolution_m) && u.resolution_m > 0) || u.block_size <= 0 || u.block_size > 64 ||
      !u.origin_m.allFinite()) {
    last_error_ = "bad geometry (resolution, block size or origin)";
    return Result::kBadInput;
  }
  const std::size_t voxels = static_cast<std::size_t>(u.block_size) * u.block_size * u.block_size;
  if (u.coords.size() % 3 != 0 || u.payload.size() != u.blockCount() * voxels) {
    last_error_ = "coords/payload sizes disagree: " + std::to_string(u.coords.size()) + " coords, " +
                  std::to_string(u.payload.size()) + " payload bytes";
    return Result::kBadInput;
  }
  if (u.uniform_coords.size() != 3 * u.uniform_values.size()) {
    last_error_ = "uniform coords/values sizes disagree: " + std::to_string(u.uniform_coords.size()) + " coords, " +
                  std::to_string(u.uniform_values.size()) + " values";
    return Result::kBadInput;
  }
  if (!u.full) {
    if (sequence_ != 0 && u.sequence <= sequence_) return Result::kStale;
    if (u.sequence != sequence_ + 1) return Result::kGap;
    if (u.block_size != block_size_ || std::abs(u.resolution_m - resolution_m_) > 1e-9 ||
        (u.origin_m - origin_W_).norm() > 1e-9) {
      if (!blocks_.empty()) {
        last_error_ = "geometry changed in an incremental update";
        return Result::kGap;
      }
    }
  } else {
    blocks_.clear();
  }
  resolution_m_ = u.resolution_m;
  block_size_ = u.block_size;
  origin_W_ = u.origin_m;
  for (std::size_t b = 0; b < u.blockCount(); ++b) {
    const Eigen::Vector3i c(u.coords[3 * b], u.coords[3 * b + 1], u.coords[3 * b + 2]);
    Block& blk = blocks_[key(c)];
    const std::int8_t* src = u.payload.data() + b * voxels;
    blk.values.assign(src, src + voxels);
    blk.unknown = blk.occupied = 0;
    for (const std::int8_t v : blk.values) {
      if (v == kUnknownValue)
        ++blk.unknown;
      else if (v >= free_below_)
        ++blk.occupied;
    }
  }
  for (std::size_t b = 0; b < u.uniform_values.size(); ++b) {
    const Eigen::Vector3i c(u.uniform_coords[3 * b], u.uniform_coords[3 * b + 1], u.uniform_coords[3 * b + 2]);
    Block& blk = blocks_[key(c)];
    blk.values.clear();
    blk.values.shrink_to_fit();
    blk.uniform = u.uniform_values[b];
    const int n = static_cast<int>(voxels);
    blk.unknown = blk.uniform == kUnknownValue ? n : 0;
    blk.occupied = blk.uniform != kUnknownValue && blk.uniform >= free_below_ ? n : 0;
  }
  sequence_ = u.sequence;
  return Result::kApplied;
}

MapReplica::State MapReplica::state(const Eigen::Vector3d& p) const {
  if (blocks_.empty()) return State::kUnknown;
  const Eigen::Vector3i v = ((p - origin_W_) / resolution_m_).array().floor().cast<int>();
  const Eigen::Vector3i b = (v.cast<double>() / block_size_).array().floor().cast<int>();
  const auto it = blocks_.find(key(b));
  if (it == blocks_.end()) return State::kUnknown;
  const Eigen::Vector3i l = v - b * block_size_;
  const std::int8_t x = it->second.at((static_cast<std::size_t>(l.z()) * block_size_ + l.y()) * block_size_ + l.x());
  return map_blocks::stateOf(x, free_below_);
}

bool MapReplica::voxelWithin(const Eigen::Vector3d& p, const Eigen::Vector3i& v, double r2) const {
  const Eigen::Vector3d c = origin_W_ + (v.cast<double>().array() + 0.5).matrix() * resolution_m_;
  const Eigen::Vector3d d = ((p - c).cwiseAbs().array() - 0.5 * resolution_m_).cwiseMax(0.0);
  return d.squaredNorm() <= r2;
}

bool MapReplica::sphereCheck(const Eigen::Vector3d& p, double r, bool allow_unknown) const {
  if (blocks_.empty() || !p.allFinite()) return allow_unknown;
  const double res = resolution_m_;
  const Eigen::Vector3i lo = ((p.array() - r - origin_W_.array()) / res).floor().cast<int>();
  const Eigen::Vector3i hi = ((p.array() + r - origin_W_.array()) / res).floor().cast<int>();
  const int bs = block_size_;
  const Eigen::Vector3i blo(floorDiv(lo.x(), bs), floorDiv(lo.y(), bs), floorDiv(lo.z(), bs));
  const Eigen::Vector3i bhi(floorDiv(hi.x(), bs), floorDiv(hi.y(), bs), floorDiv(hi.z(), bs));
  const double r2 = r * r;
  for (int bz = blo.z(); bz <= bhi.z(); ++bz)
    for (int by = blo.y(); by <= bhi.y(); ++by)
      for (int bx = blo.x(); bx <= bhi.x(); ++bx) {
        const Eigen::Vector3i b(bx, by, bz);
        const auto it = blocks_.find(key(b));
        if (it == blocks_.end()) {
          if (allow_unknown) continue;
          return false;
        }
        const Block& blk = it->second;
        if (blk.occupied == 0 && (allow_unknown || blk.unknown == 0)) continue;  // nothing here can fail
        const Eigen::Vector3i base = b * bs;
        const Eigen::Vector3i from = (lo - base).cwiseMax(0), to = (hi - base).cwiseMin(bs - 1);
        for (int z = from.z(); z <= to.z(); ++z)
          for (int y = from.y(); y <= to.y(); ++y)
            for (int x = from.x(); x <= to.x(); ++x) {
              const std::int8_t v = blk.at((static_cast<std::size_t>(z) * bs + y) * bs + x);
              const bool bad = v == kUnknownValue ? !allow_unknown : v >= free_below_;
              if (bad && voxelWithin(p, base + Eigen::Vector3i(x, y, z), r2)) return false;
            }
      }
  return true;
}

bool MapReplica::lineNotOccupied(const Eigen::Vector3d& from, const Eigen::Vector3d& u, double length_m,
                                 double step_m) const {
  if (!(step_m > 0.0)) throw std::invalid_argument("MapReplica::lineNotOccupied: step_m must be > 0");
  if (blocks_.empty()) return true;
  const double res = resolution_m_;
  const int bs = block_size_;
  bool cached = false;
  Eigen::Vector3i cached_b(0, 0, 0);
  const Block* blk = nullptr;  // of cached_b; nullptr: not in the map (unknown)
  for (double t = 0.0; t <= length_m; t += step_m) {
    const Eigen::Vector3d p = from + t * u;
    if (!p.allFinite()) continue;  // as sphereCheck: nothing to say about it
    // The voxel and block sphereCheck(p, 0) reads (p - 0 is p exactly).
    const Eigen::Vector3i v = ((p.array() - origin_W_.array()) / res).floor().cast<int>();
    const Eigen::Vector3i b(floorDiv(v.x(), bs), floorDiv(v.y(), bs), floorDiv(v.z(), bs));
    if (!cached || b != cached_b) {
      const auto it = blocks_.find(key(b));
      blk = it == blocks_.end() ? nullptr : &it->second;
      cached_b = b;
      cached = true;
    }
    if (blk == nullptr || blk->occupied == 0) continue;
    const Eigen::Vector3i base = b * bs;
    const Eigen::Vector3i l = v - base;
    const std::int8_t x = blk->at((static_cast<std::size_t>(l.z()) * bs + l.y()) * bs + l.x());
    // sphereCheck's distance test at radius 0, for a point on the voxel's border after rounding.
    if (x != kUnknownValue && x >= free_below_ && voxelWithin(p, v, 0.0)) return false;
  }
  return true;
}

}  // namespace semexp

// Replica of the background map fed by MapBlocks messages.
#include "semantic_exploration/core/occupancy_replica.hpp"

#include <cmath>

namespace semexp {

namespace {
// The message carries the resolution as float32: recover the double the source used.
double cleanResolution(double r) { return std::round(r * 1e7) / 1e7; }
}  // namespace

OccupancyReplica::OccupancyReplica(const BackgroundMapConfig& config, const Bounds& bounds)
    : config_(config), bounds_(bounds) {
  config_.integrate_colour = false;  // not replicated
  config_.integrate_min_distance = false;
  map_ = std::make_unique<OccupancyMap>(config_, bounds_);
}

bool OccupancyReplica::matches(const MapBlocksData& msg) const {
  return msg.block_size == map_->blockSize() && std::abs(msg.resolution_m - map_->resolution()) <= 1e-6 * map_->resolution() &&
         (msg.origin_m - map_->origin()).cwiseAbs().maxCoeff() <= 1e-3 * map_->resolution();
}

OccupancyReplica::Result OccupancyReplica::apply(const MapBlocksData& msg) {
  if (msg.encoding != MapBlocksData::kEncodingLogOddsI8 || msg.coords.size() % 3 != 0 ||
      msg.block_size <= 0 || msg.payload.size() != msg.blockCount() * static_cast<std::size_t>(msg.block_size) *
                                                      msg.block_size * msg.block_size)
    return Result::kRejected;
  if (!msg.full && sequence_ != 0 && msg.sequence <= sequence_) return Result::kStale;
  if (!matches(msg)) {
    if (!msg.full) {
      needs_resync_ = true;
      return Result::kGap;  // cannot place these blocks; a full map will rebuild the geometry
    }
    BackgroundMapConfig c = config_;
    c.resolution_m = cleanResolution(msg.resolution_m);
    c.block_size = msg.block_size;
    Bounds b = bounds_;
    b.min_m = msg.origin_m;
    b.max_m = b.max_m.cwiseMax(b.min_m + Eigen::Vector3d::Constant(c.resolution_m));
    map_ = std::make_unique<OccupancyMap>(c, b);
    if (!matches(msg)) return Result::kRejected;
  }
  if (!map_->applyBlocks(msg)) return Result::kRejected;
  Result r = Result::kApplied;
  if (msg.full) {
    needs_resync_ = false;
  } else if (msg.sequence != sequence_ + 1) {
    needs_resync_ = true;
    r = Result::kGap;
  }
  sequence_ = msg.sequence;
  return r;
}

}  // namespace semexp

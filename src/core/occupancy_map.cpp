// Background occupancy map: construction, integration entry points, summary
// refresh, the free start sphere and the volume figures. The work is done by
// the parts in src/core/occupancy/.
#include "semantic_exploration/core/occupancy_map.hpp"

#include "semantic_exploration/core/gains.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <stdexcept>

namespace semexp {

using occupancy::kNoDist;
using occupancy::kScale;
using occupancy::isFreeValue;
using occupancy::kUnknown;
using occupancy::Summary;
using occupancy::toFixed;

OccupancyMap::OccupancyMap(const BackgroundMapConfig& config, const Bounds& bounds)
    : cfg_((config.validate(), config)),
      bounds_((bounds.validate(), bounds)),
      store_(cfg_.resolution_m, cfg_.block_size, bounds_, cfg_.integrate_colour),
      integrator_(cfg_) {
  l_free_ = toFixed(cfg_.log_odds_free);
  l_min_ = toFixed(cfg_.log_odds_min);
  l_max_ = toFixed(cfg_.log_odds_max);
  // Reducible entropy (gains.hpp) of every storable log-odds value, indexed by value - l_min_.
  entropy_lut_.resize(static_cast<std::size_t>(l_max_ - l_min_ + 1));
  for (std::size_t i = 0; i < entropy_lut_.size(); ++i)
    entropy_lut_[i] = static_cast<float>(reducibleEntropy((l_min_ + static_cast<int>(i)) / kScale, l_min_ / kScale,
                                                          l_max_ / kScale));
  frontiers_.reset(store_.cellCount(), store_.fwords);
  dirty_.assign(store_.cellCount(), 0);
}

void OccupancyMap::releaseBlock(int cell) {
  frontiers_.onBlockReleased(store_, cell);
  store_.releaseBlock(cell);
}

void OccupancyMap::releaseFreeBlock(int cell, std::int16_t l) {
  releaseBlock(cell);
  store_.cell_value[cell] = l;
  store_.cell_dist[cell] = kNoDist;  // free voxels carry no surface distance
}

// ------------------------------------------------------------ integration

IntegrationStats OccupancyMap::integrate(const cv::Mat& depth, const cv::Mat& rgb, const PinholeCamera& camera,
                                         const Eigen::Isometry3d& T_WC) {
  if (depth.rows != camera.height || depth.cols != camera.width)
    throw std::invalid_argument("depth image size disagrees with the camera intrinsics");
  if (!rgb.empty() && (rgb.rows != depth.rows || rgb.cols != depth.cols || rgb.type() != CV_8UC3))
    throw std::invalid_argument("colour image must be CV_8UC3 of the depth image's size");
  cv::Mat d32;
  if (depth.type() == CV_32FC1)
    d32 = depth.isContinuous() ? depth : depth.clone();
  else if (depth.type() == CV_16UC1)
    depth.convertTo(d32, CV_32FC1, 0.001);
  else
    throw std::invalid_argument("depth image must be CV_32FC1 (m) or CV_16UC1 (mm)");
  cv::Mat c;
  if (!rgb.empty()) c = rgb.isContinuous() ? rgb : rgb.clone();
  return integrate(d32.ptr<float>(), c.empty() ? nullptr : c.ptr<std::uint8_t>(), camera, T_WC);
}

IntegrationStats OccupancyMap::integrate(const float* depth_m, const std::uint8_t* rgb, const PinholeCamera& camera,
                                         const Eigen::Isometry3d& T_WC) {
  changed_scratch_.clear();
  surface_scratch_.clear();
  const IntegrationStats stats =
      integrator_.integrate(store_, depth_m, rgb, camera, T_WC, changed_scratch_, &surface_scratch_);
  integrator_.summarise(store_, changed_scratch_, summary_scratch_);
  refreshSummaries(changed_scratch_, true, &summary_scratch_, SurfaceMarks::kByCaller);
  // A frame's log-odds changes mostly stay within free or occupied: only the cells where a voxel changed state
  // (and their neighbours) or an occupied voxel's distance was lowered are counted again.
  const occupancy::SurfaceRule surface_rule = surfaceMarkingRule();
  for (const int c : surface_scratch_.state_changed) surface_counter_.occupancyChanged(store_, c, surface_rule);
  for (const int c : surface_scratch_.distance_changed) surface_counter_.distanceChanged(c);
  return stats;
}

void OccupancyMap::refreshSummaries(const std::vector<int>& cells, bool track,
                                    const std::vector<Summary>* summaries, SurfaceMarks surface_marks,
                                    FreeCells free_cells) {
  const occupancy::SurfaceRule surface_rule = surfaceMarkingRule();
  for (std::size_t j = 0; j < cells.size(); ++j) {
    const int c = cells[j];
    if (surface_marks == SurfaceMarks::kAll) surface_counter_.occupancyChanged(store_, c, surface_rule);
    const Summary sm = summaries ? (*summaries)[j] : store_.cellSummary(c);
    if (free_cells == FreeCells::kByFrontier && sm.uniformFree()) {
      // Equal free voxels are one uniform leaf, but not while they border unknown space: the cell's frontier
      // voxels would be one coarse leaf, with no voxel of its own to count looks at (FrontierEvidence), and
      // would forget the looks they had whenever the cell is split again.
      const bool borders_unknown = occupancy::FrontierTracker::facesUnknown(store_, c);
      if (store_.cell_block[c] >= 0 && !borders_unknown) {
        releaseFreeBlock(c, sm.min_l);
      } else if (store_.cell_block[c] < 0 && borders_unknown) {
        store_.allocateBlock(c);
        store_.cellSummary(c);  // the block's free and occupied counts (the summary itself is sm)
      }
    }
    store_.levels[0].s[c] = sm;
    if (!track) continue;
    if (!dirty_[c]) {
      dirty_[c] = 1;
      dirty_cells_.push_back(c);
    }
    frontiers_.markCandidate(c);
  }
  store_.propagateSummaries(cells);
}

void OccupancyMap::updateFrontiers() {
  frontiers_.update(store_);
  // A block of equal free voxels kept while it bordered unknown space (refreshSummaries) is released once
  // its last frontier voxel is gone.
  for (const int c : frontiers_.takeEmptiedBlocks()) {
    if (store_.cell_block[c] < 0) continue;
    const Summary& sm = store_.levels[0].s[c];
    if (sm.uniformFree()) releaseFreeBlock(c, sm.min_l);
  }
}
std::size_t OccupancyMap::frontierCount() const { return frontiers_.count(); }
void OccupancyMap::forEachFrontier(const std::function<void(const Eigen::Vector3d&, double)>& f) const {
  frontiers_.forEach(store_, f);
}

void OccupancyMap::markFreeSphere(const Eigen::Vector3d& centre_W, double radius_m) {
  if (!(radius_m > 0.0) || !centre_W.allFinite()) return;
  const Eigen::Vector3d c = (centre_W - store_.origin) / store_.res;  // voxel units
  const double r = radius_m / store_.res, r2 = r * r;
  const std::int16_t lf = static_cast<std::int16_t>(std::max<int>(l_free_, l_min_));
  Eigen::Vector3i lo, hi;
  for (int i = 0; i < 3; ++i) {
    lo[i] = std::max(0, static_cast<int>(std::floor((c[i] - r) / store_.bs)));
    hi[i] = std::min(store_.nb[i] - 1, static_cast<int>(std::floor((c[i] + r) / store_.bs)));
  }
  std::vector<int> changed;
  for (int bz = lo.z(); bz <= hi.z(); ++bz)
    for (int by = lo.y(); by <= hi.y(); ++by)
      for (int bx = lo.x(); bx <= hi.x(); ++bx) {
        const int cell = store_.cellIndex(bx, by, bz);
        if (!store_.levels[0].s[cell].unknown_any) continue;  // nothing unknown to mark
        // voxel-centre distances: is every centre of the cell inside the sphere, or any?
        double far2 = 0.0, near2 = 0.0;
        for (int i = 0; i < 3; ++i) {
          const double a = (Eigen::Vector3i(bx, by, bz)[i] * store_.bs + 0.5) - c[i];
          const double b = a + (store_.bs - 1);
          far2 += std::max(a * a, b * b);
          const double e = std::max({a, 0.0, -b});
          near2 += e * e;
        }
        if (near2 > r2) continue;
        if (store_.cell_block[cell] < 0 && far2 <= r2) {
          store_.cell_value[cell] = lf;  // wholly inside and uniform unknown
          changed.push_back(cell);
          continue;
        }
        const int b = store_.cell_block[cell] >= 0 ? store_.cell_block[cell] : store_.allocateBlock(cell);
        std::int16_t* L = store_.logOdds(b);
        int i = 0;
        for (int z = 0; z < store_.bs; ++z)
          for (int y = 0; y < store_.bs; ++y)
            for (int x = 0; x < store_.bs; ++x, ++i) {
              const Eigen::Vector3d v(bx * store_.bs + x + 0.5, by * store_.bs + y + 0.5, bz * store_.bs + z + 0.5);
              if (L[i] == kUnknown && (v - c).squaredNorm() <= r2) L[i] = lf;
            }
        changed.push_back(cell);
      }
  refreshSummaries(changed);
}

// --------------------------------------------------------------- figures

double OccupancyMap::freeVolume() const {
  std::size_t n = 0;
  for (std::size_t c = 0; c < store_.cell_block.size(); ++c) {
    const int b = store_.cell_block[c];
    if (b < 0) {
      const std::int16_t v = store_.cell_value[c];
      if (isFreeValue(v)) n += store_.bs3;
      continue;
    }
    n += store_.block_nfree[b];
  }
  return static_cast<double>(n) * store_.res * store_.res * store_.res;
}

double OccupancyMap::occupiedVolume() const {
  std::size_t n = 0;
  for (std::size_t c = 0; c < store_.cell_block.size(); ++c) {
    const int b = store_.cell_block[c];
    if (b < 0) {
      if (store_.cell_value[c] >= 0) n += store_.bs3;
      continue;
    }
    n += store_.block_nocc[b];
  }
  return static_cast<double>(n) * store_.res * store_.res * store_.res;
}

std::size_t OccupancyMap::memoryBytes() const {
  const std::size_t ints = dirty_cells_.capacity() + changed_scratch_.capacity() +
                           surface_scratch_.state_changed.capacity() + surface_scratch_.distance_changed.capacity();
  return sizeof(*this) - sizeof(store_) - sizeof(integrator_) + store_.memoryBytes() + integrator_.memoryBytes() +
         frontiers_.memoryBytes() + surface_counter_.memoryBytes() + dirty_.capacity() + ints * sizeof(int) +
         summary_scratch_.capacity() * sizeof(Summary);
}

}  // namespace semexp

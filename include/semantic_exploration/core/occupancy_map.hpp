#pragma once
/// @file occupancy_map.hpp
/// Background occupancy map (paper Section IV-A, DESIGN Section 4).
///
/// Structure: the bounds are covered by a grid of cells of block_size^3
/// voxels (the octree level of the dense blocks). A cell is either a uniform
/// leaf (one log-odds value for all its voxels: free space carved at coarse
/// scale, or unknown) or owns a dense block of voxels. Above the cells sits
/// an implicit octree (a pyramid of dense levels, each cell covering 2x2x2
/// cells of the level below up to one root) holding min/max log-odds and
/// "has unknown"/"has known" flags of everything below it. Integration walks
/// this octree top-down against a min/max depth pyramid so that free space is
/// updated at the coarsest safe node and only nodes straddling the measured
/// surface are refined into voxel blocks; queries use the same summaries to
/// skip uniform regions.
///
/// Log-odds are stored as int16 in thousandths. A voxel is occupied when its
/// log-odds are >= 0 (OctoMap's convention), free when < 0, unknown when never
/// updated.
///
/// The parts, each in core/occupancy/ with its own test: BlockStore (cells,
/// block and surface pools, summaries), DepthPyramid (min/max depth),
/// Integrator (the walk and the voxel update, on a small thread pool) and
/// FrontierTracker (frontier flags, lists and bits).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "semantic_exploration/core/background_map_config.hpp"
#include "semantic_exploration/core/bounds.hpp"
#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/map_blocks.hpp"
#include "semantic_exploration/core/occupancy/block_store.hpp"
#include "semantic_exploration/core/occupancy/frontier_tracker.hpp"
#include "semantic_exploration/core/occupancy/integrator.hpp"
#include "semantic_exploration/core/occupancy/surface_counter.hpp"
#include "semantic_exploration/core/spherical_grid.hpp"

namespace cv {
class Mat;
}

namespace semexp {

/// First hit of a raycast.
struct RaycastHit {
  bool hit = false;                 ///< stopped on an occupied (or unknown, if asked) voxel
  VoxelState state = VoxelState::kUnknown;  ///< state of the voxel it stopped on
  double distance_m = 0.0;          ///< distance from the origin to where the ray entered that voxel, m (max range if no hit)
  Eigen::Vector3d voxel_centre_W = Eigen::Vector3d::Zero();  ///< centre of the leaf it stopped on, world, m
};

/// Settings of the 360-degree gain raycasts (DESIGN Section 5 step 3).
struct GainSettings {
  double d_min_m = 0.1;       ///< entropy is accumulated from this distance on, m
  double d_max_m = 10.0;      ///< rays end here, m
  double d_desired_m = 3.0;   ///< d_bg of Eq. 1, m
  /// Threads sharing the positions, the caller's included, >= 1 (same images
  /// for any count); the background map node sets background_map/gain_threads.
  int threads = 1;
};

/// Gain images of one position; row-major, SphericalGrid layout.
struct GainImages {
  int width = 0;
  int height = 0;
  std::vector<float> entropy;      ///< normalised entropy gain in [0, 1] (reducible entropy, gains.hpp)
  std::vector<float> distance;     ///< Eq. 1 gain of the first occupied voxel's leaf (0 if none)
  std::vector<float> hit_depth_m;  ///< distance to the first occupied voxel, m (d_max if none)
};

/// Multi-resolution occupancy map with colour, minimum observed distance and
/// incrementally maintained frontiers. Not thread-safe for writes; const
/// queries may run concurrently with each other. integrate() itself spreads
/// its work over config.integration_threads threads, with the same result for
/// any count.
class OccupancyMap {
 public:
  /// The map covers `bounds` rounded outwards to whole blocks; voxel (0,0,0)'s
  /// corner is bounds.min_m snapped down to a multiple of the resolution (so
  /// voxels align with OctoMap's). Throws ConfigError on bad config/bounds.
  OccupancyMap(const BackgroundMapConfig& config, const Bounds& bounds);

  // ---------------------------------------------------------------- input
  /// Integrates one depth frame. `depth_m`: camera.width x camera.height
  /// row-major metres; 0, NaN, inf, negative and out-of-[d_min, d_max] pixels
  /// carve nothing and are counted. `rgb`: optional (nullptr) 3 bytes per
  /// pixel, same size, registered to depth. T_WC: camera (optical) to world.
  IntegrationStats integrate(const float* depth_m, const std::uint8_t* rgb, const PinholeCamera& camera,
                             const Eigen::Isometry3d& T_WC);
  /// Same with OpenCV images: depth CV_32FC1 (m) or CV_16UC1 (mm); rgb empty
  /// or CV_8UC3 in R,G,B order. Throws std::invalid_argument on other types or
  /// sizes that disagree with the camera.
  IntegrationStats integrate(const cv::Mat& depth, const cv::Mat& rgb, const PinholeCamera& camera,
                             const Eigen::Isometry3d& T_WC);

  /// Marks the unknown voxels whose centre lies within `radius_m` of `centre_W`
  /// as free (one free update), leaving observed voxels alone: the "enough
  /// free space around the initial position" the paper assumes (Section IV).
  void markFreeSphere(const Eigen::Vector3d& centre_W, double radius_m);

  /// Re-checks frontier candidates (previous frontiers + cells changed since
  /// the last call) at the finest allocated level, and gives back as uniform
  /// leaves the free blocks whose last frontier voxel is gone. Call after integrate().
  void updateFrontiers();

  // -------------------------------------------------------------- queries
  VoxelState state(const Eigen::Vector3d& p_W) const;
  /// Log-odds at p (natural log); false if unknown or outside the map.
  bool logOdds(const Eigen::Vector3d& p_W, double& l) const;
  /// Fused colour of the leaf at p; false if it never received colour.
  bool colour(const Eigen::Vector3d& p_W, std::uint8_t rgb[3]) const;
  /// Minimum distance the leaf at p was updated from, m (infinity if never).
  double minObservedDistance(const Eigen::Vector3d& p_W) const;
  /// True when every voxel intersecting the sphere is known free. Unknown,
  /// occupied and outside-the-map space are not free.
  bool isSphereFree(const Eigen::Vector3d& centre_W, double radius_m) const;
  /// Marches from origin along dir (any length > 0) up to max_range_m and stops
  /// on the first occupied voxel (and on unknown space too if stop_at_unknown).
  /// Leaves the map = no hit.
  RaycastHit raycast(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& dir_W, double max_range_m,
                     bool stop_at_unknown = false) const;

  /// Entropy, Eq. 1 distance gain and hit depth images for each position.
  /// `max_depth_m`: empty, or grid.width*grid.height per position: rays stop
  /// there (occlusion by something else), entropy included up to it.
  /// Throws std::invalid_argument on a grid too large for one request or
  /// settings.threads < 1.
  std::vector<GainImages> computeGains(const std::vector<Eigen::Vector3d>& positions_W, const SphericalGrid& grid,
                                       const GainSettings& settings,
                                       const std::vector<float>& max_depth_m = {}) const;

  /// Surface voxels (occupied voxels with a free 6-neighbour, or, with
  /// free_margin_quadratic_per_m, free space along an axis across the
  /// unknown gap the margin leaves in front of them: the observed surface)
  /// and how many of them were updated from <= d_m: the share of the
  /// background observed from close by (paper Section IV-D's termination
  /// condition with d_m = d_bg). Other occupied voxels are left out: they
  /// are the inside of walls and floors, which noisy far returns mark
  /// occupied and no view from inside can reach from close by.
  struct SurfaceObservation {
    std::size_t occupied_voxels = 0;  ///< surface voxels (finest level; a uniform cell counts its exposed face voxels)
    std::size_t within_voxels = 0;    ///< of those, updated from <= d_m
    /// within / occupied; 1 for a map without surface (nothing left to see closer).
    double share() const {
      return occupied_voxels == 0 ? 1.0 : static_cast<double>(within_voxels) / static_cast<double>(occupied_voxels);
    }
  };
  /// Counts the surface observed from <= d_m; one pass over every cell.
  SurfaceObservation surfaceObservedWithin(double d_m) const;
  /// The same figure, counting again only the cells that changed since the
  /// previous call (and those whose count reads them): a frame's worth of
  /// cells instead of the whole map. A call with another d_m counts all.
  SurfaceObservation trackSurfaceObservedWithin(double d_m);
  /// Cells the last trackSurfaceObservedWithin() counted (all on a full count).
  std::size_t lastSurfaceCellsCounted() const { return surface_counter_.lastCounted(); }

  double freeVolume() const;      ///< m^3
  double occupiedVolume() const;  ///< m^3
  double exploredVolume() const { return freeVolume() + occupiedVolume(); }
  std::size_t memoryBytes() const;
  std::size_t blockCount() const { return store_.blockCount(); }
  /// CPU time the integration pool's extra threads (all but the calling
  /// thread) have used since the map was made, s; 0 with one thread. A
  /// caller's own thread CPU clock plus the change of this is a frame's CPU.
  double workerCpuSeconds() const { return integrator_.workerCpuSeconds(); }
  std::size_t frontierCount() const;
  /// Centre and edge length (m) of every frontier leaf: voxels, or whole
  /// uniform cells where those are the finest allocated level.
  void forEachFrontier(const std::function<void(const Eigen::Vector3d& centre_W, double size_m)>& f) const;
  /// Centre, edge length and colour (grey 128 if none) of every occupied leaf.
  void forEachOccupied(
      const std::function<void(const Eigen::Vector3d& centre_W, double size_m, const std::uint8_t rgb[3])>& f) const;

  double resolution() const { return store_.res; }
  int blockSize() const { return store_.bs; }
  const Eigen::Vector3d& origin() const { return store_.origin; }
  /// World box actually covered (bounds rounded out to whole blocks), m.
  Eigen::Vector3d extentMin() const { return store_.origin; }
  Eigen::Vector3d extentMax() const { return store_.origin + store_.nb.cast<double>() * (store_.bs * store_.res); }
  const BackgroundMapConfig& config() const { return cfg_; }

  // ------------------------------------------------------- serialisation
  /// Blocks changed since the last takeUpdate(), sequence = previous + 1.
  MapBlocksData takeUpdate();
  /// Number of cells changed since the last takeUpdate().
  std::size_t pendingUpdateCount() const { return dirty_cells_.size(); }
  /// The whole known map (full = true), sequence = last taken update's.
  /// With `uniform_as_values`, a block whose voxels all hold one value is sent
  /// as that value (uniform_coords / uniform_values) instead of block_size^3
  /// copies: the snapshot grows with the map's detail, not its known volume
  /// (1e9 known free voxels would otherwise pass roscpp's 1 GB message limit).
  MapBlocksData snapshot(bool uniform_as_values = false) const;
  std::uint64_t lastSequence() const { return sequence_; }
  /// Overwrites the cells named in `blocks` (dropping everything first if
  /// blocks.full). Colour and distance of those cells are reset; their
  /// frontiers are found again at the next updateFrontiers(). Returns
  /// false (and changes nothing) if geometry or encoding does not match.
  bool applyBlocks(const MapBlocksData& blocks);

  /// Own binary format; load(save(m)) saves to identical bytes. The three
  /// writers below replace `path` atomically (writeFileAtomically) and throw
  /// std::runtime_error saying why if they cannot; the previous file stays.
  void save(const std::string& path) const;
  static OccupancyMap load(const std::string& path);
  /// OctoMap binary tree (.bt) with every known voxel, via liboctomap.
  void exportOctomap(const std::string& path) const;
  /// Centres and colours of the occupied leaves as a PLY point cloud (no
  /// faces; the layout of writePly), e.g. for evaluation against a mesh.
  void exportOccupiedPly(const std::string& path) const;

 private:
  void saveTo(std::ostream& f) const;  ///< the own format's bytes (save())
  /// Recomputes summaries of `cells` and their ancestors (`summaries`: the
  /// cells' own, if already computed). `track` also queues the cells for the
  /// next update message and frontier check. SurfaceMarks::kAll marks the
  /// cells (and those whose count reads them) for the surface count;
  /// kByCaller leaves that to a caller that knows more precisely what changed
  /// (integrate()). FreeCells::kByFrontier: a cell of equal free voxels is a
  /// uniform leaf unless it borders unknown space, then a block, so that its
  /// frontier voxels are voxels (updateFrontiers() releases the block once
  /// they are gone); the borders are read from the voxels, not the summaries,
  /// so every written cell must hold its new values. kAsTheyAre leaves blocks
  /// and leaves as they are (load(): the saved frontier table names them).
  enum class SurfaceMarks { kAll, kByCaller };
  enum class FreeCells { kByFrontier, kAsTheyAre };
  void refreshSummaries(const std::vector<int>& cells, bool track = true,
                        const std::vector<occupancy::Summary>* summaries = nullptr,
                        SurfaceMarks surface_marks = SurfaceMarks::kAll,
                        FreeCells free_cells = FreeCells::kByFrontier);
  void releaseBlock(int cell);  ///< store_.releaseBlock, telling the frontier tracker first
  void releaseFreeBlock(int cell, std::int16_t l);  ///< releaseBlock of a block whose voxels are all free at l
  occupancy::SurfaceRule surfaceRule(double d_m) const;  ///< surfaceObservedWithin's rule for d_m
  occupancy::SurfaceRule surfaceMarkingRule() const;     ///< the rule whose reach marks changed cells
  void clearAll();
  void encodeCell(int cell, std::int8_t* out) const;
  // queries (occupancy_map_query.cpp)
  bool sphereFreeRec(int k, int ix, int iy, int iz, const Eigen::Vector3d& c_v, double rad_v) const;
  template <class F>
  void march(const Eigen::Vector3d& o_W, const Eigen::Vector3d& dir_W, double t0, double t1, F&& f) const;

  BackgroundMapConfig cfg_;
  Bounds bounds_;
  occupancy::BlockStore store_;
  occupancy::Integrator integrator_;
  occupancy::FrontierTracker frontiers_;
  occupancy::SurfaceCounter surface_counter_;  ///< per-cell counts of trackSurfaceObservedWithin
  std::int16_t l_free_, l_min_, l_max_;
  std::vector<float> entropy_lut_;  ///< reducible entropy of log-odds l_min_ + i (computeGains)
  std::vector<std::uint8_t> dirty_;  ///< per cell: changed since the last takeUpdate()
  std::vector<int> dirty_cells_;     ///< the cells with dirty_ set
  std::uint64_t sequence_ = 0;
  std::vector<int> changed_scratch_;  ///< reused per-frame list of changed cells
  occupancy::SurfaceChanges surface_scratch_;  ///< reused per frame: cells to count again for the surface
  std::vector<occupancy::Summary> summary_scratch_;  ///< their summaries
};

}  // namespace semexp

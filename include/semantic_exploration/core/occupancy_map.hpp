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
#include "semantic_exploration/core/spherical_grid.hpp"

namespace cv {
class Mat;
}

namespace semexp {

enum class VoxelState : std::uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

/// ROS-free twin of msg/MapBlocks.msg (see there for the field meanings).
struct MapBlocksData {
  static constexpr std::uint8_t kEncodingLogOddsI8 = 0;  ///< log-odds * 10 rounded, -128 unknown
  static constexpr std::int8_t kUnknownI8 = -128;

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

/// Result of one integrate() call.
struct IntegrationStats {
  std::size_t invalid_pixels = 0;   ///< depth pixels that were 0/NaN/inf/negative/out of [d_min, d_max]
  std::size_t changed_cells = 0;    ///< cells (blocks or uniform leaves) whose log-odds changed
  std::size_t voxels_updated = 0;   ///< voxels updated one by one (surface band, frustum border)
  std::size_t blocks_allocated = 0; ///< blocks allocated in this frame
};

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
/// queries may run concurrently with each other.
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
  /// the last call) at the finest allocated level. Call after integrate().
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
  std::vector<GainImages> computeGains(const std::vector<Eigen::Vector3d>& positions_W, const SphericalGrid& grid,
                                       const GainSettings& settings,
                                       const std::vector<float>& max_depth_m = {}) const;

  /// Surface voxels (occupied voxels with a free 6-neighbour: the observed
  /// surface) and how many of them were updated from <= d_m: the share of the
  /// background observed from close by (paper Section IV-D's termination
  /// condition with d_m = d_bg). Occupied voxels without a free neighbour are
  /// left out: they are the inside of walls and floors, which noisy far
  /// returns mark occupied and no view from inside can reach from close by.
  struct SurfaceObservation {
    std::size_t occupied_voxels = 0;  ///< surface voxels (finest level; a uniform cell counts its exposed face voxels)
    std::size_t within_voxels = 0;    ///< of those, updated from <= d_m
    /// within / occupied; 1 for a map without surface (nothing left to see closer).
    double share() const {
      return occupied_voxels == 0 ? 1.0 : static_cast<double>(within_voxels) / static_cast<double>(occupied_voxels);
    }
  };
  /// Counts the surface observed from <= d_m; one pass over the occupied blocks.
  SurfaceObservation surfaceObservedWithin(double d_m) const;

  double freeVolume() const;      ///< m^3
  double occupiedVolume() const;  ///< m^3
  double exploredVolume() const { return freeVolume() + occupiedVolume(); }
  std::size_t memoryBytes() const;
  std::size_t blockCount() const { return block_count_; }
  std::size_t frontierCount() const;
  /// Centre and edge length (m) of every frontier leaf: voxels, or whole
  /// uniform cells where those are the finest allocated level.
  void forEachFrontier(const std::function<void(const Eigen::Vector3d& centre_W, double size_m)>& f) const;
  /// Centre, edge length and colour (grey 128 if none) of every occupied leaf.
  void forEachOccupied(
      const std::function<void(const Eigen::Vector3d& centre_W, double size_m, const std::uint8_t rgb[3])>& f) const;

  double resolution() const { return res_; }
  int blockSize() const { return bs_; }
  const Eigen::Vector3d& origin() const { return origin_; }
  /// World box actually covered (bounds rounded out to whole blocks), m.
  Eigen::Vector3d extentMin() const { return origin_; }
  Eigen::Vector3d extentMax() const { return origin_ + nb_.cast<double>() * (bs_ * res_); }
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
  /// blocks.full). Colour and distance of those cells are reset. Returns
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

  // Internals shared by the implementation files (not part of the API).
  struct Summary {
    std::int16_t min_l;      ///< min log-odds over known voxels below
    std::int16_t max_l;      ///< max log-odds over known voxels below
    std::uint8_t known_any;  ///< some voxel below is known
    std::uint8_t unknown_any;  ///< some voxel below is unknown
  };
  static constexpr std::int16_t kUnknown = INT16_MIN;  ///< log-odds sentinel of unknown voxels
  static constexpr double kScale = 1000.0;              ///< stored log-odds per unit log-odds
  // cell_flags_ bits
  static constexpr std::uint8_t kDirty = 1;           ///< changed since the last takeUpdate()
  static constexpr std::uint8_t kFrontierCand = 2;    ///< changed since the last updateFrontiers()
  static constexpr std::uint8_t kCoarseFrontier = 4;  ///< uniform cell that is a frontier
  static constexpr std::uint8_t kBlockFrontier = 8;   ///< block with frontier bits
  static constexpr std::uint8_t kListedBlock = 16;    ///< in frontier_blocks_
  static constexpr std::uint8_t kListedCell = 32;     ///< in frontier_cells_
  static constexpr std::uint8_t kVisited = 64;        ///< scratch of updateFrontiers()

 private:
  void saveTo(std::ostream& f) const;  ///< the own format's bytes (save())
  struct FrameCtx;
  struct Level {
    Eigen::Vector3i dims;
    std::vector<Summary> s;
  };

  void initGeometry();
  int cellIndex(int bx, int by, int bz) const { return bx + nb_.x() * (by + nb_.y() * bz); }
  int allocateBlock(int cell);
  int ensureSurface(int b);  ///< surface slot of block b, allocated (distances never, no colour) if missing
  void releaseBlock(int cell);
  // integration (occupancy_map.cpp)
  void visitNode(FrameCtx& ctx, int k, int ix, int iy, int iz);
  void freeRegion(FrameCtx& ctx, int k, int ix, int iy, int iz);
  void freeCell(FrameCtx& ctx, int cell);
  void updateCellVoxels(FrameCtx& ctx, int cell);
  /// Recomputes summaries of `cells` and their ancestors; `track` also queues
  /// them for the next update message and frontier check.
  void refreshSummaries(std::vector<int>& cells, bool track = true);
  void clearAll();
  void encodeCell(int cell, std::int8_t* out) const;
  Summary cellSummary(int cell);  ///< also refreshes the block's free/occupied counts
  // queries (occupancy_map_query.cpp)
  bool sphereFreeRec(int k, int ix, int iy, int iz, const Eigen::Vector3d& c_v, double rad_v) const;
  std::int16_t voxelValue(int x, int y, int z) const;  ///< kUnknown outside
  std::int16_t voxelValueOrKnown(int x, int y, int z) const;  ///< 0 (known) outside
  template <class F>
  void march(const Eigen::Vector3d& o_W, const Eigen::Vector3d& dir_W, double t0, double t1, F&& f) const;
  // frontiers (occupancy_map_frontiers.cpp)
  void recheckBlockFrontiers(int cell, bool full);
  void checkFrontierCell(int cell, bool full);
  int blockFrontierBits(int cell) const;
  bool cellIsFrontier(int cell) const;

  BackgroundMapConfig cfg_;
  Bounds bounds_;
  double res_ = 0.04;
  int bs_ = 8, bshift_ = 3, bs3_ = 512, fwords_ = 8;
  Eigen::Vector3d origin_;
  Eigen::Vector3i nb_;  ///< cells per axis
  std::int16_t l_free_, l_occ_, l_min_, l_max_;
  std::vector<float> entropy_lut_;  ///< reducible entropy of log-odds l_min_ + i (computeGains)

  // per cell
  std::vector<std::int32_t> cell_block_;   ///< block slot or -1 (uniform leaf)
  std::vector<std::int16_t> cell_value_;   ///< log-odds of a uniform leaf
  std::vector<std::uint16_t> cell_dist_;   ///< min observed distance of a uniform leaf, mm (0xFFFF never)
  std::vector<std::uint8_t> cell_flags_;   ///< k* bits above
  std::vector<std::uint32_t> cell_stamp_;  ///< frame stamp (dedupe of changed cells)
  // per block slot (structure of arrays)
  std::vector<std::int32_t> block_cell_;   ///< owning cell or -1 (free slot)
  std::vector<std::int16_t> block_l_;      ///< bs3 per block
  // Surface data (distance, colour) only for blocks that ever held an occupied
  // voxel: most blocks (frustum borders, free space near surfaces) never do.
  std::vector<std::int32_t> block_surf_;   ///< surface slot of each block or -1
  std::vector<std::uint32_t> block_nfree_, block_nocc_;  ///< free / occupied voxels per block (volumes without a scan)
  std::vector<std::uint16_t> block_dist_;  ///< bs3 per surface slot, mm (0xFFFF never)
  std::vector<std::uint8_t> block_rgbw_;   ///< 4 per voxel (r, g, b, weight) per surface slot if colour is on
  std::vector<std::int32_t> surf_free_;    ///< released surface slots
  std::size_t surf_slots_ = 0;             ///< surface slots ever allocated
  std::vector<std::uint64_t> block_front_; ///< frontier bits, fwords_ per block
  std::vector<std::uint64_t> block_hit_;   ///< per-frame bits of voxels holding a measured endpoint, fwords_ per block
  std::vector<int> hit_cells_;             ///< cells with endpoint bits in the current frame
  std::vector<std::int32_t> free_slots_;
  std::size_t block_count_ = 0;
  std::vector<Level> levels_;  ///< levels_[0]: per cell; levels_[k]: cells of 2^k x 2^k x 2^k cells

  std::vector<int> dirty_cells_;     ///< changed since the last takeUpdate()
  std::vector<int> frontier_cand_;   ///< changed since the last updateFrontiers()
  std::vector<int> frontier_blocks_; ///< cells whose block has frontier bits (entries without kBlockFrontier are stale)
  std::vector<int> frontier_cells_;  ///< uniform cells that are frontiers (entries without kCoarseFrontier are stale)
  std::size_t frontier_voxels_ = 0;  ///< set frontier bits over all blocks
  std::size_t frontier_block_count_ = 0, frontier_cell_count_ = 0;
  std::uint32_t stamp_ = 0;
  std::uint64_t sequence_ = 0;
  std::vector<int> changed_scratch_;  ///< reused per-frame list of changed cells
  std::vector<float> depth_buf_;  ///< validated depth of the current frame (0 = invalid)
  std::vector<float> free_buf_;   ///< per pixel: voxels with depth below this are carved free (0 = invalid)
  std::vector<std::vector<float>> pyr_min_, pyr_max_;
  std::vector<Eigen::Vector2i> pyr_dims_;
};

}  // namespace semexp

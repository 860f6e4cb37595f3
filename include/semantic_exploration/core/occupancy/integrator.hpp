#pragma once
/// @file integrator.hpp
/// Depth-frame integration of the background occupancy map (internal to
/// OccupancyMap): the top-down walk of the summary octree against the depth
/// min/max pyramid, and the voxel update of the cells straddling the surface.
///
/// Work split: the walk above level kSplitLevel (nodes of 4 x 4 x 4 cells)
/// runs on the calling thread and lists the subtrees left to do in
/// depth-first order; a WorkerPool does them, each into its own output, and
/// the outputs are merged in list order. Tasks touch disjoint cells and
/// blocks and never allocate: a cell that needs a new block or surface slot
/// gets scratch memory, allocated in the store at the merge. So the map, the
/// order of the changed cells and every slot number are the same for any
/// thread count.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "semantic_exploration/core/background_map_config.hpp"
#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/occupancy/block_store.hpp"
#include "semantic_exploration/core/occupancy/depth_pyramid.hpp"
#include "semantic_exploration/core/occupancy/worker_pool.hpp"

namespace semexp {

/// Result of one OccupancyMap::integrate() call.
struct IntegrationStats {
  std::size_t invalid_pixels = 0;   ///< depth pixels that were 0/NaN/inf/negative/out of [d_min, d_max]
  std::size_t changed_cells = 0;    ///< cells (blocks or uniform leaves) whose log-odds changed
  std::size_t voxels_updated = 0;   ///< voxels updated one by one (surface band, frustum border)
  std::size_t blocks_allocated = 0; ///< blocks allocated in this frame
};

namespace occupancy {

namespace detail {
/// ceil(2^32 / d) for d = 1 .. 256, index d - 1.
constexpr std::array<std::uint64_t, 256> colourReciprocals() {
  std::array<std::uint64_t, 256> m{};
  for (std::uint64_t d = 1; d <= 256; ++d) m[d - 1] = ((std::uint64_t{1} << 32) + d - 1) / d;
  return m;
}
inline constexpr std::array<std::uint64_t, 256> kColourReciprocal = colourReciprocals();
}  // namespace detail

/// One colour channel's running mean after one more observation:
/// (c w + in + (w + 1) / 2) / (w + 1), rounded down, for c, in and the
/// weight w in [0, 255]. The division is a multiply by a table reciprocal and
/// a shift, exact here: the numerator n < 2^16 and n (w + 1) < 2^32.
inline std::uint8_t blendColour(int c, int w, int in) {
  const std::uint64_t n = static_cast<std::uint64_t>(c * w + in + (w + 1) / 2);
  return static_cast<std::uint8_t>((n * detail::kColourReciprocal[static_cast<std::size_t>(w)]) >> 32);
}

/// The cells of one frame whose surface count (SurfaceCounter) may have
/// changed; a cell may be listed more than once.
struct SurfaceChanges {
  std::vector<int> state_changed;     ///< a voxel went from unknown, free or occupied to another of these
  std::vector<int> distance_changed;  ///< an occupied voxel's observed distance was lowered
  void clear() {
    state_changed.clear();
    distance_changed.clear();
  }
};

class Integrator {
 public:
  /// Octree level whose nodes are the parallel tasks (level 0: cells).
  static constexpr int kSplitLevel = 2;

  /// Uses config.integration_threads threads (the caller's included).
  explicit Integrator(const BackgroundMapConfig& config);
  Integrator(const Integrator& other);  ///< same settings, own pool
  Integrator& operator=(const Integrator& other);
  Integrator(Integrator&&) noexcept = default;
  Integrator& operator=(Integrator&&) noexcept = default;
  ~Integrator();

  /// Integrates one depth frame (see OccupancyMap::integrate) into `store`
  /// and appends each changed cell once to `changed`, in depth-first order.
  /// Summaries are not refreshed: the caller does that with `changed`.
  /// `surface` (if given) gets the cells where a voxel changed between
  /// unknown, free and occupied, and those where an occupied voxel's observed
  /// distance went down (what the surface count, SurfaceCounter, reads).
  IntegrationStats integrate(BlockStore& store, const float* depth_m, const std::uint8_t* rgb,
                             const PinholeCamera& camera, const Eigen::Isometry3d& T_WC, std::vector<int>& changed,
                             SurfaceChanges* surface = nullptr);

  /// Summaries of `cells` computed on the pool (BlockStore::cellSummary each).
  void summarise(BlockStore& store, const std::vector<int>& cells, std::vector<Summary>& out);

  int threads() const { return pool_->threads(); }
  /// CPU time of the pool's extra threads since this integrator was made, s (WorkerPool::workerCpuSeconds).
  double workerCpuSeconds() const { return pool_->workerCpuSeconds(); }
  std::size_t memoryBytes() const;

 private:
  /// Constants of one frame.
  struct Frame {
    Eigen::Matrix3d R_CW;
    Eigen::Vector3d t_CW;
    Eigen::Vector3d cam_W;  ///< camera position, world, m
    float fx, fy, cx, cy;
    int W, H;
    const std::uint8_t* rgb;
    float band;  ///< surface band behind the depth, m
    /// With a free margin wider than the surface's front: the surface starts
    /// max(front_m, front_quad_per_m d^2) in front of depth d, and voxels
    /// between the free limit and there are not updated.
    bool gap = false;
    float front_m = 0.f, front_quad_per_m = 0.f;
  };
  struct Task {
    int k, ix, iy, iz;
    bool free;  ///< true: free the region; false: descend into it
  };
  /// A cell of a task that needs a block or surface slot allocated at the merge.
  struct Pending {
    int cell;
    int scratch_block;    ///< index into TaskOut::l blocks, or -1
    int scratch_surface;  ///< index into TaskOut::dist / rgbw slots, or -1
  };
  struct TaskOut {
    std::vector<int> changed;
    std::vector<int> state_changed, distance_changed;  ///< SurfaceChanges of the task
    std::size_t voxels_updated = 0, blocks_allocated = 0;
    std::vector<Pending> pending;
    std::vector<std::int16_t> l;      ///< scratch blocks, bs3 each
    std::vector<std::uint16_t> dist;  ///< scratch surfaces, bs3 each
    std::vector<std::uint8_t> rgbw;   ///< scratch colour, 4 bs3 each (if colour)
    void clear();
  };
  struct Endpoint {
    std::int32_t cell;   ///< cell holding the pixel's endpoint, -1 if none
    std::int32_t voxel;  ///< voxel index in that cell
  };
  enum class NodeClass { kSkip, kFree, kDescend };

  void markEndpoints(BlockStore& store, const PinholeCamera& camera, const Eigen::Isometry3d& T_WC,
                     IntegrationStats& stats);
  NodeClass classify(const BlockStore& store, const Frame& fr, int k, int ix, int iy, int iz) const;
  void plan(const BlockStore& store, const Frame& fr, int k, int ix, int iy, int iz);
  void planFree(const BlockStore& store, int k, int ix, int iy, int iz);
  void visitNode(BlockStore& store, const Frame& fr, TaskOut& out, int k, int ix, int iy, int iz);
  void descend(BlockStore& store, const Frame& fr, TaskOut& out, int k, int ix, int iy, int iz);
  void freeRegion(BlockStore& store, const Frame& fr, TaskOut& out, int k, int ix, int iy, int iz);
  void freeCell(BlockStore& store, const Frame& fr, TaskOut& out, int cell);
  void updateCellVoxels(BlockStore& store, const Frame& fr, TaskOut& out, int cell);
  void markChanged(TaskOut& out, int cell);
  static void merge(BlockStore& store, TaskOut& out, std::vector<int>& changed, SurfaceChanges* surface,
                    IntegrationStats& stats);
  std::uint64_t* hits(const BlockStore& store, int b) { return hit_.data() + static_cast<std::size_t>(b) * store.fwords; }

  BackgroundMapConfig cfg_;
  std::int16_t l_free_, l_occ_, l_min_, l_max_;
  DepthPyramid pyr_;
  std::vector<std::uint64_t> hit_;         ///< per block slot: bits of voxels holding a measured endpoint this frame
  std::vector<int> hit_cells_;             ///< cells with endpoint bits this frame
  std::vector<Endpoint> endpoint_;         ///< per pixel, this frame
  std::vector<float> ray_x_;               ///< per image column: x of its ray at unit depth, this frame
  std::vector<std::uint32_t> cell_stamp_;  ///< frame stamp per cell (each changed cell listed once)
  std::vector<std::uint32_t> hit_stamp_;   ///< frame stamp per cell (each endpoint cell listed once)
  std::uint32_t stamp_ = 0;
  std::vector<Task> tasks_;
  std::vector<TaskOut> outs_;  ///< one per task (reused: they keep their capacity)
  std::unique_ptr<WorkerPool> pool_;
};

}  // namespace occupancy
}  // namespace semexp

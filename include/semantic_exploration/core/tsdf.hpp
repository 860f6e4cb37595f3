#pragma once
/// @file tsdf.hpp
/// Sparse voxel-block TSDF of one object (paper Section IV-B): projective
/// truncated SDF, weight, colour, foreground probability and the minimum
/// distance each voxel was observed from.
///
/// Two voxel layouts share one implementation: TsdfVoxel (fixed point, the
/// one the object map uses, 10 bytes) and TsdfVoxelFloat (the float layout
/// it is measured against, 20 bytes).

#include <Eigen/Geometry>
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <opencv2/core.hpp>
#include <unordered_map>
#include <vector>

#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/mesh_gate.hpp"
#include "semantic_exploration/core/marching_cubes.hpp"
#include "semantic_exploration/core/tsdf_revision.hpp"

namespace semexp {

/// Helpers of the fixed-point voxel. Without SSE4.1 std::round compiles to a
/// libm call, and the voxel update quantises four fields per voxel; inline
/// rounding and a table for the foreground division keep the fixed-point
/// update close to the float one (issue 16).
namespace tsdf_fixed {

/// std::lround (halfway cases away from zero) for |x| < 2^31 in double,
/// inline. Exact: the truncated value and the fraction x - trunc(x) are exact
/// doubles. Not a voxel field: the integration's pixel coordinates (both
/// layouts), which called libm's lround twice per voxel.
inline int roundToInt(double x) {
  const int i = static_cast<int>(x);
  const double frac = x - static_cast<double>(i);
  return i + (frac >= 0.5) - (frac <= -0.5);
}
/// std::round for 0 <= x < 2^31 in float, inline (the fused colour, both layouts).
inline int roundNonNegativeToInt(float x) {
  const int i = static_cast<int>(x);
  return i + (x - static_cast<float>(i) >= 0.5f);
}

/// Round to nearest, halfway cases to even (as std::nearbyint in the default
/// rounding mode), for |x| < 2^22, inline and branch-free: adding 1.5 * 2^23
/// leaves the float with no fraction bits, so the addition itself rounds x,
/// and the low bits of the sum are the result. The voxel setters' rounding:
/// no conversion to int and back and no comparison, as a round half away from
/// zero needs, and unbiased over many halfway cases. Where float arithmetic
/// may run in more than float precision (x87, or FLT_EVAL_METHOD unknown, as
/// some compilers report under -ffast-math), std::nearbyint gives the same
/// results, more slowly.
inline int roundHalfEvenToInt(float x) {
#if defined(FLT_EVAL_METHOD) && FLT_EVAL_METHOD == 0
  static_assert(std::numeric_limits<float>::is_iec559 && sizeof(float) == sizeof(std::int32_t),
                "roundHalfEvenToInt reads the bits of an IEEE 754 single");
  const float t = x + 12582912.f;  // 1.5 * 2^23
  std::int32_t bits;
  std::memcpy(&bits, &t, sizeof bits);
  return bits - 0x4B400000;  // the bits of 1.5 * 2^23
#else
  return static_cast<int>(std::nearbyint(x));
#endif
}

/// Foreground probability of each stored byte, q / 254.f, so that reading it costs no division.
struct ForegroundTable {
  float p[256];
  constexpr ForegroundTable() : p() {
    for (int q = 0; q < 256; ++q) p[q] = static_cast<float>(q) / 254.f;
  }
};
inline constexpr ForegroundTable kForeground{};

}  // namespace tsdf_fixed

/// Fixed-point voxel: SDF as int16 normalised by the truncation distance,
/// foreground probability as uint8 (p = q / 254, so 0.5 is exact), weight as
/// uint16 in 1/16 steps (so at most 4095.9), minimum observed distance in
/// millimetres. Setters round to nearest, halfway cases to even, after
/// clamping to the representable range; NaN saturates to the upper bound.
struct TsdfVoxel {
  std::int16_t sdf_q = 32767;           ///< sdf / truncation * 32767
  std::uint16_t weight_q = 0;           ///< weight * 16 (capped), 0 = never observed
  std::uint16_t min_distance_mm = 65535;///< closest camera distance this voxel was seen from, mm (65535 = none)
  std::uint8_t foreground_q = 127;      ///< foreground probability * 254
  std::uint8_t rgb[3] = {0, 0, 0};      ///< fused colour

  float sdf(float truncation_m) const { return sdf_q * (truncation_m / 32767.f); }
  void setSdf(float sdf_m, float truncation_m) {
    // Clamping first equals clamping the rounded value (round is monotonic, the bounds are integers).
    const float q = std::max(-32767.f, std::min(32767.f, sdf_m / truncation_m * 32767.f));
    sdf_q = static_cast<std::int16_t>(tsdf_fixed::roundHalfEvenToInt(q));
  }
  /// Fuses an observation s_m (m) of weight w_obs into the stored SDF of
  /// weight w (w_new = w + w_obs > 0): the weighted mean, clamped and
  /// stored. Works on the quantised value (to_q = 32767 / truncation_m), so
  /// that the update needs no conversion to metres and back; returns whether
  /// the mean is negative.
  bool fuseSdf(float s_m, float w, float w_obs, float w_new, float /*truncation_m*/, float to_q) {
    const float q = (static_cast<float>(sdf_q) * w + s_m * to_q * w_obs) / w_new;
    sdf_q = static_cast<std::int16_t>(tsdf_fixed::roundHalfEvenToInt(std::max(-32767.f, std::min(32767.f, q))));
    return q < 0.f;
  }
  float weight() const { return weight_q * (1.f / 16.f); }
  void setWeight(float w) {
    const float q = std::max(0.f, std::min(65535.f, w * 16.f));
    weight_q = static_cast<std::uint16_t>(tsdf_fixed::roundHalfEvenToInt(q));
  }
  static constexpr double kMaxWeight = 65535.0 / 16.0;  ///< largest representable weight
  float foreground() const { return tsdf_fixed::kForeground.p[foreground_q]; }
  void setForeground(float p) {
    const float q = std::max(0.f, std::min(1.f, p)) * 254.f;
    foreground_q = static_cast<std::uint8_t>(tsdf_fixed::roundHalfEvenToInt(q));
  }
  float minDistance() const {
    return min_distance_mm == 65535 ? std::numeric_limits<float>::infinity() : min_distance_mm * 1e-3f;
  }
  void setMinDistance(float d_m) { min_distance_mm = quantiseDistance(d_m); }
  /// Same result as `if (d_m < minDistance()) setMinDistance(d_m)` for finite d_m (the rounded value of a
  /// smaller distance is never larger, of a larger one never smaller), without the data-dependent branch
  /// that mispredicts when the stored distance is a rounded copy of the one seen again.
  void lowerMinDistance(float d_m) { min_distance_mm = std::min(min_distance_mm, quantiseDistance(d_m)); }

 private:
  static std::uint16_t quantiseDistance(float d_m) {
    const float q = std::max(0.f, std::min(65534.f, d_m * 1e3f));
    return static_cast<std::uint16_t>(tsdf_fixed::roundHalfEvenToInt(q));
  }
};

/// Float voxel of the same content: the reference layout.
struct TsdfVoxelFloat {
  float sdf_m = 0.f;
  float weight_f = 0.f;
  float min_distance_m = std::numeric_limits<float>::infinity();
  float foreground_p = 0.5f;
  std::uint8_t rgb[3] = {0, 0, 0};

  float sdf(float) const { return sdf_m; }
  void setSdf(float sdf, float truncation_m) { sdf_m = std::max(-truncation_m, std::min(truncation_m, sdf)); }
  /// TsdfVoxel::fuseSdf in metres.
  bool fuseSdf(float s_m, float w, float w_obs, float w_new, float truncation_m, float /*to_q*/) {
    const float sdf = (sdf_m * w + s_m * w_obs) / w_new;
    setSdf(sdf, truncation_m);
    return sdf < 0.f;
  }
  float weight() const { return weight_f; }
  void setWeight(float w) { weight_f = w; }
  float foreground() const { return foreground_p; }
  void setForeground(float p) { foreground_p = p; }
  float minDistance() const { return min_distance_m; }
  void setMinDistance(float d_m) { min_distance_m = d_m; }
  void lowerMinDistance(float d_m) { min_distance_m = std::min(min_distance_m, d_m); }
  static constexpr double kMaxWeight = 1e30;
};

/// Geometry of one TSDF.
struct TsdfParams {
  double resolution_m = 0.02;  ///< voxel edge, m
  double truncation_m = 0.08;  ///< truncation distance, m
  /// Voxels farther than this behind the measured surface are not updated
  /// (clamped to truncation_m), m; the weight falls linearly from 1 at one
  /// voxel behind to 0 here, so free space hidden behind edges is not dug in.
  double behind_surface_m = 0.04;
  /// The band behind the surface grows with the depth noise: it reaches
  /// max(behind_surface_m, q d^2) behind a depth d (clamped to truncation_m),
  /// with q this value, 1/m (3 sigma of a sensor with sigma = s d^2 is q = 3 s).
  /// A narrower band than the noise updates a voxel inside a solid only from
  /// the rare rays that overshoot it, whose mean SDF is biased towards free,
  /// and that bias leaves surface inside solid objects seen from far. Pixels
  /// whose q d^2 exceeds truncation_m are not integrated at all: the band
  /// cannot hold their noise. 0 = a fixed band of behind_surface_m.
  double behind_surface_quadratic_per_m = 0.0;
  /// Observations from depths up to this count with weight 1; a deeper
  /// depth d counts (full_weight_depth_m / d)^2 rounded to the 1/16 step of
  /// the fixed-point weight and at least 1/16, so that near views outweigh
  /// the noisier far ones. The square, not the inverse variance (d^-4 for
  /// sigma = s d^2): with a 1/16 quantum the fourth power reaches its floor
  /// at twice this depth and so loses the ordering between far views. The
  /// behind-surface fall-off multiplies it. m; 0 = every observation counts 1.
  double full_weight_depth_m = 0.0;
  /// Foreground probability a voxel holds before its first observation, and
  /// the weight (in full-weight observations) that belief keeps in the
  /// foreground average: p = (prior * (w + prior_weight) + ...) / (w + prior_weight + ...).
  /// A prior under 0.5 with some weight keeps a voxel seen inside a mask in
  /// one or two detections only (a surface a mask bled onto, seen through a
  /// gap) under 0.5 until more detections confirm it. 0 weight = the paper's
  /// update (the first observation sets the probability).
  double foreground_prior = 0.5;
  double foreground_prior_weight = 0.0;
  /// Foreground probability over which a voxel's surface is tracked:
  /// rendered for matching, hit by the planner's object rays, counted when a
  /// new object is kept and as the extent of a piece that may be merged into
  /// another object. It is foreground_prior when that lies under 0.5 with
  /// some weight (any detection lifts a voxel above the prior), else 0.5.
  /// The mesh (over 0.5 or a higher MeshGate::min_foreground), the observed
  /// share and the extent of the object a piece is merged into keep the
  /// paper's 0.5. A prior that keeps bled surface out
  /// of the mesh then neither shrinks the render later detections are matched
  /// to nor drops a first detection whose pixels all lie near its mask's border.
  /// It is stickier than 0.5: a voxel one full detection lifted to 0.53 leaves
  /// the tracked surface after two or three views outside the mask, where the
  /// paper's update drops it from the render after one. The map compares with
  /// the prior as its voxel type stores it (TsdfMapT::trackedForeground()).
  float trackedForeground() const {
    return foreground_prior_weight > 0.0 && foreground_prior < 0.5 ? static_cast<float>(foreground_prior) : 0.5f;
  }
  int block_size = 8;          ///< voxels per block edge (power of two)
  double max_weight = 100.0;   ///< weight cap (one unit per full-weight observation at the surface, see full_weight_depth_m)

  /// Global voxel indices must stay within +-kMaxVoxelIndex on every axis:
  /// meshing keys voxel edges with 20 bits per axis (10.5 km at 2 cm).
  static constexpr int kMaxVoxelIndex = 1 << 19;
  /// Largest |world coordinate| whose voxels the map can hold, m.
  double maxCoordinate_m() const { return resolution_m * (kMaxVoxelIndex - 1); }
  /// Weight of an observation at depth d_m (see full_weight_depth_m): a
  /// multiple of 1/16 in [1/16, 1], so that the fixed-point voxel stores the
  /// weight its averages used.
  float depthWeight(float d_m) const {
    const float full = static_cast<float>(full_weight_depth_m);
    if (full <= 0.f || d_m <= full) return 1.f;
    const float r = full / d_m;
    return std::max(static_cast<float>(tsdf_fixed::roundNonNegativeToInt(r * r * 16.f)), 1.f) * (1.f / 16.f);
  }
  /// Largest depth integrated, m: sqrt(truncation_m / behind_surface_quadratic_per_m)
  /// (infinite without the noise band); deeper pixels are skipped.
  double maxIntegratedDepth_m() const {
    return behind_surface_quadratic_per_m > 0.0 ? std::sqrt(truncation_m / behind_surface_quadratic_per_m)
                                                : std::numeric_limits<double>::infinity();
  }
};

/// First foreground surface crossing along a ray.
struct TsdfRayHit {
  float distance_m = 0.f;      ///< along the (unit) ray from its origin, m
  float min_distance_m = 0.f;  ///< minimum distance the surface there was observed from, m (inf if never)
};

/// Summary of the surface of one TSDF (voxels with |sdf| < one voxel and
/// foreground probability over 0.5, or over the tracked threshold: see
/// TsdfMapT::summarize).
struct TsdfSummary {
  Eigen::Vector3d bbox_min_W = Eigen::Vector3d::Zero();  ///< m
  Eigen::Vector3d bbox_max_W = Eigen::Vector3d::Zero();  ///< m
  Eigen::Vector3d centroid_W = Eigen::Vector3d::Zero();  ///< m
  std::size_t voxel_count = 0;                           ///< surface voxels
  double observed_fraction = 0.0;  ///< fraction of surface voxels observed from <= d_obj, [0, 1]
  /// Sum of the weights of all voxels, surface or not (one unit per full-weight observation at the surface, each voxel
  /// capped at max_weight): grows with every integration that reaches the object, foreground or not.
  double weight_sum = 0.0;
};

struct VoxelIndexHash {
  std::size_t operator()(const Eigen::Vector3i& v) const {
    return (static_cast<std::size_t>(v.x()) * 73856093u) ^ (static_cast<std::size_t>(v.y()) * 19349669u) ^
           (static_cast<std::size_t>(v.z()) * 83492791u);
  }
};

template <class VoxelT>
class TsdfMapT {
 public:
  using Voxel = VoxelT;
  /// block_size^3 voxels, x fastest.
  struct Block {
    std::vector<VoxelT> voxels;
    bool has_negative = false;  ///< some voxel was given SDF < 0 (ray casts step over blocks without)
    explicit Block(std::size_t n) : voxels(n) {}
    const VoxelT& operator[](std::size_t i) const { return voxels[i]; }
    VoxelT& operator[](std::size_t i) { return voxels[i]; }
  };

  explicit TsdfMapT(const TsdfParams& params);

  /// TsdfParams::trackedForeground(), raised to the prior as VoxelT stores it
  /// when rounding raised that (the fixed-point voxel keeps p in 1/254 steps):
  /// a voxel that holds the prior unchanged (one updated as an undetected
  /// object only) is never tracked.
  float trackedForeground() const { return tracked_foreground_; }
  // The dense index points into blocks_: moving keeps those nodes, copying would not.
  TsdfMapT(const TsdfMapT&) = delete;
  TsdfMapT& operator=(const TsdfMapT&) = delete;
  TsdfMapT(TsdfMapT&&) = default;
  TsdfMapT& operator=(TsdfMapT&&) = default;

  const TsdfParams& params() const { return params_; }

  /// Mask value of a pixel that neither fills nor carves the object (see integrate).
  static constexpr std::uint8_t kMaskUnknown = 128;
  /// Foreground evidence of an inside mask value m (see integrate): 0.5 + 0.5 (m - 128) / 127 for m in
  /// (128, 255], so 255 is full evidence and values just above 128 nearly none; 1 for m in [1, 128).
  static float maskEvidence(std::uint8_t m) { return m > kMaskUnknown ? 0.5f + 0.5f * (m - 128) / 127.f : 1.f; }

  /// Integrates one depth image through a binary mask.
  /// @param depth_m   CV_32FC1 depth along the optical axis, m; 0, NaN, inf and
  ///                  values outside [d_min_m, d_max_m] are invalid
  /// @param rgb       CV_8UC3 rgb colour of the same size, or empty (no colour)
  /// @param mask      CV_8UC1, non-zero where the pixel belongs to this object;
  ///                  kMaskUnknown where it is not known (the pixel neither
  ///                  updates voxels nor lowers their foreground probability);
  ///                  values in (kMaskUnknown, 255) are inside with less
  ///                  foreground evidence (maskEvidence; a detection's border,
  ///                  where masks bleed)
  /// @param update_foreground  true for a detection (foreground probability
  ///                  rises inside the mask and falls where the measured
  ///                  surface outside the mask passes through known voxels);
  ///                  false for a visible but undetected object (SDF and
  ///                  colour only)
  /// @return number of voxels whose SDF was updated
  std::size_t integrate(const PinholeCamera& camera, const Eigen::Isometry3d& T_WC, const cv::Mat& depth_m,
                        const cv::Mat& rgb, const cv::Mat& mask, bool update_foreground);

  /// Voxel with global index `index` (voxel centre (index + 0.5) * resolution), null if not allocated.
  const VoxelT* voxel(const Eigen::Vector3i& index) const;
  Eigen::Vector3i voxelIndex(const Eigen::Vector3f& p_W) const {
    return (p_W * inv_resolution_).array().floor().template cast<int>();
  }
  Eigen::Vector3f voxelCentre(const Eigen::Vector3i& index) const {
    return (index.cast<float>().array() + 0.5f) * static_cast<float>(params_.resolution_m);
  }
  /// Trilinearly interpolated SDF at p_W, m; false if one of the 8 voxels around it was never observed.
  bool interpolate(const Eigen::Vector3f& p_W, float& sdf_m) const;

  /// First zero crossing from positive to negative SDF of a tracked surface
  /// (mean foreground of the two voxels over TsdfParams::trackedForeground()),
  /// along origin_W + t dir_W (dir_W unit), t in [t_min, t_max].
  bool castRay(const Eigen::Vector3f& origin_W, const Eigen::Vector3f& dir_W, float t_min, float t_max,
               TsdfRayHit& hit) const;

  /// Fuses `other` (same resolution and block size) into this map: weights
  /// add (capped), SDF, foreground and colour are weight-averaged, minimum
  /// distances take the minimum. Used to merge two maps of one object.
  /// @throws std::invalid_argument if the grids differ
  void mergeFrom(const TsdfMapT& other);

  /// Sets the foreground probability of every voxel whose centre p_W lies
  /// beyond the plane (normal_W . p_W > offset_m) to 0: that part of the map
  /// belongs to another object. Returns the voxels changed.
  std::size_t dropForegroundBeyond(const Eigen::Vector3f& normal_W, float offset_m);

  /// Marching-cubes mesh of the zero crossing where the mean foreground
  /// probability of a cube's 8 voxels exceeds 0.5, with colour, over the cubes whose 8 voxels each hold a weight of
  /// at least min_weight (and more than 0), in observations.
  Mesh extractMesh(float min_weight = 0.f) const {
    MeshGate gate;
    gate.min_weight = min_weight;
    return extractMesh(gate);
  }
  /// The same over the cubes whose 8 voxels each pass `gate` and whose
  /// mean foreground exceeds gate.min_foreground.
  Mesh extractMesh(const MeshGate& gate) const;

  /// Summary of the surface voxels (|sdf| < one voxel) whose foreground
  /// probability exceeds 0.5 (the mesh's surface; with tracked, exceeds
  /// TsdfParams::trackedForeground()); observed_fraction counts those seen
  /// from <= d_obj_m.
  TsdfSummary summarize(double d_obj_m, bool tracked = false) const;
  /// True if some voxel is a tracked surface voxel (stops at the first one).
  bool hasSurface() const;
  /// A surface voxel as summarize() counts it: observed, |sdf| under one
  /// voxel, foreground over 0.5 (the mesh's) or, with tracked, over
  /// trackedForeground().
  bool isSurfaceVoxel(const VoxelT& vx, bool tracked) const {
    return vx.weight() > 0.f && std::abs(vx.sdf(truncation_m_)) < static_cast<float>(params_.resolution_m) &&
           vx.foreground() > (tracked ? tracked_foreground_ : 0.5f);
  }

  /// Changes with every call that may change a voxel (integrate,
  /// dropForegroundBeyond, mergeFrom) and differs between any two maps of the
  /// process (a moved-from map gets a new one), so a cache keyed by it
  /// (ObjectSummaryCache) is never taken for a state it was not computed from.
  std::uint64_t revision() const { return revision_.value(); }

  /// Axis-aligned box of the allocated blocks in world, m; false if empty.
  bool allocatedBox(Eigen::AlignedBox3f& box_W) const;
  std::size_t blockCount() const { return blocks_.size(); }
  std::size_t voxelCount() const { return blocks_.size() * voxels_per_block_; }
  /// Bytes of voxel payload (excluding hash-map overhead).
  std::size_t voxelBytes() const { return voxelCount() * sizeof(VoxelT); }

  /// A block as saved (tsdf_io.hpp): its index, its block_size^3 voxels (x
  /// fastest) and Block::has_negative.
  struct SavedBlock {
    Eigen::Vector3i index;
    std::vector<VoxelT> voxels;
    bool has_negative = false;
  };
  /// Calls f(block index, voxels (block_size^3, x fastest), has_negative) for every allocated block.
  template <class F>
  void forEachBlock(F&& f) const {
    for (const auto& kv : blocks_) f(kv.first, kv.second.voxels, kv.second.has_negative);
  }
  /// Sets the blocks given (allocating them) to their saved content: loads a
  /// saved map (tsdf_io.hpp).
  /// @throws std::invalid_argument if a block does not hold block_size^3 voxels
  void loadBlocks(std::vector<SavedBlock> blocks);

  /// Calls f(global voxel index, voxel) for every allocated voxel.
  template <class F>
  void forEachVoxel(F&& f) const {
    const int B = params_.block_size;
    for (const auto& kv : blocks_) {
      const Eigen::Vector3i base = kv.first * B;
      for (int z = 0, i = 0; z < B; ++z)
        for (int y = 0; y < B; ++y)
          for (int x = 0; x < B; ++x, ++i) f(Eigen::Vector3i(base + Eigen::Vector3i(x, y, z)), kv.second[i]);
    }
  }

 private:
  Eigen::Vector3i blockOf(const Eigen::Vector3i& v) const {
    // Arithmetic shift = floor division by the power-of-two block size.
    return {v.x() >> block_shift_, v.y() >> block_shift_, v.z() >> block_shift_};
  }
  Block& allocate(const Eigen::Vector3i& block_index);
  /// Block `b` or null: O(1) through the dense index when it is built, else the hash map.
  const Block* findBlock(const Eigen::Vector3i& b) const {
    if (!dense_.empty()) {
      const Eigen::Vector3i r = b - dense_min_;
      if (r.x() < 0 || r.y() < 0 || r.z() < 0 || r.x() >= dense_dims_.x() || r.y() >= dense_dims_.y() ||
          r.z() >= dense_dims_.z())
        return nullptr;
      return dense_[r.x() + dense_dims_.x() * (r.y() + dense_dims_.y() * r.z())];
    }
    const auto it = blocks_.find(b);
    return it == blocks_.end() ? nullptr : &it->second;
  }
  /// Rebuilds the dense block index over the allocated box (after allocation).
  void rebuildIndex();
  static constexpr double kMaxDenseIndex = 1 << 21;  ///< cells (8 bytes each)

  TsdfParams params_;
  int voxels_per_block_;
  int block_shift_;  ///< log2(block_size)
  float inv_resolution_;
  float truncation_m_;
  float tracked_foreground_;
  std::unordered_map<Eigen::Vector3i, Block, VoxelIndexHash> blocks_;
  Eigen::Vector3i block_min_{0, 0, 0}, block_max_{-1, -1, -1};  ///< inclusive range of allocated block indices
  /// Dense index of block pointers over [block_min_, block_max_] (empty if too large):
  /// ray casts and meshing look blocks up without hashing.
  std::vector<Block*> dense_;
  Eigen::Vector3i dense_min_{0, 0, 0}, dense_dims_{0, 0, 0};
  TsdfRevision revision_;  ///< revision()
};

using TsdfMap = TsdfMapT<TsdfVoxel>;
using TsdfMapFloat = TsdfMapT<TsdfVoxelFloat>;

extern template class TsdfMapT<TsdfVoxel>;
extern template class TsdfMapT<TsdfVoxelFloat>;

}  // namespace semexp

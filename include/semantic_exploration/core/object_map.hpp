#pragma once
/// @file object_map.hpp
/// The set of object submaps (paper Section IV-B): one fixed-point TSDF per
/// object at its class's resolution; frame integration of matched
/// detections and of visible undetected objects; rendering of all objects
/// into an object-id image; object gain images (Eq. 1 with d_obj); meshes
/// and saving.

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "semantic_exploration/core/bounds.hpp"
#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/class_table.hpp"
#include "semantic_exploration/core/object_id_pool.hpp"
#include "semantic_exploration/core/object_map_config.hpp"
#include "semantic_exploration/core/object_masks.hpp"
#include "semantic_exploration/core/spherical_grid.hpp"
#include "semantic_exploration/core/tsdf.hpp"

namespace semexp {

/// One object submap.
struct MappedObject {
  std::uint32_t id = 0;              ///< > 0, at most 65535 (object-id images are 16-bit)
  int class_id = 0;                  ///< index into the class table (> 0)
  std::string class_name;
  double resolution_m = 0.0;         ///< voxel edge, m
  std::uint32_t detection_count = 0; ///< frames in which it was detected
  /// frames in which it was in view (rendered) but not detected, integrated without foreground probability
  std::uint32_t undetected_count = 0;
  TsdfMap tsdf;

  MappedObject(std::uint32_t id_, int class_id_, std::string name, const TsdfParams& params)
      : id(id_), class_id(class_id_), class_name(std::move(name)), resolution_m(params.resolution_m), tsdf(params) {}
};

/// Distance between the nearest centres of a's and b's tracked surface voxels
/// (TsdfParams::trackedForeground()), m; infinity if none lie under max_m
/// apart or either has none. Cost: (2 ceil(max_m / resolution) + 1)^3 lookups
/// per surface voxel of a: give the smaller map as a.
/// @throws std::invalid_argument if the maps do not share one voxel grid (resolution and block size)
double trackedSurfaceDistance(const TsdfMap& a, const TsdfMap& b, double max_m);

/// A detection of the current frame after matching.
struct ObjectDetection {
  std::uint16_t instance_id = 0;  ///< its pixels' value in the instance image
  std::uint32_t object_id = 0;    ///< matched object, 0 = create a new object
  int class_id = 0;               ///< class of the detection
};

/// What integrateFrame did.
struct FrameIntegration {
  std::vector<std::uint32_t> created;     ///< new object ids
  std::vector<std::uint32_t> detected;    ///< objects updated as detected (incl. created)
  std::vector<std::uint32_t> undetected;  ///< visible objects updated without foreground probability
  /// (merged, into): objects found to be the same as a detected one (see ObjectMapConfig::merge_fraction), now gone
  std::vector<std::pair<std::uint32_t, std::uint32_t>> merged;
  /// One per `merged` entry, in its order: which rule merged them, with its figures (for the log).
  std::vector<std::string> merge_reasons;
  /// (new, from): objects split off a known one, whose detection lay split_gap_m apart from another detection of
  /// it in this frame (see ObjectMapConfig::split_gap_m); also listed in `created`
  std::vector<std::pair<std::uint32_t, std::uint32_t>> split;
  std::uint32_t dropped_unknown_class = 0;   ///< detections with a class id outside the class table
  std::uint32_t dropped_not_of_interest = 0; ///< detections of classes without object maps
  std::uint32_t dropped_unknown_object = 0;  ///< detections matched to an object id the map does not have
  std::uint32_t dropped_full = 0;            ///< new objects refused: no free 16-bit id (see ObjectIdPool)
  /// new objects not kept: under min_new_object_pixels mask pixels with depth outside other objects, or no
  /// surface voxel after integration
  std::uint32_t dropped_empty = 0;
};

/// Paper Eq. (1): gain of a surface seen from d_exp_m that was observed from
/// at best d_node_m, with desired distance d_desired_m, normalised by d_max_m; in [0, 1].
double objectDistanceGain(double d_node_m, double d_exp_m, double d_desired_m, double d_max_m);

class ObjectMap {
 public:
  /// @throws ConfigError if a config is invalid
  ObjectMap(const ObjectMapConfig& config, const ClassTable& classes);

  const ObjectMapConfig& config() const { return config_; }
  const ClassTable& classes() const { return classes_; }

  /// "" if every class's object map can hold all surfaces seen from inside
  /// `bounds` up to `range_m` away (TsdfParams::maxCoordinate_m at the class's
  /// resolution), else why not. Camera poses outside the bounds must then be
  /// refused by the caller.
  std::string checkBounds(const Bounds& bounds, double range_m) const;
  /// Empty if every class of interest is integrated out to d_bg_m (m) at least, the distance the background
  /// is observed from so that objects are found; else why not (the noise band's depth limit,
  /// TsdfParams::maxIntegratedDepth_m, falls with the class resolution).
  std::string checkIntegratedDepth(double d_bg_m) const;

  /// New empty object of class `class_id` at the class's resolution; 0 if
  /// the class is unknown or no 16-bit id is free (see ObjectIdPool).
  std::uint32_t createObject(int class_id);
  const MappedObject* object(std::uint32_t id) const;
  const std::map<std::uint32_t, std::unique_ptr<MappedObject>>& objects() const { return objects_; }

  /// Integrates one frame.
  /// 1. Renders the known objects (occluded by the depth image and each other).
  /// 2. Each detection of a class of interest updates its object (created if
  ///    object_id == 0) through its mask minus the pixels rendered as another
  ///    object, foreground probability included; detections of one object are
  ///    merged, so detection_count grows by one per frame.
  ///    Two detections of one object whose surfaces lie split_gap_m apart
  ///    split it: the second starts a new object (see ObjectMapConfig).
  ///    Mask pixels behind a depth edge of their mask neither fill nor carve
  ///    the object (ObjectMapConfig::mask_depth_edge_m).
  ///    A visible undetected object of the same class whose render lies
  ///    mostly inside such a mask (merge_fraction) is the same object seen
  ///    in pieces before if its surface also lies inside the detected one's
  ///    box, or if one of the two is a small piece of the other touching it
  ///    (ObjectMapConfig::piece_max_share): the two are merged. The merged
  ///    object keeps the detected one's id, unless the detected one is the
  ///    piece (and was not split in this frame): then the larger keeps its own.
  /// 3. Every other rendered object updates SDF and colour through its
  ///    rendered mask, without the foreground probability.
  /// @param depth_m CV_32FC1 m; rgb CV_8UC3 or empty; instance_image CV_16UC1 (same size)
  /// @param rendered optional: render() of the current map from the same pose
  ///        and depth (e.g. the one matching used), so step 1 is skipped
  /// @throws std::invalid_argument if the images do not match the camera
  FrameIntegration integrateFrame(const PinholeCamera& camera, const Eigen::Isometry3d& T_WC, const cv::Mat& depth_m,
                                  const cv::Mat& rgb, const cv::Mat& instance_image,
                                  const std::vector<ObjectDetection>& detections, const cv::Mat* rendered = nullptr);

  /// Grows with every integrated frame (a render is reusable while it is unchanged).
  std::uint64_t version() const { return version_; }

  /// Renders all objects from T_WC into `object_ids` (CV_16UC1, 0 = none).
  /// Each pixel shows the nearest object surface (foreground probability >
  /// 0.5), hidden if it lies farther than the measured depth plus
  /// render_depth_tolerance_m + render_depth_tolerance_rel * depth (`depth_m` CV_32FC1 m, or empty for no occlusion;
  /// invalid depth pixels do not occlude).
  /// @param depth_out optional CV_32FC1 z-depth of the shown surface, m (0 = none)
  void render(const PinholeCamera& camera, const Eigen::Isometry3d& T_WC, const cv::Mat& depth_m,
              cv::Mat& object_ids, cv::Mat* depth_out = nullptr) const;

  /// Object gain images for a batch of positions (layout: SphericalGrid).
  /// Per ray: the nearest object surface before max_depth_m (or d_max_m);
  /// gain = Eq. (1) with d_obj_m on that surface's minimum observed distance;
  /// hit depth = its distance, d_max_m if none.
  /// @param max_depth_m empty, or grid.width * grid.height values per position
  ///        (row-major), the ray's occluding depth, m (NaN = none)
  /// @param gains, hit_depth_m one CV_32FC1 grid.height x grid.width image per position
  void computeGains(const std::vector<Eigen::Vector3d>& positions_W, const SphericalGrid& grid,
                    const std::vector<float>& max_depth_m, double d_obj_m, double d_max_m, std::vector<cv::Mat>& gains,
                    std::vector<cv::Mat>& hit_depth_m) const;

  /// The object's summary as saved and published (ObjectInfo): that of its
  /// reconstructed surface (foreground over 0.5, observed share from <=
  /// d_obj_m), or, while it has none, of its tracked surface
  /// (TsdfParams::trackedForeground()). An object made from one detection
  /// whose pixels all lay near its mask's border has only a tracked surface
  /// under the foreground prior; it still needs a place and a share for the
  /// planner, not a box at the origin.
  TsdfSummary summarize(const MappedObject& object, double d_obj_m) const;

  /// The object's mesh as saved and published: TsdfMap::extractMesh over the
  /// voxels that pass ObjectMapConfig::meshGate() (mesh_min_weight and the SDF
  /// error gate mesh_max_sdf_std_m), without the pieces farther than
  /// mesh_fragment_gap_m from its main surface.
  Mesh mesh(const MappedObject& object) const;

  /// Writes object_<id>_<class>.ply per object and objects.json (the
  /// summaries) into `directory` (created if missing). Returns the written
  /// paths; on failure returns what was written so far and sets `error`.
  std::vector<std::string> save(const std::string& directory, double d_obj_m, std::string* error = nullptr) const;

  /// Ids present in an object-id image, ascending.
  static std::vector<std::uint32_t> visibleIds(const cv::Mat& object_ids);

 private:
  /// The TSDF geometry of a new object of class_id (the class's resolution, the config's truncation and bands).
  TsdfParams tsdfParams(int class_id) const;
  /// separateMasks(a, b) with the rims each mask bled onto surfaces behind it left out (they would join the two).
  MaskSeparation separation(const cv::Mat& a, const cv::Mat& b, const PinholeCamera& camera,
                            const cv::Mat& depth_m) const;
  /// Step 2's merges (object_map_merge.cpp): finds the objects not detected in this frame that are the same
  /// object as a detected one (inside its box, or a piece of it), merges them and lists them in result.merged.
  /// Where the detected object is the piece, the other keeps its id and takes over its mask in `masks`.
  /// @param masks detected object id -> the union of its detections' masks in this frame
  /// @param keep_ids detected objects that keep their id in any case (those split in this frame)
  /// @return merged id -> the id it was merged into (every key is gone from the map)
  std::map<std::uint32_t, std::uint32_t> mergeSameObjects(const PinholeCamera& camera, const cv::Mat& depth_m,
                                                          const cv::Mat& rendered,
                                                          std::map<std::uint32_t, cv::Mat>& masks,
                                                          const std::set<std::uint32_t>& keep_ids,
                                                          FrameIntegration& result);
  ObjectMapConfig config_;
  ClassTable classes_;
  std::map<std::uint32_t, std::unique_ptr<MappedObject>> objects_;
  ObjectIdPool ids_;  ///< ids of erased and merged objects come back (see ObjectIdPool)
  std::uint64_t version_ = 0;
};

}  // namespace semexp

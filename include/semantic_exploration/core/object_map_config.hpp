#pragma once
/// @file object_map_config.hpp
/// Settings of the per-object TSDF submaps (paper Section IV-B).

#include <cmath>
#include <string>

#include "semantic_exploration/core/config_error.hpp"
#include "semantic_exploration/core/mesh_gate.hpp"
#include "semantic_exploration/core/object_masks.hpp"

namespace semexp {

struct ObjectMapConfig {
  double truncation_voxels = 4.0;  ///< TSDF truncation distance in voxels of the object's resolution
  double max_weight = 100.0;       ///< TSDF weight cap (one unit per full-weight observation; <= 4095, 1/16 fixed point)
  int block_size = 8;              ///< voxels per block edge
  double publish_period_s = 1.0;   ///< minimum period between mesh marker updates, s
  /// How far behind the measured surface voxels are still updated, in voxels
  /// (<= truncation_voxels); keeps free space hidden behind edges from being dug in.
  double behind_surface_voxels = 2.0;
  /// The band behind the surface also covers q d^2 behind a depth d (3 sigma of
  /// the depth noise: q = 3 s for sigma = s d^2), 1/m; depths whose q d^2 exceeds
  /// the truncation are not integrated (TsdfParams::behind_surface_quadratic_per_m).
  /// 0 = a fixed band.
  double behind_surface_quadratic_per_m = 0.006;
  /// Observations from depths up to this count fully in the TSDF and the
  /// foreground probability; a deeper depth d counts (full_weight_depth_m / d)^2,
  /// rounded to the 1/16 weight step and at least 1/16 (TsdfParams::full_weight_depth_m).
  /// The depth noise grows as d^2, so a view from 3 m would otherwise pull a
  /// surface as hard as one from 1 m. m; 0 = every observation counts 1 (the paper's update).
  double full_weight_depth_m = 0.0;
  /// A rendered object surface farther than the measured depth d plus
  /// render_depth_tolerance_m + render_depth_tolerance_rel * d is hidden
  /// (the relative part follows the depth noise, which grows with distance).
  double render_depth_tolerance_m = 0.05;  ///< m
  double render_depth_tolerance_rel = 0.03; ///< fraction of the measured depth
  /// A visible object that was not detected in a frame, whose rendered pixels
  /// lie at least this much (fraction) inside the mask of a detected object
  /// of the same class and whose surface box lies this much inside that
  /// object's box, is the same object: it is merged into that one. So is an
  /// object detected only once and not rendered in the frame whose surface
  /// box lies this much inside a larger detected object's box.
  double merge_fraction = 0.8;
  /// A visible undetected object rendered merge_fraction inside a detected
  /// one's mask whose box reaches past that object's box is still merged
  /// when one of the two is a piece of the other: it holds at most this share
  /// of the other's tracked surface voxels, their surfaces within the mask
  /// lie less than split_gap_m apart, and their nearest tracked surface
  /// voxels less than piece_max_distance_m. Where the detected object is the
  /// piece, the larger keeps its id. The tracked voxel count is a
  /// proxy for size: it counts what has been seen of each so far. In the
  /// missions traced, pieces held 2-19% of the other object's count and
  /// neighbouring chairs 61-88% (smaller / larger; docs/BENCHMARKS.md).
  /// Fraction; 0 = off (so is split_gap_m 0).
  double piece_max_share = 0.3;
  /// The piece rule's 3D test: the nearest centres of the two objects'
  /// tracked surface voxels lie less than this apart. The mask gap alone
  /// cannot tell a piece that touches from a small object standing in front
  /// of the larger one (both give negative gaps). In the missions traced, the
  /// pieces lay 0.000 and 0.045 m from their chair, the two small objects it
  /// must keep apart 0.22 and 0.24 m (docs/BENCHMARKS.md): 0.1 m leaves a
  /// factor of two either side. m; must be > 0.
  double piece_max_distance_m = 0.1;
  /// A new object is made only from a detection that keeps at least this many
  /// mask pixels with valid depth outside the (grown) renders of known objects,
  /// px; fewer (a rim round a known object) would make a spurious object of a
  /// few voxels that later views never render, update or merge.
  int min_new_object_pixels = 100;
  /// Depth-edge-aware masks: a detection's mask pixel whose depth lies more
  /// than mask_depth_edge_m + mask_depth_edge_rel * d behind the nearest depth
  /// d of the mask within mask_depth_edge_window_px pixels is where the mask
  /// bled past the object onto a surface behind it; it neither fills nor
  /// carves the object (see markDepthEdges). 0 px = off.
  double mask_depth_edge_m = 0.3;      ///< m
  double mask_depth_edge_rel = 0.05;   ///< fraction of the nearer depth
  int mask_depth_edge_window_px = 8;   ///< px, at least the width a mask bleeds by

  /// Two detections matched to one object in one frame whose 3D points lie
  /// at least this far apart (maskGap_m) are two objects the map had taken
  /// for one (a bled mask covered both): the second starts an object of its
  /// own. Parts of one object that a detector split into two masks touch. m; 0 = off.
  double split_gap_m = 0.05;

  /// A detection's mask pixel k <= foreground_border_px pixels inside its
  /// border raises the foreground probability by less: its evidence is
  /// 0.5 + 0.5 k / (foreground_border_px + 1) instead of 1 (markMaskBorder).
  /// A mask that bleeds in some detections only (onto the floor round the
  /// legs, the edge of a table: surfaces at the object's depth, which
  /// depth edges do not catch) then leaves the bled ring under foreground 0.5
  /// while the object's own border, inside the mask in every detection,
  /// stays above it. px, at least the width a mask bleeds by; 0 = off.
  int foreground_border_px = 8;

  /// Foreground probability of a voxel before its first observation and the
  /// weight that belief keeps in the foreground average, in full-weight
  /// observations (TsdfParams::foreground_prior). A prior under 0.5 with some
  /// weight needs several detections to bring a voxel's surface into the mesh:
  /// a surface a mask bled onto in one or two detections stays out of it.
  /// Matching, the new-object test, the extent of a piece to be merged and the
  /// planner's object rays see the tracked surface, every voxel a detection
  /// lifted above the prior (TsdfParams::trackedForeground()); the mesh, the
  /// observed share and the extent of the object a piece merges into keep 0.5
  /// (the mesh: mesh_min_foreground, 0.5 by default).
  /// foreground_prior_weight * (0.5 - foreground_prior) must stay under 0.5:
  /// one full-evidence observation then still lifts a new voxel above 0.5
  /// (a detection seen whole gives its object a mesh surface at once).
  /// Off by default (the paper's update): with 0.3 and weight 2 the
  /// exploration_objects_setpoints rostest once saw a chair 64% complete,
  /// under its 70% bound (docs/BENCHMARKS.md). With 0.3 and weight 2, one
  /// full detection lifts a new voxel to 0.53, one whose evidence is under
  /// 0.9 (7 px or less inside a mask's border, see foreground_border_px)
  /// leaves it under 0.5; with all the simulator's faults on, it took the
  /// median object RMSE from 5.82 to 1.59 cm on the same frames.
  /// foreground_prior_weight 0 = the paper's update.
  double foreground_prior = 0.5;         ///< probability, [0, 1]
  double foreground_prior_weight = 0.0;  ///< observations, [0, max_weight]

  /// Meshes (saved and published) keep the largest connected piece of an
  /// object's surface and the pieces within this distance of it (see
  /// dropMeshFragments); farther pieces are strays that bled masks or noise
  /// left (a few vertices a metre or more from the chair). The TSDF keeps them. m; 0 = off.
  double mesh_fragment_gap_m = 0.3;
  /// Meshes (saved and published) leave out each marching cube one of whose
  /// 8 voxels holds less weight than this (TsdfMapT::extractMesh): a zero
  /// crossing that few observations support is where depth noise left a
  /// surface in the air beside the object. A voxel gains up to 1 per view
  /// (less just behind the surface where rays run oblique, and less beyond
  /// full_weight_depth_m), so 2 meshes a surface seen about three times.
  /// 2 is the least weight that keeps a noisy chair's strays under 1% of its
  /// vertices with the simulator's depth noise; with that noise doubled it
  /// takes 4. It costs completeness on objects seen only in passing (a chair
  /// of a 250 s rostest flight fell under 70%), so the default stays 0, the
  /// paper's extraction (docs/BENCHMARKS.md). The TSDF, the render for
  /// matching and the observed share keep every voxel. Full-weight
  /// observations, <= max_weight; 0 = every observed voxel.
  double mesh_min_weight = 0.0;
  /// Meshes also leave out each marching cube one of whose voxels has a
  /// fused SDF whose standard error, as estimated by MeshGate::max_sdf_std_m
  /// (depth_noise at the nearest distance the voxel was seen from over the
  /// square root of its weight: a lower bound), exceeds this. Unlike
  /// mesh_min_weight it asks more observations of a surface seen only from
  /// far, and four times as many of a sensor twice as noisy (with
  /// depth_noise set to that sensor's). m; 0 = off (the paper's extraction).
  double mesh_max_sdf_std_m = 0.0;
  /// The camera's depth noise (Table I; the simulator's noise block), for
  /// mesh_max_sdf_std_m.
  DepthNoise depth_noise;
  /// Meshes also leave out each marching cube whose 8 voxels' mean
  /// foreground probability is at or under this (MeshGate::min_foreground).
  /// 0.5 is the paper's extraction. Above it, surface that a bled mask lifted
  /// only just over 0.5 in one or two detections stays out: a wall strip
  /// behind a chair, seen from afar, held foreground 0.5-0.6 where the
  /// chair's own surface held a median of 0.83 (docs/BENCHMARKS.md).
  /// Probability, [0.5, 1). The TSDF, the tracked surface (matching, the
  /// planner's object rays) and the observed share are unaffected.
  double mesh_min_foreground = 0.5;
  /// ObjectMap::save also writes each object's TSDF (object_<id>_<class>.tsdf,
  /// tsdf_io.hpp) beside its mesh, so that meshes can be extracted again
  /// offline under another gate (remesh_objects) without flying again.
  /// Every save does (run_mission.py's periodic snapshots too): a few MB
  /// per object.
  bool save_tsdf = false;

  /// The voxels saved and published meshes are extracted over.
  MeshGate meshGate() const {
    MeshGate g;
    g.min_weight = static_cast<float>(mesh_min_weight);
    g.max_sdf_std_m = mesh_max_sdf_std_m;
    g.noise = depth_noise;
    g.min_foreground = static_cast<float>(mesh_min_foreground);
    return g;
  }

  DepthEdgeParams depthEdgeParams() const {
    return {mask_depth_edge_m, mask_depth_edge_rel, mask_depth_edge_window_px};
  }

  void validate(const std::string& ns = "object_map/") const {
    require(std::isfinite(truncation_voxels) && truncation_voxels >= 1, ns + "truncation_voxels", "must be >= 1");
    require(std::isfinite(max_weight) && max_weight >= 1 && max_weight <= 4095, ns + "max_weight",
            "must be in [1, 4095] (16-bit fixed-point weight)");
    require(block_size >= 2 && block_size <= 64 && (block_size & (block_size - 1)) == 0, ns + "block_size",
            "must be a power of two in [2, 64]");
    require(publish_period_s >= 0, ns + "publish_period_s", "must be >= 0 s");
    require(std::isfinite(behind_surface_voxels) && behind_surface_voxels >= 1 &&
                behind_surface_voxels <= truncation_voxels,
            ns + "behind_surface_voxels", "must be in [1, truncation_voxels]");
    require(std::isfinite(behind_surface_quadratic_per_m) && behind_surface_quadratic_per_m >= 0,
            ns + "behind_surface_quadratic_per_m", "must be >= 0 1/m");
    require(std::isfinite(full_weight_depth_m) && full_weight_depth_m >= 0, ns + "full_weight_depth_m",
            "must be >= 0 m");
    require(std::isfinite(render_depth_tolerance_m) && render_depth_tolerance_m >= 0, ns + "render_depth_tolerance_m",
            "must be >= 0 m");
    require(std::isfinite(merge_fraction) && merge_fraction > 0.5 && merge_fraction <= 1, ns + "merge_fraction",
            "must be in (0.5, 1]");
    require(std::isfinite(piece_max_share) && piece_max_share >= 0 && piece_max_share < 1, ns + "piece_max_share",
            "must be in [0, 1) (1 would take any two touching objects for one)");
    require(std::isfinite(piece_max_distance_m) && piece_max_distance_m > 0, ns + "piece_max_distance_m",
            "must be > 0 m");
    require(std::isfinite(render_depth_tolerance_rel) && render_depth_tolerance_rel >= 0 && render_depth_tolerance_rel < 1,
            ns + "render_depth_tolerance_rel", "must be in [0, 1)");
    require(min_new_object_pixels >= 1, ns + "min_new_object_pixels", "must be >= 1 px");
    require(std::isfinite(mask_depth_edge_m) && mask_depth_edge_m > 0, ns + "mask_depth_edge_m", "must be > 0 m");
    require(std::isfinite(mask_depth_edge_rel) && mask_depth_edge_rel >= 0, ns + "mask_depth_edge_rel", "must be >= 0");
    require(std::isfinite(split_gap_m) && split_gap_m >= 0, ns + "split_gap_m", "must be >= 0 m");
    require(std::isfinite(mesh_fragment_gap_m) && mesh_fragment_gap_m >= 0, ns + "mesh_fragment_gap_m", "must be >= 0 m");
    require(std::isfinite(mesh_min_weight) && mesh_min_weight >= 0 && mesh_min_weight <= max_weight,
            ns + "mesh_min_weight", "must be in [0, max_weight] observations");
    depth_noise.validate(ns + "depth_noise/");
    require(std::isfinite(mesh_max_sdf_std_m) && mesh_max_sdf_std_m >= 0, ns + "mesh_max_sdf_std_m",
            "must be >= 0 m");
    // Else no voxel could ever pass (even at the noise floor and max_weight): every mesh would stay empty.
    require(mesh_max_sdf_std_m == 0 || depth_noise.sigma_min_m <= mesh_max_sdf_std_m * std::sqrt(max_weight),
            ns + "mesh_max_sdf_std_m", "must be 0 or >= depth_noise/sigma_min_m / sqrt(max_weight)");
    require(std::isfinite(mesh_min_foreground) && mesh_min_foreground >= 0.5 && mesh_min_foreground < 1,
            ns + "mesh_min_foreground", "must be in [0.5, 1) (no mean foreground exceeds 1)");
    require(foreground_border_px >= 0 && foreground_border_px <= 64, ns + "foreground_border_px",
            "must be in [0, 64] px");
    require(std::isfinite(foreground_prior) && foreground_prior >= 0 && foreground_prior <= 1,
            ns + "foreground_prior", "must be in [0, 1]");
    require(std::isfinite(foreground_prior_weight) && foreground_prior_weight >= 0 &&
                foreground_prior_weight <= max_weight,
            ns + "foreground_prior_weight", "must be in [0, max_weight]");
    // One detection must raise a voxel above 0.5, else no new object ever holds a surface.
    require(foreground_prior_weight * (0.5 - foreground_prior) < 0.5, ns + "foreground_prior_weight",
            "times (0.5 - foreground_prior) must be < 0.5: one detection could not make an object");
    require(mask_depth_edge_window_px >= 0 && mask_depth_edge_window_px <= 64, ns + "mask_depth_edge_window_px",
            "must be in [0, 64] px");
  }
};

}  // namespace semexp

#pragma once
/// @file object_remesh.hpp
/// Meshes of a saved object map extracted again under another gate, from the
/// TSDFs ObjectMap::save writes with object_map/save_tsdf: a gate can be
/// compared on the same flight without flying it again.

#include <string>

#include "semantic_exploration/core/config_error.hpp"

#include "semantic_exploration/core/mesh_gate.hpp"
#include "semantic_exploration/core/object_map_config.hpp"

namespace semexp {

/// The mesh settings of `c` (those readSavedMeshSettings reads) as
/// objects.json records them, the "mesh_gate" object: the object_map
/// parameter names, %.17g so that they read back exactly.
std::string meshGateJson(const ObjectMapConfig& c);

/// Sets the mesh settings of `c` (mesh_min_weight, mesh_max_sdf_std_m,
/// mesh_min_foreground, mesh_fragment_gap_m, depth_noise) to those a saved
/// object map records in dir/objects.json ("mesh_gate"), the ones its meshes
/// were extracted under. False (and `c` unchanged, *error set) if the index
/// cannot be read or records no gate.
bool readSavedMeshSettings(const std::string& dir, ObjectMapConfig& c, std::string* error = nullptr);

/// For every object_<id>_<class>.tsdf in in_dir, writes
/// object_<id>_<class>.ply to out_dir (created if needed): objectMesh under
/// c.meshGate() and c.mesh_fragment_gap_m. Writes out_dir/objects.json as
/// in_dir's with its mesh_gate set to c's, so that out_dir reads as a saved
/// object map of those meshes (its index still names the TSDFs, which stay
/// in in_dir). Returns the meshes written, or -1 with *error set: `c` is
/// invalid (the message names the parameter); out_dir is in_dir, or holds
/// meshes of objects in_dir has no TSDF of (another map's: nothing is
/// deleted); in_dir holds no TSDF or no objects.json; a TSDF does not load;
/// a file cannot be written.
int remeshSavedObjects(const std::string& in_dir, const std::string& out_dir, const ObjectMapConfig& c,
                       std::string* error = nullptr);

}  // namespace semexp

#pragma once
/// @file object_remesh.hpp
/// Meshes of a saved object map extracted again under another gate, from the
/// TSDFs ObjectMap::save writes with object_map/save_tsdf: a gate can be
/// compared on the same flight without flying it again.

#include <string>

#include "semantic_exploration/core/mesh_gate.hpp"

namespace semexp {

/// For every object_<id>_<class>.tsdf in in_dir, writes
/// object_<id>_<class>.ply to out_dir (created if needed): objectMesh under
/// `gate` and fragment_gap_m (m). Copies objects.json when out_dir differs,
/// so that out_dir reads as a saved object map. Returns the meshes written,
/// or -1 with *error set (in_dir holds no TSDF or no objects.json, a TSDF
/// does not load, a file cannot be written).
int remeshSavedObjects(const std::string& in_dir, const std::string& out_dir, const MeshGate& gate,
                       double fragment_gap_m, std::string* error = nullptr);

}  // namespace semexp

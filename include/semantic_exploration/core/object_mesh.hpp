#pragma once
/// @file object_mesh.hpp
/// An object's mesh without stray fragments: surface bits that bled masks or
/// noise left far from the object's body.

#include <cstddef>

#include "semantic_exploration/core/marching_cubes.hpp"
#include "semantic_exploration/core/mesh_gate.hpp"
#include "semantic_exploration/core/tsdf.hpp"

namespace semexp {

/// Keeps the largest connected piece of `mesh` (pieces share vertices) and
/// every piece with a vertex within gap_m of a kept vertex, repeatedly; drops
/// the rest. An object is one compact surface: a piece farther than gap_m from
/// all of it is not the object's. gap_m <= 0 keeps everything.
/// @return vertices dropped
std::size_t dropMeshFragments(Mesh& mesh, double gap_m);

/// An object's mesh as saved and published: TsdfMap::extractMesh over the
/// voxels that pass `gate`, then dropMeshFragments at fragment_gap_m.
Mesh objectMesh(const TsdfMap& tsdf, const MeshGate& gate, double fragment_gap_m);

}  // namespace semexp

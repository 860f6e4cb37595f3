#pragma once
/// @file marching_cubes.hpp
/// Triangle meshes, the marching-cubes case table and PLY export.
///
/// The case table is not a hand-typed copy of the classic 256-entry table: it
/// is derived once at start-up from the cube's faces (see marching_cubes.cpp),
/// so every case is correct by construction and face ambiguities are resolved
/// the same way in both cubes sharing a face (watertight meshes).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace semexp {

/// Indexed triangle mesh with per-vertex colour. Triangles are wound
/// counter-clockwise seen from outside (normal towards positive SDF).
struct Mesh {
  std::vector<Eigen::Vector3f> vertices_W;              ///< vertex positions, m
  std::vector<std::array<std::uint8_t, 3>> colours;     ///< rgb8 per vertex (same size as vertices_W)
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< vertex indices

  bool empty() const { return triangles.empty(); }
  /// Appends `other` (indices shifted).
  void append(const Mesh& other);
};

/// Writes `mesh` as a binary little-endian PLY (vertex x y z float, red green
/// blue uchar; face vertex_indices uchar/uint), atomically (writeFileAtomically:
/// a failed write leaves the previous file). Returns false on I/O failure and
/// then says why in `error` (if given).
bool writePly(const Mesh& mesh, const std::string& path, std::string* error = nullptr);

/// Reads a PLY written by writePly (binary little-endian or ASCII with the
/// same element layout). Returns false if the file is not in that layout.
bool readPly(const std::string& path, Mesh& mesh);

/// Marching-cubes case table.
///
/// Cube corner i sits at offset ((i & 1), (i >> 1) & 1, (i >> 2) & 1) voxels.
/// Case index bit i is set when corner i is inside (SDF < 0). Edge e joins
/// corners kEdgeCorners[e][0] and kEdgeCorners[e][1].
struct MarchingCubesTable {
  static constexpr int kEdgeCorners[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                               {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  /// Per case: triangles as triples of edge ids, at most 12 triangles (-1 terminated).
  std::array<std::array<std::int8_t, 37>, 256> triangles;

  /// The table, built on first use (thread-safe).
  static const MarchingCubesTable& get();
};

}  // namespace semexp

#include "semantic_exploration/core/object_mesh.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>
#include <vector>

#include "semantic_exploration/core/neighbour_cells.hpp"

namespace semexp {

namespace {

std::uint32_t findRoot(std::vector<std::uint32_t>& parent, std::uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

}  // namespace

std::size_t dropMeshFragments(Mesh& mesh, double gap_m) {
  const std::size_t n = mesh.vertices_W.size();
  if (!(gap_m > 0.0) || n == 0) return 0;
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  for (const auto& t : mesh.triangles)
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t a = findRoot(parent, t[0]), b = findRoot(parent, t[k]);
      if (a != b) parent[b] = a;
    }
  // Pieces as vertex lists, largest first.
  std::unordered_map<std::uint32_t, std::size_t> piece_of_root;
  std::vector<std::vector<std::uint32_t>> pieces;
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t r = findRoot(parent, i);
    auto it = piece_of_root.find(r);
    if (it == piece_of_root.end()) {
      it = piece_of_root.emplace(r, pieces.size()).first;
      pieces.emplace_back();
    }
    pieces[it->second].push_back(i);
  }
  if (pieces.size() == 1) return 0;
  std::stable_sort(pieces.begin(), pieces.end(), [](const auto& a, const auto& b) { return a.size() > b.size(); });
  // Kept vertices hashed in cells of gap_m: a vertex within gap_m of one lies in the 27 cells round its own.
  const float inv_cell = static_cast<float>(1.0 / gap_m);
  const float gap2 = static_cast<float>(gap_m * gap_m);
  std::unordered_map<Eigen::Vector3i, std::vector<std::uint32_t>, VoxelIndexHash> grid;
  const auto cell = [&](const Eigen::Vector3f& p) { return (p * inv_cell).array().floor().cast<int>().matrix().eval(); };
  std::vector<bool> keep_vertex(n, false), kept(pieces.size(), false);
  const auto keepPiece = [&](std::size_t k) {
    kept[k] = true;
    for (const std::uint32_t i : pieces[k]) {
      keep_vertex[i] = true;
      grid[cell(mesh.vertices_W[i])].push_back(i);
    }
  };
  const auto near = [&](std::uint32_t i) {
    const Eigen::Vector3f& p = mesh.vertices_W[i];
    return visitNeighbourCells(grid, cell(p),
                               [&](std::uint32_t j) { return (mesh.vertices_W[j] - p).squaredNorm() <= gap2; });
  };
  keepPiece(0);
  for (bool changed = true; changed;) {  // a piece kept can bring another within reach
    changed = false;
    for (std::size_t k = 1; k < pieces.size(); ++k) {
      if (kept[k] || !std::any_of(pieces[k].begin(), pieces[k].end(), near)) continue;
      keepPiece(k);
      changed = true;
    }
  }
  Mesh out;
  std::vector<std::uint32_t> index(n, 0);
  for (std::uint32_t i = 0; i < n; ++i) {
    if (!keep_vertex[i]) continue;
    index[i] = static_cast<std::uint32_t>(out.vertices_W.size());
    out.vertices_W.push_back(mesh.vertices_W[i]);
    if (i < mesh.colours.size()) out.colours.push_back(mesh.colours[i]);
  }
  for (const auto& t : mesh.triangles)
    if (keep_vertex[t[0]]) out.triangles.push_back({index[t[0]], index[t[1]], index[t[2]]});
  const std::size_t dropped = n - out.vertices_W.size();
  mesh = std::move(out);
  return dropped;
}

Mesh objectMesh(const TsdfMap& tsdf, const MeshGate& gate, double fragment_gap_m) {
  Mesh m = tsdf.extractMesh(gate);
  dropMeshFragments(m, fragment_gap_m);
  return m;
}

}  // namespace semexp

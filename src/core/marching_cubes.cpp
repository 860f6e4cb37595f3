#include "semantic_exploration/core/marching_cubes.hpp"

#include "semantic_exploration/core/atomic_file.hpp"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <sstream>

namespace semexp {

constexpr int MarchingCubesTable::kEdgeCorners[12][2];

void Mesh::append(const Mesh& other) {
  const auto offset = static_cast<std::uint32_t>(vertices_W.size());
  vertices_W.insert(vertices_W.end(), other.vertices_W.begin(), other.vertices_W.end());
  colours.insert(colours.end(), other.colours.begin(), other.colours.end());
  for (const auto& t : other.triangles) triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
}

namespace {

// Cube faces, corners listed counter-clockwise seen from outside the cube.
constexpr int kFaces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

int edgeOf(int a, int b) {
  for (int e = 0; e < 12; ++e) {
    const int* c = MarchingCubesTable::kEdgeCorners[e];
    if ((c[0] == a && c[1] == b) || (c[0] == b && c[1] == a)) return e;
  }
  return -1;
}

// The iso-surface of one case is a set of closed polygons whose sides lie on
// the cube faces. On each face, walking the corners counter-clockwise (seen
// from outside), a side runs from the edge where the walk enters the inside
// to the edge where it next leaves it; each inside run of corners is thus cut
// off separately (the ambiguous face separates its inside corners). Each
// crossed edge is entered on one of its faces and left on the other, so
// following "entered -> left" chains the sides into loops, which are oriented
// so a fan over them faces the outside (positive SDF).
MarchingCubesTable build() {
  MarchingCubesTable table;
  for (int mc_case = 0; mc_case < 256; ++mc_case) {
    auto& out = table.triangles[mc_case];
    out.fill(-1);
    const auto inside = [&](int corner) { return ((mc_case >> corner) & 1) != 0; };
    int next[12];
    std::fill(next, next + 12, -1);
    for (const auto& face : kFaces) {
      for (int k = 0; k < 4; ++k) {
        const int a = face[k], b = face[(k + 1) % 4];
        if (inside(a) || !inside(b)) continue;  // not an entry
        for (int j = 1; j < 4; ++j) {
          const int c = face[(k + j) % 4], d = face[(k + j + 1) % 4];
          if (inside(c) && !inside(d)) {
            next[edgeOf(a, b)] = edgeOf(c, d);
            break;
          }
        }
      }
    }
    bool used[12] = {false};
    int n_out = 0;
    for (int start = 0; start < 12; ++start) {
      if (next[start] < 0 || used[start]) continue;
      std::vector<int> loop;
      for (int e = start; !used[e]; e = next[e]) {
        used[e] = true;
        loop.push_back(e);
      }
      for (size_t i = 1; i + 1 < loop.size(); ++i) {
        out[n_out++] = static_cast<std::int8_t>(loop[0]);
        out[n_out++] = static_cast<std::int8_t>(loop[i]);
        out[n_out++] = static_cast<std::int8_t>(loop[i + 1]);
      }
    }
  }
  return table;
}

}  // namespace

const MarchingCubesTable& MarchingCubesTable::get() {
  static const MarchingCubesTable table = build();
  return table;
}

namespace {

void writePlyTo(const Mesh& mesh, std::ostream& f) {
  f << "ply\nformat binary_little_endian 1.0\ncomment semantic_exploration object mesh\n"
    << "element vertex " << mesh.vertices_W.size() << "\n"
    << "property float x\nproperty float y\nproperty float z\n"
    << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    << "element face " << mesh.triangles.size() << "\n"
    << "property list uchar uint vertex_indices\nend_header\n";
  // Assemble little-endian records byte by byte so big-endian hosts write the same file.
  std::vector<char> buf;
  buf.reserve(mesh.vertices_W.size() * 15 + mesh.triangles.size() * 13);
  const auto put32 = [&buf](std::uint32_t v) {
    for (int i = 0; i < 4; ++i) buf.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  };
  for (size_t i = 0; i < mesh.vertices_W.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      std::uint32_t bits;
      const float x = mesh.vertices_W[i][k];
      std::memcpy(&bits, &x, 4);
      put32(bits);
    }
    const auto& c = i < mesh.colours.size() ? mesh.colours[i] : std::array<std::uint8_t, 3>{200, 200, 200};
    for (int k = 0; k < 3; ++k) buf.push_back(static_cast<char>(c[k]));
  }
  for (const auto& t : mesh.triangles) {
    buf.push_back(3);
    for (int k = 0; k < 3; ++k) put32(t[k]);
  }
  f.write(buf.data(), static_cast<std::streamsize>(buf.size()));
}

}  // namespace

bool writePly(const Mesh& mesh, const std::string& path, std::string* error) {
  try {
    writeFileAtomically(path, [&mesh](std::ostream& f) { writePlyTo(mesh, f); });
  } catch (const std::exception& e) {
    if (error) *error = e.what();
    return false;
  }
  return true;
}

bool readPly(const std::string& path, Mesh& mesh) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return false;
  std::string line, format;
  size_t n_vertices = 0, n_faces = 0;
  std::getline(f, line);
  if (line != "ply") return false;
  while (std::getline(f, line) && line != "end_header") {
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") ls >> format;
    if (word == "element") {
      std::string what;
      size_t n = 0;
      ls >> what >> n;
      (what == "vertex" ? n_vertices : n_faces) = n;
    }
  }
  mesh = Mesh();
  mesh.vertices_W.resize(n_vertices);
  mesh.colours.resize(n_vertices);
  mesh.triangles.resize(n_faces);
  if (format == "ascii") {
    for (size_t i = 0; i < n_vertices; ++i) {
      int r, g, b;
      f >> mesh.vertices_W[i].x() >> mesh.vertices_W[i].y() >> mesh.vertices_W[i].z() >> r >> g >> b;
      mesh.colours[i] = {static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g), static_cast<std::uint8_t>(b)};
    }
    for (size_t i = 0; i < n_faces; ++i) {
      int n;
      f >> n >> mesh.triangles[i][0] >> mesh.triangles[i][1] >> mesh.triangles[i][2];
      if (n != 3) return false;
    }
    return static_cast<bool>(f);
  }
  if (format != "binary_little_endian") return false;
  const auto get32 = [&f]() {
    unsigned char b[4] = {0, 0, 0, 0};
    f.read(reinterpret_cast<char*>(b), 4);
    return static_cast<std::uint32_t>(b[0]) | (static_cast<std::uint32_t>(b[1]) << 8) |
           (static_cast<std::uint32_t>(b[2]) << 16) | (static_cast<std::uint32_t>(b[3]) << 24);
  };
  for (size_t i = 0; i < n_vertices; ++i) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t bits = get32();
      std::memcpy(&mesh.vertices_W[i][k], &bits, 4);
    }
    char c[3];
    f.read(c, 3);
    for (int k = 0; k < 3; ++k) mesh.colours[i][k] = static_cast<std::uint8_t>(c[k]);
  }
  for (size_t i = 0; i < n_faces; ++i) {
    char n = 0;
    f.read(&n, 1);
    if (n != 3) return false;
    for (int k = 0; k < 3; ++k) mesh.triangles[i][k] = get32();
  }
  return static_cast<bool>(f);
}

}  // namespace semexp

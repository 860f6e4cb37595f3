// Background occupancy map: MapBlocks encoding, own binary format, OctoMap export.
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "semantic_exploration/core/atomic_file.hpp"
#include "semantic_exploration/core/marching_cubes.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"

namespace semexp {

using occupancy::kNoDist;
using occupancy::kScale;
using occupancy::isFreeValue;
using occupancy::kUnknown;
using occupancy::Summary;

namespace {
constexpr char kMagic[8] = {'S', 'E', 'M', 'E', 'X', 'P', 'O', 'M'};
constexpr std::uint32_t kVersion = 2;  // 2: free_margin_quadratic_per_m (1 is read as 0)

inline std::int8_t encodeL(std::int16_t l) { return map_blocks::encodeMilli(l); }
inline std::int16_t decodeL(std::int8_t q) { return map_blocks::decodeMilli(q); }

template <class T>
void put(std::ostream& f, const T& v) {
  f.write(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <class T>
void putVec(std::ostream& f, const T* p, std::size_t n) {
  f.write(reinterpret_cast<const char*>(p), static_cast<std::streamsize>(n * sizeof(T)));
}
template <class T>
T get(std::ifstream& f) {
  T v{};
  f.read(reinterpret_cast<char*>(&v), sizeof(T));
  if (!f) throw std::runtime_error("truncated map file");
  return v;
}
template <class T>
void getVec(std::ifstream& f, T* p, std::size_t n) {
  f.read(reinterpret_cast<char*>(p), static_cast<std::streamsize>(n * sizeof(T)));
  if (!f) throw std::runtime_error("truncated map file");
}
}  // namespace

void OccupancyMap::encodeCell(int cell, std::int8_t* out) const {
  const int b = store_.cell_block[cell];
  if (b < 0) {
    std::fill_n(out, store_.bs3, encodeL(store_.cell_value[cell]));
    return;
  }
  const std::int16_t* L = store_.logOdds(b);
  for (int i = 0; i < store_.bs3; ++i) out[i] = encodeL(L[i]);
}

MapBlocksData OccupancyMap::takeUpdate() {
  MapBlocksData m;
  m.sequence = ++sequence_;
  m.full = false;
  m.resolution_m = store_.res;
  m.block_size = store_.bs;
  m.origin_m = store_.origin;
  std::sort(dirty_cells_.begin(), dirty_cells_.end());
  m.coords.reserve(3 * dirty_cells_.size());
  m.payload.resize(dirty_cells_.size() * static_cast<std::size_t>(store_.bs3));
  std::size_t j = 0;
  for (int cell : dirty_cells_) {
    dirty_[cell] = 0;
    const Eigen::Vector3i c = store_.cellCoords(cell);
    m.coords.insert(m.coords.end(), {c.x(), c.y(), c.z()});
    encodeCell(cell, m.payload.data() + j * store_.bs3);
    ++j;
  }
  dirty_cells_.clear();
  return m;
}

MapBlocksData OccupancyMap::snapshot(bool uniform_as_values) const {
  MapBlocksData m;
  m.sequence = sequence_;
  m.full = true;
  m.resolution_m = store_.res;
  m.block_size = store_.bs;
  m.origin_m = store_.origin;
  std::size_t n = 0;
  for (std::size_t c = 0; c < store_.cell_block.size(); ++c) n += store_.levels[0].s[c].known_any;
  if (!uniform_as_values) {
    m.coords.reserve(3 * n);
    m.payload.reserve(n * static_cast<std::size_t>(store_.bs3));
  }
  std::vector<std::int8_t> block(static_cast<std::size_t>(store_.bs3));
  for (int cell = 0; cell < static_cast<int>(store_.cell_block.size()); ++cell) {
    if (!store_.levels[0].s[cell].known_any) continue;
    const Eigen::Vector3i cc = store_.cellCoords(cell);
    const std::int32_t c[3] = {cc.x(), cc.y(), cc.z()};
    encodeCell(cell, block.data());
    // A voxel block may hold one value too (its voxels converged to the clamp): checked on the encoded values.
    if (uniform_as_values && std::all_of(block.begin(), block.end(), [&](std::int8_t q) { return q == block[0]; })) {
      m.uniform_coords.insert(m.uniform_coords.end(), c, c + 3);
      m.uniform_values.push_back(block[0]);
    } else {
      m.coords.insert(m.coords.end(), c, c + 3);
      m.payload.insert(m.payload.end(), block.begin(), block.end());
    }
  }
  return m;
}

void OccupancyMap::clearAll() {
  store_.reset();
  frontiers_.reset(store_.cellCount(), store_.fwords);
  surface_counter_.reset();
  dirty_.assign(store_.cellCount(), 0);
  dirty_cells_.clear();
}

bool OccupancyMap::applyBlocks(const MapBlocksData& m) {
  if (m.encoding != MapBlocksData::kEncodingLogOddsI8 || m.block_size != store_.bs ||
      std::abs(m.resolution_m - store_.res) > 1e-6 * store_.res || (m.origin_m - store_.origin).cwiseAbs().maxCoeff() > 1e-3 * store_.res ||
      m.coords.size() % 3 != 0 || m.payload.size() != m.blockCount() * static_cast<std::size_t>(store_.bs3) ||
      m.uniform_coords.size() != 3 * m.uniform_values.size())
    return false;
  if (m.full) clearAll();
  std::vector<int> changed;
  const std::size_t n_detailed = m.blockCount();
  changed.reserve(n_detailed + m.uniform_values.size());
  for (std::size_t j = 0; j < n_detailed + m.uniform_values.size(); ++j) {
    // Detailed blocks first, then the uniform ones (one value each).
    const bool listed_uniform = j >= n_detailed;
    const std::int32_t* c = listed_uniform ? &m.uniform_coords[3 * (j - n_detailed)] : &m.coords[3 * j];
    const int x = c[0], y = c[1], z = c[2];
    if (x < 0 || y < 0 || z < 0 || x >= store_.nb.x() || y >= store_.nb.y() || z >= store_.nb.z()) continue;
    const int cell = store_.cellIndex(x, y, z);
    const std::int8_t* q = listed_uniform ? &m.uniform_values[j - n_detailed] : m.payload.data() + j * store_.bs3;
    const bool uniform = listed_uniform || std::all_of(q, q + store_.bs3, [&](std::int8_t a) { return a == q[0]; });
    store_.cell_dist[cell] = kNoDist;
    if (uniform) {
      releaseBlock(cell);
      store_.cell_value[cell] = decodeL(q[0]);
    } else {
      store_.cell_value[cell] = kUnknown;
      const int b = store_.cell_block[cell] >= 0 ? store_.cell_block[cell] : store_.allocateBlock(cell);
      std::int16_t* L = store_.logOdds(b);
      for (int i = 0; i < store_.bs3; ++i) L[i] = decodeL(q[i]);
      if (store_.block_surf[b] >= 0) {  // colour and distance are not replicated
        store_.releaseSurface(b);
      }
    }
    changed.push_back(cell);
  }
  // A uniform free cell that now borders unknown space is split into a block by refreshSummaries, as in
  // integration: the written cells and their uniform free face neighbours (unknown written next to one).
  std::vector<int> refresh = changed;
  for (const int cell : changed)
    store_.forEachFaceNeighbour(cell, [&](int nc) {
      if (store_.cell_block[nc] < 0 && isFreeValue(store_.cell_value[nc]))
        refresh.push_back(nc);
    });
  std::sort(refresh.begin(), refresh.end());
  refresh.erase(std::unique(refresh.begin(), refresh.end()), refresh.end());
  refreshSummaries(refresh, false);
  // Frontiers: an overwritten cell may gain or lose frontier voxels, and so may its face neighbours
  // (their unknown neighbour may now be known, or known voxels unknown again); the next
  // updateFrontiers() re-checks them all.
  for (const int cell : changed) {
    frontiers_.markCandidate(cell);
    store_.forEachFaceNeighbour(cell, [&](int nc) { frontiers_.markCandidate(nc); });
  }
  return true;
}

// ---------------------------------------------------------- own format

void OccupancyMap::save(const std::string& path) const {
  writeFileAtomically(path, [this](std::ostream& f) { saveTo(f); });
}

void OccupancyMap::saveTo(std::ostream& f) const {
  f.write(kMagic, sizeof(kMagic));
  put(f, kVersion);
  put(f, cfg_.resolution_m);
  put(f, static_cast<std::int32_t>(cfg_.block_size));
  put(f, cfg_.log_odds_free);
  put(f, cfg_.log_odds_occupied);
  put(f, cfg_.log_odds_min);
  put(f, cfg_.log_odds_max);
  put(f, cfg_.surface_band_m);
  put(f, cfg_.surface_front_m);
  put(f, cfg_.surface_front_quadratic_per_m);
  put(f, cfg_.free_margin_quadratic_per_m);
  put(f, static_cast<std::uint8_t>(cfg_.integrate_colour));
  put(f, static_cast<std::uint8_t>(cfg_.integrate_min_distance));
  put(f, cfg_.publish_period_s);
  for (int i = 0; i < 3; ++i) put(f, bounds_.min_m[i]);
  for (int i = 0; i < 3; ++i) put(f, bounds_.max_m[i]);
  put(f, sequence_);
  putVec(f, store_.cell_value.data(), store_.cell_value.size());
  putVec(f, store_.cell_dist.data(), store_.cell_dist.size());
  put(f, static_cast<std::uint64_t>(store_.blockCount()));
  for (int cell = 0; cell < static_cast<int>(store_.cell_block.size()); ++cell) {
    const int b = store_.cell_block[cell];
    if (b < 0) continue;
    const std::size_t o = static_cast<std::size_t>(b) * store_.bs3;
    put(f, static_cast<std::int32_t>(cell));
    putVec(f, store_.block_l.data() + o, store_.bs3);
    const int sl = store_.block_surf[b];
    put(f, static_cast<std::uint8_t>(sl >= 0));
    if (sl >= 0) {
      const std::size_t so = static_cast<std::size_t>(sl) * store_.bs3;
      putVec(f, store_.surf_dist.data() + so, store_.bs3);
      if (cfg_.integrate_colour) putVec(f, store_.surf_rgbw.data() + 4 * so, 4 * store_.bs3);
    }
    putVec(f, frontiers_.blockBits(b), store_.fwords);
  }
  std::vector<int> fb, fc;  // live entries, in list order
  frontiers_.liveLists(fb, fc);
  put(f, static_cast<std::uint64_t>(fb.size()));
  putVec(f, fb.data(), fb.size());
  put(f, static_cast<std::uint64_t>(fc.size()));
  putVec(f, fc.data(), fc.size());
}

OccupancyMap OccupancyMap::load(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("cannot read " + path);
  char magic[8];
  getVec(f, magic, 8);
  if (std::memcmp(magic, kMagic, 8) != 0) throw std::runtime_error(path + " is not a semantic_exploration map");
  const auto version = get<std::uint32_t>(f);
  if (version != 1 && version != kVersion) throw std::runtime_error(path + ": unsupported map version");
  BackgroundMapConfig cfg;
  cfg.resolution_m = get<double>(f);
  cfg.block_size = get<std::int32_t>(f);
  cfg.log_odds_free = get<double>(f);
  cfg.log_odds_occupied = get<double>(f);
  cfg.log_odds_min = get<double>(f);
  cfg.log_odds_max = get<double>(f);
  cfg.surface_band_m = get<double>(f);
  cfg.surface_front_m = get<double>(f);
  cfg.surface_front_quadratic_per_m = get<double>(f);
  // Version 1 maps were made before the free margin existed: without one, whatever the default is now.
  cfg.free_margin_quadratic_per_m = version >= 2 ? get<double>(f) : 0.0;
  cfg.integrate_colour = get<std::uint8_t>(f) != 0;
  cfg.integrate_min_distance = get<std::uint8_t>(f) != 0;
  cfg.publish_period_s = get<double>(f);
  Bounds bounds;
  for (int i = 0; i < 3; ++i) bounds.min_m[i] = get<double>(f);
  for (int i = 0; i < 3; ++i) bounds.max_m[i] = get<double>(f);
  OccupancyMap m(cfg, bounds);
  m.sequence_ = get<std::uint64_t>(f);
  getVec(f, m.store_.cell_value.data(), m.store_.cell_value.size());
  getVec(f, m.store_.cell_dist.data(), m.store_.cell_dist.size());
  const std::uint64_t nblocks = get<std::uint64_t>(f);
  std::vector<int> cells;
  for (std::uint64_t j = 0; j < nblocks; ++j) {
    const std::int32_t cell = get<std::int32_t>(f);
    if (cell < 0 || cell >= static_cast<std::int32_t>(m.store_.cell_block.size()) || m.store_.cell_block[cell] >= 0)
      throw std::runtime_error(path + ": corrupt block table");
    const int b = m.store_.allocateBlock(cell);
    const std::size_t o = static_cast<std::size_t>(b) * m.store_.bs3;
    getVec(f, m.store_.block_l.data() + o, m.store_.bs3);
    if (get<std::uint8_t>(f)) {
      const std::size_t so = static_cast<std::size_t>(m.store_.ensureSurface(b)) * m.store_.bs3;
      getVec(f, m.store_.surf_dist.data() + so, m.store_.bs3);
      if (cfg.integrate_colour) getVec(f, m.store_.surf_rgbw.data() + 4 * so, 4 * m.store_.bs3);
    }
    getVec(f, m.frontiers_.mutableBlockBits(m.store_, b), m.store_.fwords);
  }
  for (int c = 0; c < static_cast<int>(m.store_.cell_block.size()); ++c) cells.push_back(c);
  m.refreshSummaries(cells, false, nullptr, SurfaceMarks::kAll, FreeCells::kAsTheyAre);  // blocks as saved
  std::vector<int> fb(get<std::uint64_t>(f));
  getVec(f, fb.data(), fb.size());
  std::vector<int> fc(get<std::uint64_t>(f));
  getVec(f, fc.data(), fc.size());
  if (!m.frontiers_.restore(m.store_, fb, fc)) throw std::runtime_error(path + ": corrupt frontier table");
  return m;
}

void OccupancyMap::exportOctomap(const std::string& path) const {
  octomap::OcTree tree(store_.res);
  tree.setClampingThresMin(1.0 / (1.0 + std::exp(-cfg_.log_odds_min)));
  tree.setClampingThresMax(1.0 / (1.0 + std::exp(-cfg_.log_odds_max)));
  for (int cell = 0; cell < static_cast<int>(store_.cell_block.size()); ++cell) {
    if (!store_.levels[0].s[cell].known_any) continue;
    const int b = store_.cell_block[cell];
    const Eigen::Vector3i base = store_.cellCoords(cell) * store_.bs;
    for (int i = 0; i < store_.bs3; ++i) {
      const std::int16_t l = b < 0 ? store_.cell_value[cell] : store_.block_l[static_cast<std::size_t>(b) * store_.bs3 + i];
      if (l == kUnknown) continue;
      const Eigen::Vector3d c = store_.voxelCentre(base + store_.voxelInCell(i));
      tree.setNodeValue(octomap::point3d(static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z())),
                        static_cast<float>(l / kScale), true);
    }
  }
  tree.updateInnerOccupancy();
  writeFileAtomically(path, [&tree](std::ostream& f) {
    if (!tree.writeBinary(f)) throw std::runtime_error("OctoMap could not write the tree");
  });
}

void OccupancyMap::exportOccupiedPly(const std::string& path) const {
  Mesh cloud;
  forEachOccupied([&cloud](const Eigen::Vector3d& c, double, const std::uint8_t rgb[3]) {
    cloud.vertices_W.push_back(c.cast<float>());
    cloud.colours.push_back({rgb[0], rgb[1], rgb[2]});
  });
  std::string error;
  if (!writePly(cloud, path, &error)) throw std::runtime_error(error);
}

}  // namespace semexp

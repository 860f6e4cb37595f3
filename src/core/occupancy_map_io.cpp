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

namespace {
constexpr std::uint16_t kNoDist = 0xFFFF;
constexpr char kMagic[8] = {'S', 'E', 'M', 'E', 'X', 'P', 'O', 'M'};
constexpr std::uint32_t kVersion = 1;

// log-odds (thousandths) -> MapBlocks int8 (tenths); keeps the sign so that a
// replica classifies every voxel as the source does.
inline std::int8_t encodeL(std::int16_t l) {
  if (l == OccupancyMap::kUnknown) return MapBlocksData::kUnknownI8;
  long q = std::lround(l / 100.0);
  q = std::clamp(q, -127L, 127L);
  if (l < 0 && q >= 0) q = -1;
  return static_cast<std::int8_t>(q);
}
inline std::int16_t decodeL(std::int8_t q) {
  return q == MapBlocksData::kUnknownI8 ? OccupancyMap::kUnknown : static_cast<std::int16_t>(q * 100);
}

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
  const int b = cell_block_[cell];
  if (b < 0) {
    std::fill_n(out, bs3_, encodeL(cell_value_[cell]));
    return;
  }
  const std::int16_t* L = block_l_.data() + static_cast<std::size_t>(b) * bs3_;
  for (int i = 0; i < bs3_; ++i) out[i] = encodeL(L[i]);
}

MapBlocksData OccupancyMap::takeUpdate() {
  MapBlocksData m;
  m.sequence = ++sequence_;
  m.full = false;
  m.resolution_m = res_;
  m.block_size = bs_;
  m.origin_m = origin_;
  std::sort(dirty_cells_.begin(), dirty_cells_.end());
  m.coords.reserve(3 * dirty_cells_.size());
  m.payload.resize(dirty_cells_.size() * static_cast<std::size_t>(bs3_));
  std::size_t j = 0;
  for (int cell : dirty_cells_) {
    cell_flags_[cell] &= static_cast<std::uint8_t>(~kDirty);
    m.coords.push_back(cell % nb_.x());
    m.coords.push_back((cell / nb_.x()) % nb_.y());
    m.coords.push_back(cell / (nb_.x() * nb_.y()));
    encodeCell(cell, m.payload.data() + j * bs3_);
    ++j;
  }
  dirty_cells_.clear();
  return m;
}

MapBlocksData OccupancyMap::snapshot(bool uniform_as_values) const {
  MapBlocksData m;
  m.sequence = sequence_;
  m.full = true;
  m.resolution_m = res_;
  m.block_size = bs_;
  m.origin_m = origin_;
  std::size_t n = 0;
  for (std::size_t c = 0; c < cell_block_.size(); ++c) n += levels_[0].s[c].known_any;
  if (!uniform_as_values) {
    m.coords.reserve(3 * n);
    m.payload.reserve(n * static_cast<std::size_t>(bs3_));
  }
  std::vector<std::int8_t> block(static_cast<std::size_t>(bs3_));
  for (int cell = 0; cell < static_cast<int>(cell_block_.size()); ++cell) {
    if (!levels_[0].s[cell].known_any) continue;
    const std::int32_t c[3] = {cell % nb_.x(), (cell / nb_.x()) % nb_.y(), cell / (nb_.x() * nb_.y())};
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
  block_cell_.clear();
  block_l_.clear();
  block_surf_.clear();
  block_nfree_.clear();
  block_nocc_.clear();
  block_dist_.clear();
  block_rgbw_.clear();
  surf_free_.clear();
  surf_slots_ = 0;
  block_front_.clear();
  block_hit_.clear();
  free_slots_.clear();
  block_count_ = 0;
  dirty_cells_.clear();
  frontier_cand_.clear();
  frontier_blocks_.clear();
  frontier_cells_.clear();
  frontier_voxels_ = 0;
  frontier_block_count_ = frontier_cell_count_ = 0;
  initGeometry();
}

bool OccupancyMap::applyBlocks(const MapBlocksData& m) {
  if (m.encoding != MapBlocksData::kEncodingLogOddsI8 || m.block_size != bs_ ||
      std::abs(m.resolution_m - res_) > 1e-6 * res_ || (m.origin_m - origin_).cwiseAbs().maxCoeff() > 1e-3 * res_ ||
      m.coords.size() % 3 != 0 || m.payload.size() != m.blockCount() * static_cast<std::size_t>(bs3_) ||
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
    if (x < 0 || y < 0 || z < 0 || x >= nb_.x() || y >= nb_.y() || z >= nb_.z()) continue;
    const int cell = cellIndex(x, y, z);
    const std::int8_t* q = listed_uniform ? &m.uniform_values[j - n_detailed] : m.payload.data() + j * bs3_;
    const bool uniform = listed_uniform || std::all_of(q, q + bs3_, [&](std::int8_t a) { return a == q[0]; });
    cell_dist_[cell] = kNoDist;
    if (uniform) {
      releaseBlock(cell);
      cell_value_[cell] = decodeL(q[0]);
    } else {
      cell_value_[cell] = kUnknown;
      const int b = cell_block_[cell] >= 0 ? cell_block_[cell] : allocateBlock(cell);
      std::int16_t* L = block_l_.data() + static_cast<std::size_t>(b) * bs3_;
      for (int i = 0; i < bs3_; ++i) L[i] = decodeL(q[i]);
      if (block_surf_[b] >= 0) {  // colour and distance are not replicated
        surf_free_.push_back(block_surf_[b]);
        block_surf_[b] = -1;
      }
    }
    changed.push_back(cell);
  }
  refreshSummaries(changed, false);
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
  put(f, static_cast<std::uint8_t>(cfg_.integrate_colour));
  put(f, static_cast<std::uint8_t>(cfg_.integrate_min_distance));
  put(f, cfg_.publish_period_s);
  for (int i = 0; i < 3; ++i) put(f, bounds_.min_m[i]);
  for (int i = 0; i < 3; ++i) put(f, bounds_.max_m[i]);
  put(f, sequence_);
  putVec(f, cell_value_.data(), cell_value_.size());
  putVec(f, cell_dist_.data(), cell_dist_.size());
  put(f, static_cast<std::uint64_t>(block_count_));
  for (int cell = 0; cell < static_cast<int>(cell_block_.size()); ++cell) {
    const int b = cell_block_[cell];
    if (b < 0) continue;
    const std::size_t o = static_cast<std::size_t>(b) * bs3_;
    put(f, static_cast<std::int32_t>(cell));
    putVec(f, block_l_.data() + o, bs3_);
    const int sl = block_surf_[b];
    put(f, static_cast<std::uint8_t>(sl >= 0));
    if (sl >= 0) {
      const std::size_t so = static_cast<std::size_t>(sl) * bs3_;
      putVec(f, block_dist_.data() + so, bs3_);
      if (cfg_.integrate_colour) putVec(f, block_rgbw_.data() + 4 * so, 4 * bs3_);
    }
    putVec(f, block_front_.data() + static_cast<std::size_t>(b) * fwords_, fwords_);
  }
  std::vector<int> fb, fc;  // live entries, in list order
  for (int c : frontier_blocks_)
    if (cell_flags_[c] & kBlockFrontier) fb.push_back(c);
  for (int c : frontier_cells_)
    if (cell_flags_[c] & kCoarseFrontier) fc.push_back(c);
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
  if (get<std::uint32_t>(f) != kVersion) throw std::runtime_error(path + ": unsupported map version");
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
  cfg.integrate_colour = get<std::uint8_t>(f) != 0;
  cfg.integrate_min_distance = get<std::uint8_t>(f) != 0;
  cfg.publish_period_s = get<double>(f);
  Bounds bounds;
  for (int i = 0; i < 3; ++i) bounds.min_m[i] = get<double>(f);
  for (int i = 0; i < 3; ++i) bounds.max_m[i] = get<double>(f);
  OccupancyMap m(cfg, bounds);
  m.sequence_ = get<std::uint64_t>(f);
  getVec(f, m.cell_value_.data(), m.cell_value_.size());
  getVec(f, m.cell_dist_.data(), m.cell_dist_.size());
  const std::uint64_t nblocks = get<std::uint64_t>(f);
  std::vector<int> cells;
  for (std::uint64_t j = 0; j < nblocks; ++j) {
    const std::int32_t cell = get<std::int32_t>(f);
    if (cell < 0 || cell >= static_cast<std::int32_t>(m.cell_block_.size()) || m.cell_block_[cell] >= 0)
      throw std::runtime_error(path + ": corrupt block table");
    const int b = m.allocateBlock(cell);
    const std::size_t o = static_cast<std::size_t>(b) * m.bs3_;
    getVec(f, m.block_l_.data() + o, m.bs3_);
    if (get<std::uint8_t>(f)) {
      const std::size_t so = static_cast<std::size_t>(m.ensureSurface(b)) * m.bs3_;
      getVec(f, m.block_dist_.data() + so, m.bs3_);
      if (cfg.integrate_colour) getVec(f, m.block_rgbw_.data() + 4 * so, 4 * m.bs3_);
    }
    getVec(f, m.block_front_.data() + static_cast<std::size_t>(b) * m.fwords_, m.fwords_);
  }
  for (int c = 0; c < static_cast<int>(m.cell_block_.size()); ++c) cells.push_back(c);
  m.refreshSummaries(cells, false);
  m.frontier_blocks_.resize(get<std::uint64_t>(f));
  getVec(f, m.frontier_blocks_.data(), m.frontier_blocks_.size());
  m.frontier_cells_.resize(get<std::uint64_t>(f));
  getVec(f, m.frontier_cells_.data(), m.frontier_cells_.size());
  for (int c : m.frontier_cells_) {
    if (m.cell_block_.at(c) >= 0) throw std::runtime_error(path + ": corrupt frontier table");
    m.cell_flags_[c] |= kCoarseFrontier | kListedCell;
  }
  m.frontier_cell_count_ = m.frontier_cells_.size();
  for (int c : m.frontier_blocks_) {
    if (m.cell_block_.at(c) < 0) throw std::runtime_error(path + ": corrupt frontier table");
    m.cell_flags_[c] |= kBlockFrontier | kListedBlock;
    m.frontier_voxels_ += static_cast<std::size_t>(m.blockFrontierBits(c));
  }
  m.frontier_block_count_ = m.frontier_blocks_.size();
  return m;
}

void OccupancyMap::exportOctomap(const std::string& path) const {
  octomap::OcTree tree(res_);
  tree.setClampingThresMin(1.0 / (1.0 + std::exp(-cfg_.log_odds_min)));
  tree.setClampingThresMax(1.0 / (1.0 + std::exp(-cfg_.log_odds_max)));
  for (int cell = 0; cell < static_cast<int>(cell_block_.size()); ++cell) {
    if (!levels_[0].s[cell].known_any) continue;
    const int bz = cell / (nb_.x() * nb_.y()), by = (cell / nb_.x()) % nb_.y(), bx = cell % nb_.x();
    const int b = cell_block_[cell];
    int i = 0;
    for (int z = 0; z < bs_; ++z)
      for (int y = 0; y < bs_; ++y)
        for (int x = 0; x < bs_; ++x, ++i) {
          const std::int16_t l = b < 0 ? cell_value_[cell] : block_l_[static_cast<std::size_t>(b) * bs3_ + i];
          if (l == kUnknown) continue;
          const Eigen::Vector3d c =
              origin_ + (Eigen::Vector3d(bx * bs_ + x, by * bs_ + y, bz * bs_ + z) + Eigen::Vector3d::Constant(0.5)) * res_;
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

#include "semantic_exploration/core/tsdf_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "semantic_exploration/core/atomic_file.hpp"

namespace semexp {

namespace {

constexpr const char* kFormat = "semexp_tsdf";
constexpr int kVersion = 1;
constexpr std::size_t kVoxelBytes = 10;

// Little-endian packing, whatever the host's byte order.
void put16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v & 0xff);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
std::uint16_t get16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }
void put32(std::uint8_t* p, std::int32_t s) {
  const auto v = static_cast<std::uint32_t>(s);
  for (int k = 0; k < 4; ++k) p[k] = static_cast<std::uint8_t>((v >> (8 * k)) & 0xff);
}
std::int32_t get32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int k = 0; k < 4; ++k) v |= static_cast<std::uint32_t>(p[k]) << (8 * k);
  return static_cast<std::int32_t>(v);
}

// The order blocks are written in and must be read in: by z, then y, then x.
std::tuple<int, int, int> blockOrder(const Eigen::Vector3i& b) { return {b.z(), b.y(), b.x()}; }

bool fail(std::string* error, const std::string& why) {
  if (error) *error = why;
  return false;
}

}  // namespace

bool saveTsdf(const TsdfMap& map, const std::string& path, std::string* error) {
  const TsdfParams& p = map.params();
  std::ostringstream header;
  header.precision(17);
  header << kFormat << " " << kVersion << "\n"
         << "resolution_m " << p.resolution_m << "\ntruncation_m " << p.truncation_m << "\nbehind_surface_m "
         << p.behind_surface_m << "\nbehind_surface_quadratic_per_m " << p.behind_surface_quadratic_per_m
         << "\nfull_weight_depth_m " << p.full_weight_depth_m << "\nforeground_prior " << p.foreground_prior
         << "\nforeground_prior_weight " << p.foreground_prior_weight << "\nblock_size " << p.block_size
         << "\nmax_weight " << p.max_weight << "\nblocks " << map.blockCount() << "\n";
  const std::size_t n = static_cast<std::size_t>(p.block_size) * p.block_size * p.block_size;
  try {
    writeFileAtomically(path, [&](std::ostream& f) {
      f << header.str();
      // Blocks in index order, not the hash map's: one map always gives the same bytes.
      struct Entry {
        Eigen::Vector3i b;
        const std::vector<TsdfVoxel>* voxels;
        bool has_negative;
      };
      std::vector<Entry> blocks;
      map.forEachBlock([&](const Eigen::Vector3i& b, const std::vector<TsdfVoxel>& voxels, bool has_negative) {
        blocks.push_back({b, &voxels, has_negative});
      });
      std::sort(blocks.begin(), blocks.end(),
                [](const Entry& x, const Entry& y) { return blockOrder(x.b) < blockOrder(y.b); });
      std::vector<std::uint8_t> buf(13 + n * kVoxelBytes);
      for (const auto& [b, block, has_negative] : blocks) {
        const std::vector<TsdfVoxel>& voxels = *block;
        for (int k = 0; k < 3; ++k) put32(&buf[4 * k], b[k]);
        buf[12] = has_negative ? 1 : 0;
        std::uint8_t* q = &buf[13];
        for (const TsdfVoxel& v : voxels) {
          put16(q, static_cast<std::uint16_t>(v.sdf_q));
          put16(q + 2, v.weight_q);
          put16(q + 4, v.min_distance_mm);
          q[6] = v.foreground_q;
          std::memcpy(q + 7, v.rgb, 3);
          q += kVoxelBytes;
        }
        f.write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size()));
      }
    });
  } catch (const std::exception& e) {
    return fail(error, e.what());
  }
  return true;
}

std::unique_ptr<TsdfMap> loadTsdf(const std::string& path, std::string* error) {
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    fail(error, "cannot open " + path);
    return nullptr;
  }
  const auto bad = [&](const std::string& why) {
    fail(error, path + ": " + why);
    return nullptr;
  };
  std::string format;
  int version = 0;
  if (!(f >> format >> version) || format != kFormat) return bad("not a semexp_tsdf file");
  if (version != kVersion) return bad("format version " + std::to_string(version) + ", this build reads 1");
  TsdfParams p;
  std::size_t blocks = 0;
  const auto field = [&](const char* key, auto& value) {
    std::string k;
    return static_cast<bool>(f >> k >> value) && k == key;
  };
  if (!(field("resolution_m", p.resolution_m) && field("truncation_m", p.truncation_m) &&
        field("behind_surface_m", p.behind_surface_m) &&
        field("behind_surface_quadratic_per_m", p.behind_surface_quadratic_per_m) &&
        field("full_weight_depth_m", p.full_weight_depth_m) && field("foreground_prior", p.foreground_prior) &&
        field("foreground_prior_weight", p.foreground_prior_weight) && field("block_size", p.block_size) &&
        field("max_weight", p.max_weight) && field("blocks", blocks)))
    return bad("header unreadable");
  if (f.get() != '\n') return bad("header unreadable");
  // The header is checked before anything is allocated from it (block_size^3 voxels per block).
  const auto nonNegative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  // Voxels of at least 0.1 mm (the inverse resolution is a float); the prior's weight within the cap.
  if (!(nonNegative(p.resolution_m) && p.resolution_m >= 1e-4 && nonNegative(p.truncation_m) && p.truncation_m > 0 &&
        nonNegative(p.behind_surface_m) && nonNegative(p.behind_surface_quadratic_per_m) &&
        nonNegative(p.full_weight_depth_m) && nonNegative(p.foreground_prior) && p.foreground_prior <= 1 &&
        nonNegative(p.foreground_prior_weight) && p.block_size >= 2 && p.block_size <= 64 &&
        (p.block_size & (p.block_size - 1)) == 0 && std::isfinite(p.max_weight) && p.max_weight >= 1 &&
        p.max_weight <= TsdfVoxel::kMaxWeight && p.foreground_prior_weight <= p.max_weight))
    return bad("a parameter in the header is out of range");
  const auto max_weight_q = static_cast<std::uint16_t>(std::ceil(p.max_weight * 16.0));
  try {
    auto map = std::make_unique<TsdfMap>(p);
    const std::size_t n = static_cast<std::size_t>(p.block_size) * p.block_size * p.block_size;
    std::vector<TsdfMap::SavedBlock> saved;  // not reserved from the header: a corrupt count must not allocate
    std::vector<std::uint8_t> buf(13 + n * kVoxelBytes);
    for (std::size_t i = 0; i < blocks; ++i) {
      const auto at = [&] { return "block " + std::to_string(i) + " of " + std::to_string(blocks); };  // errors only
      if (!f.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(buf.size())))
        return bad("truncated at " + at());
      TsdfMap::SavedBlock b;
      b.index = Eigen::Vector3i(get32(&buf[0]), get32(&buf[4]), get32(&buf[8]));
      if ((b.index.cast<std::int64_t>().cwiseAbs() * p.block_size).maxCoeff() >= TsdfParams::kMaxVoxelIndex)
        return bad(at() + " lies outside the map's index range");
      // Index order (the writer's) also rules out a block given twice.
      if (i > 0 && blockOrder(b.index) <= blockOrder(saved.back().index))
        return bad(at() + " is out of index order or repeated");
      // The flag is sticky (a voxel once given a negative SDF may have turned positive since): kept as saved,
      // and set wherever a voxel is negative now, so that ray casts never step over a surface.
      b.has_negative = buf[12] != 0;
      b.voxels.resize(n);
      const std::uint8_t* q = &buf[13];
      for (TsdfVoxel& v : b.voxels) {
        v.sdf_q = static_cast<std::int16_t>(get16(q));
        v.weight_q = get16(q + 2);
        v.min_distance_mm = get16(q + 4);
        v.foreground_q = q[6];
        std::memcpy(v.rgb, q + 7, 3);
        q += kVoxelBytes;
        if (v.sdf_q < -32767 || v.foreground_q > 254 || v.weight_q > max_weight_q)
          return bad(at() + " holds a voxel out of range (sdf, foreground or weight)");
        b.has_negative = b.has_negative || v.sdf_q < 0;
      }
      saved.push_back(std::move(b));
    }
    if (f.peek() != std::char_traits<char>::eof()) return bad("bytes after the last block");
    map->loadBlocks(std::move(saved));
    return map;
  } catch (const std::exception& e) {  // allocation: the file cannot be held
    return bad(e.what());
  }
}

}  // namespace semexp

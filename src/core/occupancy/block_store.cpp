// Background occupancy map storage: cells, block and surface pools, summaries.
#include "semantic_exploration/core/occupancy/block_store.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace semexp {
namespace occupancy {

namespace {
constexpr Summary kUnknownSummary{INT16_MAX, INT16_MIN, 0, 1};
}  // namespace

BlockStore::BlockStore(double resolution_m, int block_size, const Bounds& bounds, bool with_colour)
    : res(resolution_m), bs(block_size), colour(with_colour) {
  // The integrator's per-slab buffers hold rows of at most 64 voxels (BackgroundMapConfig::validate says the
  // same for configured maps; this also covers stores built without it).
  if (bs < 2 || bs > 64 || (bs & (bs - 1)) != 0)
    throw std::invalid_argument("BlockStore: block_size must be a power of two in [2, 64], got " + std::to_string(bs));
  bshift = 0;
  while ((1 << bshift) < bs) ++bshift;
  bs3 = bs * bs * bs;
  fwords = (bs3 + 63) / 64;
  for (int i = 0; i < 3; ++i) {
    origin[i] = std::floor(bounds.min_m[i] / res + 1e-6) * res;
    const double nvox = std::ceil((bounds.max_m[i] - origin[i]) / res - 1e-6);
    nb[i] = std::max(1, static_cast<int>(std::ceil(nvox / bs)));
  }
  reset();
}

void BlockStore::reset() {
  const std::size_t ncell = static_cast<std::size_t>(nb.prod());
  cell_block.assign(ncell, -1);
  cell_value.assign(ncell, kUnknown);
  cell_dist.assign(ncell, kNoDist);
  block_cell.clear();
  block_l.clear();
  block_surf.clear();
  block_nfree.clear();
  block_nocc.clear();
  surf_dist.clear();
  surf_rgbw.clear();
  free_slots_.clear();
  surf_free_.clear();
  surf_slots_ = 0;
  block_count_ = 0;
  levels.clear();
  SummaryLevel l0;
  l0.dims = nb;
  l0.s.assign(ncell, kUnknownSummary);
  levels.push_back(std::move(l0));
  while ((levels.back().dims.array() > 1).any()) {
    SummaryLevel l;
    l.dims = (levels.back().dims.array() + 1) / 2;
    l.s.assign(static_cast<std::size_t>(l.dims.prod()), kUnknownSummary);
    levels.push_back(std::move(l));
  }
}

int BlockStore::allocateBlock(int cell) {
  int b;
  if (!free_slots_.empty()) {
    b = free_slots_.back();
    free_slots_.pop_back();
  } else {
    b = static_cast<int>(block_cell.size());
    if (block_cell.size() == block_cell.capacity()) {
      const std::size_t cap = block_cell.capacity() + block_cell.capacity() / 4 + 64;
      block_cell.reserve(cap);
      block_surf.reserve(cap);
      block_nfree.reserve(cap);
      block_nocc.reserve(cap);
      block_l.reserve(cap * bs3);
    }
    block_cell.push_back(-1);
    block_surf.push_back(-1);
    block_nfree.push_back(0);
    block_nocc.push_back(0);
    block_l.resize(block_l.size() + bs3);
  }
  block_cell[b] = cell;
  std::fill_n(logOdds(b), bs3, cell_value[cell]);
  block_surf[b] = -1;
  cell_block[cell] = b;
  ++block_count_;
  return b;
}

int BlockStore::ensureSurface(int b) {
  if (block_surf[b] >= 0) return block_surf[b];
  int sl;
  if (!surf_free_.empty()) {
    sl = surf_free_.back();
    surf_free_.pop_back();
  } else {
    sl = static_cast<int>(surf_slots_++);
    if (surf_dist.size() == surf_dist.capacity()) {
      const std::size_t cap = surf_dist.capacity() / bs3 + surf_dist.capacity() / bs3 / 4 + 64;
      surf_dist.reserve(cap * bs3);
      if (colour) surf_rgbw.reserve(cap * 4 * bs3);
    }
    surf_dist.resize(surf_dist.size() + bs3);
    if (colour) surf_rgbw.resize(surf_rgbw.size() + 4 * bs3);
  }
  std::fill_n(dist(sl), bs3, kNoDist);
  if (colour) std::fill_n(rgbw(sl), 4 * bs3, 0);
  block_surf[b] = sl;
  return sl;
}

void BlockStore::releaseSurface(int b) {
  if (block_surf[b] < 0) return;
  surf_free_.push_back(block_surf[b]);
  block_surf[b] = -1;
}

void BlockStore::releaseBlock(int cell) {
  const int b = cell_block[cell];
  if (b < 0) return;
  releaseSurface(b);
  block_cell[b] = -1;
  free_slots_.push_back(b);
  cell_block[cell] = -1;
  --block_count_;
}

Summary BlockStore::cellSummary(int cell) {
  const int b = cell_block[cell];
  if (b < 0) {
    const std::int16_t v = cell_value[cell];
    if (v == kUnknown) return kUnknownSummary;
    return Summary{v, v, 1, 0};
  }
  const std::int16_t* L = logOdds(b);
  // Branch-free, so that it vectorises. kUnknown (INT16_MIN) is below every
  // known value: it takes part in the max as it is, and in the min as v - 1
  // wrapped around to INT16_MAX (known values are above INT16_MIN, so v - 1
  // does not wrap for them). It counts as negative: the free count subtracts it.
  std::int16_t mn1 = INT16_MAX, mx = INT16_MIN;
  int nneg = 0, nunk = 0;
  for (int i = 0; i < bs3; ++i) {
    const std::int16_t v = L[i];
    mn1 = std::min(mn1, static_cast<std::int16_t>(static_cast<std::uint16_t>(v) - 1u));
    mx = std::max(mx, v);
    nneg += v < 0;
    nunk += v == kUnknown;
  }
  const int nfree = nneg - nunk, nocc = bs3 - nneg;
  const bool unk = nunk > 0;
  const int mn = nunk == bs3 ? INT16_MAX : mn1 + 1;
  block_nfree[b] = static_cast<std::uint32_t>(nfree);
  block_nocc[b] = static_cast<std::uint32_t>(nocc);
  const bool known = mn <= mx;
  return Summary{static_cast<std::int16_t>(mn), static_cast<std::int16_t>(mx), static_cast<std::uint8_t>(known),
                 static_cast<std::uint8_t>(unk)};
}

void BlockStore::propagateSummaries(std::vector<int> cur) {
  for (std::size_t k = 1; k < levels.size(); ++k) {
    const Eigen::Vector3i& pd = levels[k - 1].dims;
    const Eigen::Vector3i& d = levels[k].dims;
    for (int& c : cur) {
      const int x = c % pd.x(), y = (c / pd.x()) % pd.y(), z = c / (pd.x() * pd.y());
      c = (x >> 1) + d.x() * ((y >> 1) + d.y() * (z >> 1));
    }
    std::sort(cur.begin(), cur.end());
    cur.erase(std::unique(cur.begin(), cur.end()), cur.end());
    for (int c : cur) {
      const int x = c % d.x(), y = (c / d.x()) % d.y(), z = c / (d.x() * d.y());
      Summary s{INT16_MAX, INT16_MIN, 0, 0};
      for (int dz = 0; dz < 2; ++dz)
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int cx = 2 * x + dx, cy = 2 * y + dy, cz = 2 * z + dz;
            if (cx >= pd.x() || cy >= pd.y() || cz >= pd.z()) continue;
            const Summary& ch = levels[k - 1].at(cx, cy, cz);
            s.min_l = std::min(s.min_l, ch.min_l);
            s.max_l = std::max(s.max_l, ch.max_l);
            s.known_any |= ch.known_any;
            s.unknown_any |= ch.unknown_any;
          }
      levels[k].s[c] = s;
    }
  }
}

std::size_t BlockStore::memoryBytes() const {
  std::size_t m = sizeof(*this);
  m += cell_block.capacity() * sizeof(std::int32_t) + cell_value.capacity() * sizeof(std::int16_t) +
       cell_dist.capacity() * sizeof(std::uint16_t);
  m += block_cell.capacity() * sizeof(std::int32_t) + block_l.capacity() * sizeof(std::int16_t) +
       surf_dist.capacity() * sizeof(std::uint16_t) + surf_rgbw.capacity() +
       block_surf.capacity() * sizeof(std::int32_t) + surf_free_.capacity() * sizeof(std::int32_t) +
       (block_nfree.capacity() + block_nocc.capacity()) * sizeof(std::uint32_t) +
       free_slots_.capacity() * sizeof(std::int32_t);
  for (const SummaryLevel& l : levels) m += l.s.capacity() * sizeof(Summary);
  return m;
}

}  // namespace occupancy
}  // namespace semexp

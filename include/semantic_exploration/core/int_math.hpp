#pragma once
/// @file int_math.hpp
/// Integer helpers shared by the voxel-grid code.

#include <cassert>
#include <cmath>
#include <cstdint>

namespace semexp {

/// a / b rounded towards minus infinity (C++'s / rounds towards zero), for
/// b > 0: the block or cell holding voxel index a when blocks are b voxels wide.
inline int floorDiv(int a, int b) {
  assert(b > 0);
  const int q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

/// One 64-bit hash key for a cell index: 21 bits per axis (x lowest), each
/// coordinate offset by 2^20, so cell indices in [-2^20, 2^20) get distinct
/// keys (about +-42 km at 4 cm cells); others wrap and may share a key.
inline std::uint64_t cellKey21(std::int64_t x, std::int64_t y, std::int64_t z) {
  const auto c = [](std::int64_t v) { return static_cast<std::uint64_t>(v + (1 << 20)) & 0x1FFFFF; };
  return c(x) | (c(y) << 21) | (c(z) << 42);
}

/// cellKey21 of the cell of edge cell_m that holds the point (x_m, y_m, z_m) (m): floor(x_m / cell_m) and so on.
inline std::uint64_t pointCellKey21(double x_m, double y_m, double z_m, double cell_m) {
  const auto cell = [cell_m](double v_m) { return static_cast<std::int64_t>(std::floor(v_m / cell_m)); };
  return cellKey21(cell(x_m), cell(y_m), cell(z_m));
}

}  // namespace semexp

#pragma once
/// @file int_math.hpp
/// Integer helpers shared by the voxel-grid code.

#include <cassert>

namespace semexp {

/// a / b rounded towards minus infinity (C++'s / rounds towards zero), for
/// b > 0: the block or cell holding voxel index a when blocks are b voxels wide.
inline int floorDiv(int a, int b) {
  assert(b > 0);
  const int q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

}  // namespace semexp

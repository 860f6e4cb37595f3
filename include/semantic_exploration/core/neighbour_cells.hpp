#pragma once
/// @file neighbour_cells.hpp
/// Items hashed in cubic cells (a map from cell index to the items in it): an
/// item within one cell's width of a point lies in the 27 cells around the
/// point's own, so a search within that width visits those cells only.

#include <Eigen/Core>

namespace semexp {

/// Calls visit(item) for each item of `grid` (a map from Eigen::Vector3i cell
/// index to a sequence of items) in the 27 cells around `cell`, z, y, x
/// outermost to innermost, until visit returns true. Returns whether it did.
template <class Grid, class Visit>
bool visitNeighbourCells(const Grid& grid, const Eigen::Vector3i& cell, Visit&& visit) {
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const auto it = grid.find(cell + Eigen::Vector3i(dx, dy, dz));
        if (it == grid.end()) continue;
        for (const auto& item : it->second)
          if (visit(item)) return true;
      }
  return false;
}

}  // namespace semexp

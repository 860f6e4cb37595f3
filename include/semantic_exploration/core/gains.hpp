#pragma once
/// @file gains.hpp
/// Per-voxel information measures shared by the gain raycasts (paper IV-D.3).

#include <algorithm>
#include <cmath>

namespace semexp {

/// Shannon entropy of a binary occupancy variable with probability `p`, bits.
/// 1 at p = 0.5, 0 at p = 0 or 1.
inline double binaryEntropy(double p) {
  if (p <= 0.0 || p >= 1.0) return 0.0;
  return -(p * std::log2(p) + (1.0 - p) * std::log2(1.0 - p));
}

/// Entropy of a voxel holding log-odds `l` (natural log), bits.
inline double logOddsEntropy(double l) { return binaryEntropy(1.0 / (1.0 + std::exp(-l))); }

/// Entropy a measurement can still remove from a voxel holding log-odds `l`,
/// bits, in a map that clamps log-odds to [l_min, l_max] (l_min < 0 < l_max):
/// the voxel's entropy minus what it keeps at the clamp on its side, scaled so
/// that an unknown voxel (l = 0) has 1 and a voxel at the clamp 0.
/// Plain Shannon entropy is not zero at the clamp (0.53 bit at OctoMap's
/// l_min = -2): well-observed free space would keep looking informative, and
/// a view of it would seem worth flying to forever.
inline double reducibleEntropy(double l, double l_min, double l_max) {
  const double floor = logOddsEntropy(l < 0.0 ? l_min : l_max);
  if (!(floor < 1.0)) return 1.0;
  return std::clamp((logOddsEntropy(l) - floor) / (1.0 - floor), 0.0, 1.0);
}

/// Distance gain of one node, paper Eq. (1).
/// @param d_node_m   minimum distance the node has been observed from, m
/// @param d_exp_m    distance the node would be observed from at the candidate, m
/// @param d_desired_m desired observation distance (d_bg or d_obj), m
/// @param d_max_m    maximum sensor range (normaliser), m
/// @return 0 if the node was already seen from d_desired or closer, or the
///         candidate would not see it closer than before; otherwise the
///         improvement (d_node - max(d_exp, d_desired)) / d_max.
inline double distanceGain(double d_node_m, double d_exp_m, double d_desired_m, double d_max_m) {
  if (d_node_m <= d_desired_m || d_node_m <= d_exp_m) return 0.0;
  return (d_node_m - std::max(d_exp_m, d_desired_m)) / d_max_m;
}

}  // namespace semexp

#pragma once
/// @file interfaces.hpp
/// The small interfaces through which the planning core sees the maps, so it
/// depends on no map implementation (the ROS node backs them with the map
/// replica and the gain services; tests with synthetic grids).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "semantic_exploration/core/planning/candidate_evaluation.hpp"

namespace semexp {

/// True iff the sphere of radius_m around p_W (world, m) is entirely known
/// free space. Unknown and occupied space, and anything outside the map
/// bounds, are not free. Must be safe to call from several threads at once.
using CollisionQuery = std::function<bool(const Eigen::Vector3d& p_W, double radius_m)>;

/// True iff no point from_W + t u_W, for t = 0, step_m, 2 step_m, ... while
/// t <= length_m (t summed step by step), lies in an occupied voxel (unknown
/// allowed): the same answer as a not-occupied CollisionQuery at radius 0,
/// point by point, from a map that can skip a block with nothing occupied.
/// u_W is a unit vector; length_m and step_m in m, step_m > 0. Must be safe
/// to call from several threads at once.
using LineQuery =
    std::function<bool(const Eigen::Vector3d& from_W, const Eigen::Vector3d& u_W, double length_m, double step_m)>;

/// Gain images at a batch of positions (one GainSet per position, images in
/// the SphericalGrid layout of the planner's raycast width x height). Empty
/// images mean "no such gain". Called from one thread.
using GainProvider = std::function<std::vector<GainSet>(const std::vector<Eigen::Vector3d>& positions_W)>;

/// Invalid-depth history masks (1 = valid) at a batch of positions; an empty
/// mask means all valid.
using HistoryProvider =
    std::function<std::vector<std::vector<std::uint8_t>>(const std::vector<Eigen::Vector3d>& positions_W)>;

/// What the planner needs to know of one object of the object map.
struct ObjectSummary {
  std::uint32_t id = 0;
  Eigen::Vector3d bbox_min_W = Eigen::Vector3d::Zero();  ///< m
  Eigen::Vector3d bbox_max_W = Eigen::Vector3d::Zero();  ///< m
  Eigen::Vector3d centroid_W = Eigen::Vector3d::Zero();  ///< m
  double observed_fraction = 0.0;  ///< fraction of its surface observed from <= d_obj, [0, 1]
};

}  // namespace semexp

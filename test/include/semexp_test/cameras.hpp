#pragma once
/// @file cameras.hpp
/// Test cameras and camera poses. Every pose is T_WC of the optical frame
/// (x right, y down, z forward) in a world with z up.

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "semantic_exploration/core/camera.hpp"

namespace semexp_test {

/// A width x height px camera with focal length f_px and the principal point
/// at the image centre; depth range as PinholeCamera's defaults.
inline semexp::PinholeCamera centredCamera(int width, int height, double f_px) {
  semexp::PinholeCamera cam;
  cam.width = width;
  cam.height = height;
  cam.fx = cam.fy = f_px;
  cam.cx = 0.5 * (width - 1);
  cam.cy = 0.5 * (height - 1);
  return cam;
}

/// Half the Table I image (160 x 120 px) with the same fields of view.
inline semexp::PinholeCamera halfSizeCamera() { return centredCamera(160, 120, 131.25); }

/// A 64 x 48 px camera with Table I's fields of view: keeps many-frame object tests fast.
inline semexp::PinholeCamera tinyCamera() { return centredCamera(64, 48, 52.5); }

/// Camera at pos_W looking along the unit vector fwd_W, its x axis level.
inline Eigen::Isometry3d lookAlong(const Eigen::Vector3d& pos_W, const Eigen::Vector3d& fwd_W) {
  const Eigen::Vector3d right = fwd_W.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = fwd_W.cross(right);
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  T_WC.linear().col(0) = right;
  T_WC.linear().col(1) = down;
  T_WC.linear().col(2) = fwd_W;
  T_WC.translation() = pos_W;
  return T_WC;
}

/// Camera at eye_W looking at target_W.
inline Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye_W, const Eigen::Vector3d& target_W) {
  return lookAlong(eye_W, (target_W - eye_W).normalized());
}

/// Camera at `pos` looking along yaw (about +z from +x), pitched down by `tilt`, rad.
inline Eigen::Isometry3d lookPose(const Eigen::Vector3d& pos, double yaw, double tilt) {
  return lookAlong(pos, {std::cos(yaw) * std::cos(tilt), std::sin(yaw) * std::cos(tilt), -std::sin(tilt)});
}

/// A level camera at p_W looking along yaw_rad (about world +z from +x), its
/// axes written out exactly (lookPose(p, yaw, 0) rounds them).
inline Eigen::Isometry3d levelCameraPose(const Eigen::Vector3d& p_W, double yaw_rad) {
  Eigen::Matrix3d R_WC;
  R_WC.col(0) = Eigen::Vector3d(std::sin(yaw_rad), -std::cos(yaw_rad), 0.0);  // right
  R_WC.col(1) = -Eigen::Vector3d::UnitZ();                                    // down
  R_WC.col(2) = Eigen::Vector3d(std::cos(yaw_rad), std::sin(yaw_rad), 0.0);   // forward
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R_WC;
  T.translation() = p_W;
  return T;
}

/// n poses on a horizontal circle of `radius` around target at height offset dz, looking at target.
inline std::vector<Eigen::Isometry3d> ring(const Eigen::Vector3d& target, double radius, double dz, int n,
                                           double phase = 0.0) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < n; ++i) {
    const double a = phase + 2.0 * M_PI * i / n;
    poses.push_back(lookAt(target + Eigen::Vector3d(radius * std::cos(a), radius * std::sin(a), dz), target));
  }
  return poses;
}

}  // namespace semexp_test

#pragma once
/// @file trajectory.hpp
/// Time parameterisation of the planner's winning path for a flight
/// controller, and the sampled form a setpoint streamer follows.
///
/// The path is flown one segment at a time, at rest at every vertex: on the
/// segment from vertex i to i+1 a progress s in [0, 1] moves position
/// linearly from p_i to p_i+1 and yaw from psi_i to psi_i + remainder(psi_i+1
/// - psi_i, 2 pi) (the short way round, so the yaw never jumps at +-pi), and
/// s(t) is a trapezoidal (or, if too short to reach cruise, triangular)
/// profile. Its rate and acceleration are the largest that keep speed <=
/// v_max_mps, yaw rate <= omega_max_radps (the planner's utility limits),
/// linear acceleration <= a_max_mps2 and yaw acceleration <= alpha_max_radps2.
/// Stopping at every vertex keeps velocity continuous without corner
/// rounding, so the flown polyline is exactly the one the planner checked
/// for collisions; the RRT* paths have few vertices.

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

/// Limits of the trajectory besides the planner's v_max_mps and omega_max_radps (PlannerConfig).
///
/// The acceleration limits should stay below what the vehicle can do, so that
/// its controller has headroom to correct tracking errors: tracking a stream
/// of this trajectory's setpoints, the simulated MAV (1 m/s^2, 1 rad/s^2)
/// overshoots the end of a 6 m segment by 26 cm when the trajectory also uses
/// 1 m/s^2, and by 3 cm at 0.8 m/s^2 (test/python/test_sim_setpoints.py).
struct TrajectoryConfig {
  double a_max_mps2 = 0.8;        ///< `planner/a_max_mps2`: linear acceleration limit, m/s^2
  double alpha_max_radps2 = 0.8;  ///< `planner/alpha_max_radps2`: yaw acceleration limit, rad/s^2
  double trajectory_sample_period_s = 0.1;   ///< `planner/trajectory_sample_period_s`: time between published samples, s

  void validate(const std::string& ns = "planner/") const {
    require(std::isfinite(a_max_mps2) && a_max_mps2 > 0, ns + "a_max_mps2", "must be > 0 m/s^2");
    require(std::isfinite(alpha_max_radps2) && alpha_max_radps2 > 0, ns + "alpha_max_radps2", "must be > 0 rad/s^2");
    require(std::isfinite(trajectory_sample_period_s) && trajectory_sample_period_s >= 0.001 && trajectory_sample_period_s <= 10,
            ns + "trajectory_sample_period_s", "must be in [0.001, 10] s");
  }
};

/// The MAV's state on a trajectory at one time.
struct TrajectoryState {
  double t_s = 0.0;                                          ///< time since the trajectory's start, s
  Eigen::Vector3d position_W = Eigen::Vector3d::Zero();      ///< m
  Eigen::Vector3d velocity_W = Eigen::Vector3d::Zero();      ///< m/s
  Eigen::Vector3d acceleration_W = Eigen::Vector3d::Zero();  ///< m/s^2
  /// Yaw, rad; continuous along the trajectory (not wrapped to [-pi, pi], so
  /// a turn across +-pi does not jump).
  double yaw_rad = 0.0;
  double yaw_rate_radps = 0.0;  ///< rad/s
};

/// A rest-to-rest time parameterisation of a path with yaws (see the file comment).
class Trajectory {
 public:
  /// Throws std::invalid_argument if path_W and yaw_rad differ in size, the
  /// path is empty, a value is not finite or a limit is not > 0.
  Trajectory(const std::vector<Eigen::Vector3d>& path_W, const std::vector<double>& yaw_rad, double v_max_mps,
             double omega_max_radps, const TrajectoryConfig& config);

  /// Total duration, s (0 for a single vertex).
  double duration_s() const { return t_end_.empty() ? 0.0 : t_end_.back(); }
  /// The state at t_s, clamped to [0, duration_s()].
  TrajectoryState at(double t_s) const;
  /// States every period_s from 0, plus one at exactly duration_s().
  std::vector<TrajectoryState> sample(double period_s) const;

 private:
  /// One segment: s(t) accelerates at accel_ for t_ramp_, cruises at rate_, brakes.
  struct Segment {
    Eigen::Vector3d p0, d;  ///< start and displacement, m
    double yaw0 = 0, dyaw = 0;  ///< start yaw and (short-way) change, rad
    double rate = 0, accel = 0, t_ramp = 0, duration = 0;  ///< of the progress s: 1/s, 1/s^2, s, s
  };
  std::vector<Segment> segments_;
  std::vector<double> t_end_;  ///< cumulative end time of each segment, s
  Eigen::Vector3d end_W_ = Eigen::Vector3d::Zero();
  double end_yaw_rad_ = 0.0;
};

/// Duration of a rest-to-rest trapezoidal profile over `distance` with rate
/// limit `rate_max` and acceleration limit `accel_max` (any consistent unit),
/// s: distance / rate_max + rate_max / accel_max, or 2 sqrt(distance /
/// accel_max) when cruise is not reached.
double trapezoidDuration_s(double distance, double rate_max, double accel_max);

/// A trajectory given as timed samples (e.g. received in a message), evaluated
/// by linear interpolation of position and of yaw (the short way between
/// neighbouring samples). With samples every 0.1 s of a trajectory whose
/// acceleration is <= 1 m/s^2 the position differs from the exact one by <=
/// a dt^2 / 8 = 1.25 mm.
class SampledTrajectory {
 public:
  struct Sample {
    double t_s = 0.0;  ///< time since the start, s; strictly increasing
    Eigen::Vector3d position_W = Eigen::Vector3d::Zero();
    double yaw_rad = 0.0;
  };
  SampledTrajectory() = default;
  /// Throws std::invalid_argument (naming the sample) if empty, not finite or not strictly increasing in time.
  explicit SampledTrajectory(std::vector<Sample> samples);
  bool empty() const { return samples_.empty(); }
  double duration_s() const { return samples_.empty() ? 0.0 : samples_.back().t_s; }
  const Sample& front() const { return samples_.front(); }
  const Sample& back() const { return samples_.back(); }
  /// Position and yaw at t_s, clamped to [first t, last t]; yaw in [-pi, pi].
  Sample at(double t_s) const;

 private:
  std::vector<Sample> samples_;
};

}  // namespace semexp

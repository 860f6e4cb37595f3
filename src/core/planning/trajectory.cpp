#include "semantic_exploration/core/planning/trajectory.hpp"

#include <algorithm>
#include <stdexcept>

namespace semexp {

namespace {

constexpr double kMinLength_m = 1e-9;    // shorter segments move yaw only
constexpr double kMinYaw_rad = 1e-12;    // smaller yaw changes are none
constexpr double kTwoPi = 2.0 * M_PI;

std::string atIndex(const char* what, std::size_t i) { return std::string(what) + " " + std::to_string(i); }

}  // namespace

double trapezoidDuration_s(double distance, double rate_max, double accel_max) {
  if (distance <= 0) return 0.0;
  // Cruise is reached iff the ramps up and down (rate_max^2 / accel_max together) fit in the distance.
  if (rate_max * rate_max / accel_max >= distance) return 2.0 * std::sqrt(distance / accel_max);
  return distance / rate_max + rate_max / accel_max;
}

Trajectory::Trajectory(const std::vector<Eigen::Vector3d>& path_W, const std::vector<double>& yaw_rad,
                       double v_max_mps, double omega_max_radps, const TrajectoryConfig& config) {
  if (path_W.empty()) throw std::invalid_argument("trajectory: the path is empty");
  if (path_W.size() != yaw_rad.size())
    throw std::invalid_argument("trajectory: " + std::to_string(path_W.size()) + " path vertices but " +
                                std::to_string(yaw_rad.size()) + " yaws");
  for (std::size_t i = 0; i < path_W.size(); ++i)
    if (!path_W[i].allFinite() || !std::isfinite(yaw_rad[i]))
      throw std::invalid_argument("trajectory: " + atIndex("vertex", i) + " is not finite");
  if (!(v_max_mps > 0 && omega_max_radps > 0 && config.a_max_mps2 > 0 && config.alpha_max_radps2 > 0) ||
      !std::isfinite(v_max_mps + omega_max_radps + config.a_max_mps2 + config.alpha_max_radps2))
    throw std::invalid_argument("trajectory: every limit must be finite and > 0");

  double yaw = yaw_rad.front();  // unwrapped: each segment turns the short way from the previous end
  double t = 0.0;
  for (std::size_t i = 0; i + 1 < path_W.size(); ++i) {
    Segment s;
    s.p0 = path_W[i];
    s.d = path_W[i + 1] - path_W[i];
    s.yaw0 = yaw;
    s.dyaw = std::remainder(yaw_rad[i + 1] - yaw_rad[i], kTwoPi);
    const double length = s.d.norm(), turn = std::abs(s.dyaw);
    if (length < kMinLength_m && turn < kMinYaw_rad) continue;  // a repeated vertex
    // Limits of the progress s in [0, 1]: each physical limit divided by what s = 1 covers.
    double rate_max = INFINITY, accel_max = INFINITY;
    if (length >= kMinLength_m) {
      rate_max = v_max_mps / length;
      accel_max = config.a_max_mps2 / length;
    }
    if (turn >= kMinYaw_rad) {
      rate_max = std::min(rate_max, omega_max_radps / turn);
      accel_max = std::min(accel_max, config.alpha_max_radps2 / turn);
    }
    s.accel = accel_max;
    s.duration = trapezoidDuration_s(1.0, rate_max, accel_max);
    s.rate = std::min(rate_max, std::sqrt(accel_max));  // the triangle's peak when cruise is not reached
    s.t_ramp = s.rate / s.accel;
    yaw += s.dyaw;
    t += s.duration;
    segments_.push_back(s);
    t_end_.push_back(t);
  }
  end_W_ = path_W.back();
  // The last yaw exactly, in the turn count the segments reached.
  end_yaw_rad_ = yaw_rad.back() + kTwoPi * std::round((yaw - yaw_rad.back()) / kTwoPi);
  if (segments_.empty()) end_yaw_rad_ = yaw_rad.front();
}

TrajectoryState Trajectory::at(double t_s) const {
  TrajectoryState st;
  st.t_s = std::clamp(t_s, 0.0, duration_s());
  if (segments_.empty() || !(t_s < duration_s())) {  // the end (also for NaN): exact, at rest
    st.t_s = duration_s();
    st.position_W = end_W_;
    st.yaw_rad = end_yaw_rad_;
    return st;
  }
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(t_end_.begin(), t_end_.end(), st.t_s) -
                                                 t_end_.begin());
  const Segment& s = segments_[k];
  const double tau = st.t_s - (k == 0 ? 0.0 : t_end_[k - 1]);
  double p = 0, v = 0, a = 0;  // progress, its rate and acceleration
  if (tau < s.t_ramp) {
    p = 0.5 * s.accel * tau * tau;
    v = s.accel * tau;
    a = s.accel;
  } else if (tau <= s.duration - s.t_ramp) {
    p = 0.5 * s.accel * s.t_ramp * s.t_ramp + s.rate * (tau - s.t_ramp);
    v = s.rate;
  } else {
    const double left = s.duration - tau;
    p = 1.0 - 0.5 * s.accel * left * left;
    v = s.accel * left;
    a = -s.accel;
  }
  st.position_W = s.p0 + p * s.d;
  st.velocity_W = v * s.d;
  st.acceleration_W = a * s.d;
  st.yaw_rad = s.yaw0 + p * s.dyaw;
  st.yaw_rate_radps = v * s.dyaw;
  return st;
}

std::vector<TrajectoryState> Trajectory::sample(double period_s) const {
  if (!(period_s > 0)) throw std::invalid_argument("trajectory: the sample period must be > 0 s");
  std::vector<TrajectoryState> out;
  const double T = duration_s();
  // Samples closer than a thousandth of a period to the end are left to the end sample.
  for (std::size_t k = 0;; ++k) {
    const double t = static_cast<double>(k) * period_s;
    if (t >= T - 1e-3 * period_s) break;
    out.push_back(at(t));
  }
  out.push_back(at(T));
  return out;
}

SampledTrajectory::SampledTrajectory(std::vector<Sample> samples) : samples_(std::move(samples)) {
  if (samples_.empty()) throw std::invalid_argument("the trajectory has no points");
  for (std::size_t i = 0; i < samples_.size(); ++i) {
    const Sample& s = samples_[i];
    if (!std::isfinite(s.t_s) || !s.position_W.allFinite() || !std::isfinite(s.yaw_rad))
      throw std::invalid_argument(atIndex("point", i) + " is not finite");
    if (i > 0 && !(s.t_s > samples_[i - 1].t_s))
      throw std::invalid_argument(atIndex("point", i) + ": time_from_start does not increase");
  }
}

SampledTrajectory::Sample SampledTrajectory::at(double t_s) const {
  if (samples_.empty()) throw std::logic_error("SampledTrajectory::at on an empty trajectory");
  Sample out;
  if (!(t_s > samples_.front().t_s)) {
    out = samples_.front();
  } else if (!(t_s < samples_.back().t_s)) {
    out = samples_.back();
  } else {
    const auto it = std::upper_bound(samples_.begin(), samples_.end(), t_s,
                                     [](double t, const Sample& s) { return t < s.t_s; });
    const Sample& b = *it;
    const Sample& a = *(it - 1);
    const double f = (t_s - a.t_s) / (b.t_s - a.t_s);
    out.t_s = t_s;
    out.position_W = a.position_W + f * (b.position_W - a.position_W);
    out.yaw_rad = a.yaw_rad + f * std::remainder(b.yaw_rad - a.yaw_rad, kTwoPi);
  }
  out.yaw_rad = std::remainder(out.yaw_rad, kTwoPi);
  return out;
}

}  // namespace semexp

#include "semantic_exploration/ros/frame_timing.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace semexp_ros {

namespace {

double wallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

double threadCpuSeconds() {
  timespec ts{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0) return 0.0;
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

FrameTimer::FrameTimer() : wall0_s_(wallSeconds()), cpu0_s_(threadCpuSeconds()) {}

double FrameTimer::wall_ms() const { return (wallSeconds() - wall0_s_) * 1e3; }

double FrameTimer::cpu_ms() const { return (threadCpuSeconds() - cpu0_s_) * 1e3; }

CpuBudget::CpuBudget(std::size_t window) : window_(std::max<std::size_t>(1, window)) {}

void CpuBudget::add(double cpu_ms) {
  ++frames_;
  if (values_ms_.size() < window_) {
    values_ms_.push_back(cpu_ms);
    return;
  }
  values_ms_[next_] = cpu_ms;
  next_ = (next_ + 1) % window_;
}

double CpuBudget::percentile_ms(double p) const {
  if (values_ms_.empty()) return 0.0;
  std::vector<double> v = values_ms_;
  const double n = static_cast<double>(v.size());
  const auto rank = static_cast<std::size_t>(std::max(1.0, std::ceil(std::min(100.0, p) / 100.0 * n)));
  const auto k = static_cast<std::ptrdiff_t>(rank - 1);
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[static_cast<std::size_t>(k)];
}

}  // namespace semexp_ros

#include "semantic_exploration/ros/frame_timing.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

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

FrameTimer::FrameTimer(std::function<double()> helper_cpu_s)
    : helper_cpu_s_(std::move(helper_cpu_s)), wall0_s_(wallSeconds()), cpu0_s_(threadCpuSeconds()) {
  if (helper_cpu_s_) helper0_s_ = helper_cpu_s_();
}

double FrameTimer::wall_ms() const { return (wallSeconds() - wall0_s_) * 1e3; }

double FrameTimer::cpu_ms() const {
  const double helpers_s = helper_cpu_s_ ? std::max(0.0, helper_cpu_s_() - helper0_s_) : 0.0;
  return (threadCpuSeconds() - cpu0_s_ + helpers_s) * 1e3;
}

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

#pragma once
/// @file frame_timing.hpp
/// Per-frame cost of a mapping node: the wall time and the CPU time of the
/// thread that handled the frame (CLOCK_THREAD_CPUTIME_ID: the node's own
/// work, not time spent waiting for a pose or sharing the cores) plus that of
/// the helper threads it handed work to (a worker pool's own clock), and the
/// median and 95th percentile of the latter over recent frames, so that a
/// run's report can show each node's CPU budget. No ROS in here.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace semexp_ros {

/// Started when a frame's callback begins.
class FrameTimer {
 public:
  /// `helper_cpu_s`, if given, is a monotone clock of the CPU time (s) of the
  /// threads the frame's work is handed to besides the calling one (e.g.
  /// OccupancyMap::workerCpuSeconds): its change counts in cpu_ms().
  explicit FrameTimer(std::function<double()> helper_cpu_s = {});
  /// Wall time since construction, ms.
  double wall_ms() const;
  /// CPU time since construction, ms: the calling thread's (call it from the
  /// thread that constructed it) plus the helpers' (never negative).
  double cpu_ms() const;

 private:
  std::function<double()> helper_cpu_s_;
  double wall0_s_;
  double cpu0_s_;
  double helper0_s_ = 0.0;
};

/// Thread CPU time of the calling thread, s.
double threadCpuSeconds();

/// Median and 95th percentile of the last `window` frame costs (ms), by the
/// nearest-rank rule: the p-th percentile of n sorted values is the value at
/// rank ceil(p/100 x n), so both are values that were measured.
class CpuBudget {
 public:
  explicit CpuBudget(std::size_t window = 1000);
  void add(double cpu_ms);
  /// Frames added since start (not only those in the window).
  std::uint64_t frames() const { return frames_; }
  /// 0 before the first frame.
  double median_ms() const { return percentile_ms(50.0); }
  double p95_ms() const { return percentile_ms(95.0); }
  /// p in (0, 100]; 0 before the first frame.
  double percentile_ms(double p) const;

 private:
  std::size_t window_;
  std::vector<double> values_ms_;  ///< ring of the last `window_` values
  std::size_t next_ = 0;           ///< where the next value goes once the ring is full
  std::uint64_t frames_ = 0;
};

}  // namespace semexp_ros

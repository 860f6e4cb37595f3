#pragma once
/// @file parallel_for.hpp
/// Runs job(i) for every i in [0, n) on up to `threads` threads, the caller's
/// included, handing out indices one at a time (jobs of uneven cost balance
/// themselves). For work of milliseconds per call: the extra threads are
/// started and joined on every call (occupancy::WorkerPool keeps its threads,
/// but belongs to the integrator and is not re-entrant).
///
/// An exception thrown by a job stops the hand-out, and the first one is
/// rethrown to the caller once every thread has finished. A thread that
/// cannot be started leaves its share to the others.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace semexp {

/// job must write only to what index i owns.
template <typename Job>
void parallelFor(std::size_t n, int threads, const Job& job) {
  std::atomic<std::size_t> next{0};
  std::exception_ptr first_error;
  std::mutex error_mutex;
  auto worker = [&]() {
    try {
      for (std::size_t i = next++; i < n; i = next++) job(i);
    } catch (...) {
      next = n;  // no new indices: the others finish the ones they hold
      const std::lock_guard<std::mutex> lock(error_mutex);
      if (!first_error) first_error = std::current_exception();
    }
  };
  const int k = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(std::max(1, threads)), n));
  std::vector<std::thread> pool;
  for (int t = 1; t < k; ++t) {
    try {
      pool.emplace_back(worker);
    } catch (const std::system_error&) {
      break;  // no more threads: the caller and the started ones do the rest
    }
  }
  worker();
  for (auto& t : pool) t.join();
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace semexp

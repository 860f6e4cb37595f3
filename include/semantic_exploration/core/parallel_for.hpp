#pragma once
/// @file parallel_for.hpp
/// Runs job(i) for every i in [0, n) on up to `threads` threads, the caller's
/// included, handing out indices one at a time (jobs of uneven cost balance
/// themselves). For work of a few milliseconds and more per call: the extra
/// threads are started and joined on every call.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace semexp {

/// job must write only to what index i owns, and must not throw.
template <typename Job>
void parallelFor(std::size_t n, int threads, const Job& job) {
  std::atomic<std::size_t> next{0};
  auto worker = [&]() {
    for (std::size_t i = next++; i < n; i = next++) job(i);
  };
  const int k = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(std::max(1, threads)), n));
  std::vector<std::thread> pool;
  for (int t = 1; t < k; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

}  // namespace semexp

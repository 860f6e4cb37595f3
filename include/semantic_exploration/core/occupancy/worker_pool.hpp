#pragma once
/// @file worker_pool.hpp
/// A small fixed pool of threads that runs the tasks of one call to run() and
/// returns when all are done (internal to the occupancy map's integrator).

#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace semexp {
namespace occupancy {

class WorkerPool {
 public:
  /// `threads` >= 1 in all, the calling thread included (1: no extra thread).
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  /// Calls f(i) once for every i in [0, n), spread over the threads (the
  /// caller takes part); returns when all calls returned. Which thread runs
  /// which i is not fixed: f must write only to what task i owns. Not
  /// re-entrant; f must not throw.
  void run(std::size_t n, const std::function<void(std::size_t)>& f);
  /// CPU time the pool's own threads (not the callers of run()) have used
  /// since construction, s: what a caller's thread CPU clock misses of the
  /// work it hands out. 0 with one thread.
  double workerCpuSeconds() const;

 private:
  void workerLoop();
  void drain();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(std::size_t)>* job_ = nullptr;
  std::size_t n_ = 0, next_ = 0, finished_ = 0;
  std::size_t generation_ = 0;
  bool stop_ = false;
};

}  // namespace occupancy
}  // namespace semexp

// Fixed thread pool of the occupancy map's integrator.
#include "semantic_exploration/core/occupancy/worker_pool.hpp"

#include <pthread.h>
#include <time.h>

namespace semexp {
namespace occupancy {

WorkerPool::WorkerPool(int threads) {
  for (int i = 1; i < threads; ++i) workers_.emplace_back([this] { workerLoop(); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void WorkerPool::run(std::size_t n, const std::function<void(std::size_t)>& f) {
  if (workers_.empty() || n <= 1) {
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = &f;
    n_ = n;
    next_ = 0;
    finished_ = 0;
    ++generation_;
  }
  wake_.notify_all();
  drain();
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return finished_ == n_; });
  job_ = nullptr;
}

double WorkerPool::workerCpuSeconds() const {
  double s = 0.0;
  for (const std::thread& t : workers_) {
    // Each worker's own CPU clock: it runs until the pool is destroyed, so its handle stays valid.
    clockid_t clock;
    timespec ts{};
    if (pthread_getcpuclockid(const_cast<std::thread&>(t).native_handle(), &clock) != 0 ||
        clock_gettime(clock, &ts) != 0)
      continue;
    s += static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
  }
  return s;
}

// Takes task indices one at a time until none is left.
void WorkerPool::drain() {
  while (true) {
    std::size_t i;
    const std::function<void(std::size_t)>* job;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (job_ == nullptr || next_ >= n_) return;
      i = next_++;
      job = job_;
    }
    (*job)(i);
    std::lock_guard<std::mutex> lock(mutex_);
    if (++finished_ == n_) done_.notify_all();
  }
}

void WorkerPool::workerLoop() {
  std::size_t seen = 0;
  while (true) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
    }
    drain();
  }
}

}  // namespace occupancy
}  // namespace semexp

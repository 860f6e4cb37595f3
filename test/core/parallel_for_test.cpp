// parallelFor (parallel_for.hpp): every index once, on any thread count, and
// a job's exception reaches the caller after all threads have finished.
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

#include "semantic_exploration/core/parallel_for.hpp"

using semexp::parallelFor;

TEST(ParallelFor, RunsEveryIndexOnceOnAnyThreadCount) {
  for (int threads : {-1, 0, 1, 2, 3, 16}) {
    std::vector<int> calls(37, 0);  // each index owns its slot
    parallelFor(calls.size(), threads, [&](std::size_t i) { ++calls[i]; });
    for (std::size_t i = 0; i < calls.size(); ++i) EXPECT_EQ(calls[i], 1) << threads << " threads, index " << i;
  }
  int none = 0;
  parallelFor(0, 4, [&](std::size_t) { ++none; });
  EXPECT_EQ(none, 0);
}

TEST(ParallelFor, AJobsExceptionReachesTheCallerAfterTheOthersFinish) {
  for (int threads : {1, 2, 4}) {
    std::atomic<int> running{0}, finished{0};
    try {
      parallelFor(100, threads, [&](std::size_t i) {
        ++running;
        if (i == 10) throw std::runtime_error("job 10 failed");
        ++finished;
        --running;
      });
      FAIL() << "no exception with " << threads << " threads";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "job 10 failed");
    }
    // Only the failed job is still counted as running: every other job that started also returned.
    EXPECT_EQ(running.load(), 1) << threads << " threads";
    // Indices 0-9 were handed out before 10, so they ran to the end; on one
    // thread the hand-out stops right there (with more, others may take a
    // few more indices before the failed job throws).
    if (threads == 1)
      EXPECT_EQ(finished.load(), 10);
    else
      EXPECT_GE(finished.load(), 10) << threads << " threads";
  }
}

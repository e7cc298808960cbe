// ThreadPool: every index once per call, reuse across calls, exceptions reach the caller, and
// the same workers serve every call (their thread_local state survives).
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "motion_model_estimation/core/thread_pool.h"

namespace {

TEST(ThreadPool, RunsEveryIndexExactlyOncePerCall) {
  for (int threads : {1, 2, 3}) {
    mme::ThreadPool pool(threads);
    EXPECT_EQ(pool.threads(), threads);
    for (size_t count : {0u, 1u, 7u, 1000u}) {
      std::vector<std::atomic<int>> hits(count);
      pool.parallelFor(count, [&](size_t i) { ++hits[i]; });
      for (size_t i = 0; i < count; ++i) EXPECT_EQ(hits[i].load(), 1) << "index " << i;
    }
  }
}

TEST(ThreadPool, UsesItsWorkersAndKeepsThemBetweenCalls) {
  mme::ThreadPool pool(2);
  std::mutex m;
  std::set<std::thread::id> first, later;
  // Enough slow work that the worker takes part.
  auto body = [&](std::set<std::thread::id>* ids) {
    return [&m, ids](size_t) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      std::lock_guard<std::mutex> lock(m);
      ids->insert(std::this_thread::get_id());
    };
  };
  pool.parallelFor(40, body(&first));
  for (int call = 0; call < 5; ++call) pool.parallelFor(40, body(&later));
  EXPECT_EQ(first.size(), 2u);  // the caller and the worker
  EXPECT_EQ(later, first);      // no new threads: the same two ran every later call
}

TEST(ThreadPool, RethrowsTheFirstExceptionAndStaysUsable) {
  mme::ThreadPool pool(2);
  EXPECT_THROW(pool.parallelFor(100, [](size_t i) {
                 if (i == 37) throw std::runtime_error("bad individual");
               }),
               std::runtime_error);
  std::atomic<int> sum{0};
  pool.parallelFor(10, [&](size_t i) { sum += static_cast<int>(i); });
  EXPECT_EQ(sum.load(), 45);
}

}  // namespace

// A fixed set of worker threads for data-parallel loops (the population's evaluations). The
// workers live as long as the pool: no thread start per generation, and each worker keeps its
// thread_local scratch (the cost function's workspace) warm between calls. Between calls a
// worker spins for a short while before it sleeps: during a run the next generation's work
// comes within microseconds, and a sleeping thread takes tens of microseconds to wake.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace mme {

class ThreadPool {
 public:
  /// `threads` >= 1 counts the calling thread: threads - 1 workers are started.
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  /// Calls body(i) for every i in [0, count), spread over the workers and the caller; returns
  /// when all calls have returned. Which thread runs which i is not fixed, so body must give
  /// the same result whichever runs it. The first exception thrown by body is rethrown here
  /// (the indices not started by then are skipped). Not reentrant: one caller at a time.
  void parallelFor(size_t count, const std::function<void(size_t)>& body);

  /// How long an idle worker spins before it sleeps [microseconds].
  static constexpr int kSpinMicroseconds = 200;

 private:
  void workerLoop();
  void runShare();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(size_t)>* body_ = nullptr;
  size_t count_ = 0;
  std::atomic<size_t> next_{0};       ///< next index to hand out
  std::atomic<uint64_t> job_{0};      ///< bumped (under mutex_) per parallelFor call
  std::atomic<int> busy_{0};          ///< workers still in the current job
  std::atomic<bool> stop_{false};
  std::atomic<bool> failed_{false};
  std::exception_ptr error_;          ///< under mutex_
};

}  // namespace mme

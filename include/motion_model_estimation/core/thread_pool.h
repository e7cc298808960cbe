// A fixed set of worker threads for data-parallel loops (the population's evaluations). The
// workers live as long as the pool: no thread start per generation, and each worker keeps its
// thread_local scratch (the cost function's workspace) warm between calls.
#pragma once

#include <condition_variable>
#include <cstddef>
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
  /// the same result whichever runs it. The first exception thrown by body is rethrown here.
  void parallelFor(size_t count, const std::function<void(size_t)>& body);

 private:
  void workerLoop();
  void runShare();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(size_t)>* body_ = nullptr;
  size_t count_ = 0;
  size_t next_ = 0;            ///< next index to hand out (under mutex_)
  uint64_t job_ = 0;           ///< bumped per parallelFor call
  int busy_ = 0;               ///< workers still in the current job
  bool stop_ = false;
  std::exception_ptr error_;
};

}  // namespace mme

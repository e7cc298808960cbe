// Latency statistics of the live node: the time from a frame's arrival to the publication of
// the markers drawn from it, over the last 1024 drawn frames, with nearest-rank percentiles.
// Thread-safe (the markers thread adds, the ~stats timer reads). No ROS here.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <vector>

namespace mme {

struct LatencySummary {
  uint64_t count = 0;   ///< latencies ever added (frames whose markers were published)
  size_t kept = 0;      ///< latencies the percentiles are taken over (the last `window`)
  double p50_ms = 0.0;  ///< [ms] nearest-rank median of the kept ones (0 when none)
  double p99_ms = 0.0;  ///< [ms] nearest-rank 99th percentile of the kept ones (0 when none)
};

class LatencyStats {
 public:
  static constexpr size_t kDefaultWindow = 1024;

  explicit LatencyStats(size_t window = kDefaultWindow);
  void add(double latency_ms);
  LatencySummary summary() const;

  /// Nearest-rank percentile, q in (0, 1]: the smallest value with at least q of the values at
  /// or below it, i.e. the ceil(q n)-th smallest. `values` is reordered. NaN when it is empty.
  static double percentile(std::vector<double>* values, double q);

 private:
  const size_t window_;
  mutable std::mutex mutex_;
  std::deque<double> latencies_ms_;
  uint64_t count_ = 0;
};

}  // namespace mme

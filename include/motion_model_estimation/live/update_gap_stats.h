// Gaps between consecutive estimate updates (the worker's successful OnlineEstimator::update()
// calls): how long the estimate went without refreshing, the longest over the whole run and the
// longest in the last 10 s. The gap still open (since the last update) counts too, so a stalled
// worker or a window too short to identify on shows at once, not only at the next update.
// Times are [s] on a monotonic clock of the caller's. Thread-safe. No ROS here.
#pragma once

#include <cstdint>
#include <deque>
#include <mutex>
#include <utility>

namespace mme {

struct UpdateGapSummary {
  uint64_t updates = 0;          ///< successful updates so far
  double max_gap_ms = 0.0;       ///< [ms] longest gap since the first update (0 before it)
  double recent_max_gap_ms = 0.0;  ///< [ms] longest gap that ended in the last `recent_s`
};

class UpdateGapStats {
 public:
  static constexpr double kDefaultRecentS = 10.0;

  explicit UpdateGapStats(double recent_s = kDefaultRecentS);
  void onUpdate(double now_s);  ///< an update succeeded at `now_s`
  uint64_t updates() const;
  /// As of `now_s` (>= the last update's time), the open gap included.
  UpdateGapSummary summary(double now_s) const;

 private:
  const double recent_s_;
  mutable std::mutex mutex_;
  uint64_t updates_ = 0;
  double last_s_ = 0.0;
  double max_gap_s_ = 0.0;
  std::deque<std::pair<double, double>> recent_;  // (end [s], gap [s]) of the last recent_s_
};

}  // namespace mme

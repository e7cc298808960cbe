// Gaps between consecutive estimate updates (the worker's successful OnlineEstimator::update()
// calls): how long the estimate went without refreshing, the longest over the whole run and the
// longest in the last 10 s. The gap still open (since the last update) counts too, so a stalled
// worker or a window too short to identify on shows at once, not only at the next update.
// Every gap's length is also counted in 1-ms bins for its 99th percentile, and the caller may
// say where a gap's time went (UpdateGapBreakdown): the largest gap keeps its breakdown.
// Times are [s] on a monotonic clock of the caller's. Thread-safe. No ROS here.
#pragma once

#include <cstdint>
#include <deque>
#include <mutex>
#include <utility>
#include <vector>

namespace mme {

/// Where the worker's time between two updates went, as its own thread clock saw it
/// (thread_times.h): on a core, runnable but waiting for one, or neither (sleeping between
/// updates that found nothing to do, blocked on a lock, I/O or a page fault).
struct UpdateGapBreakdown {
  double in_update_s = 0.0;  ///< [s] wall time inside update() calls
  double on_cpu_s = 0.0;     ///< [s] the worker's time on a core
  double waiting_s = 0.0;    ///< [s] runnable, waiting for a core
  bool known = false;        ///< false: the caller did not measure it
};

struct UpdateGapSummary {
  uint64_t updates = 0;          ///< successful updates so far
  double max_gap_ms = 0.0;       ///< [ms] longest gap since the first update (0 before it)
  double recent_max_gap_ms = 0.0;  ///< [ms] longest gap that ended in the last `recent_s`
  /// [ms] 99th percentile (nearest rank, 1-ms bins) of the closed gaps (0 before the first)
  double p99_gap_ms = 0.0;
  /// The breakdown of the longest closed gap (known false when it was not measured).
  UpdateGapBreakdown max_gap_breakdown;
};

class UpdateGapStats {
 public:
  static constexpr double kDefaultRecentS = 10.0;

  explicit UpdateGapStats(double recent_s = kDefaultRecentS);
  /// An update succeeded at `now_s`, ending a gap whose time went as `breakdown` says.
  void onUpdate(double now_s, const UpdateGapBreakdown& breakdown = UpdateGapBreakdown());
  uint64_t updates() const;
  /// As of `now_s` (>= the last update's time), the open gap included.
  UpdateGapSummary summary(double now_s) const;

 private:
  const double recent_s_;
  mutable std::mutex mutex_;
  uint64_t updates_ = 0;
  double last_s_ = 0.0;
  double max_gap_s_ = 0.0;
  UpdateGapBreakdown max_gap_breakdown_;
  std::vector<uint64_t> gap_bins_;  // closed gaps per 1-ms bin; the last bin holds longer ones
  uint64_t closed_gaps_ = 0;
  std::deque<std::pair<double, double>> recent_;  // (end [s], gap [s]) of the last recent_s_
};

}  // namespace mme

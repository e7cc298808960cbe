#include "motion_model_estimation/live/update_gap_stats.h"

#include <algorithm>
#include <cmath>

namespace mme {

namespace {
constexpr size_t kGapBins = 10000;  ///< 1-ms bins up to 10 s: a fixed memory, whatever the run
}

UpdateGapStats::UpdateGapStats(double recent_s) : recent_s_(recent_s), gap_bins_(kGapBins, 0) {}

void UpdateGapStats::onUpdate(double now_s, const UpdateGapBreakdown& breakdown) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (updates_ > 0) {
    const double gap_s = now_s - last_s_;
    if (gap_s > max_gap_s_) {
      max_gap_s_ = gap_s;
      max_gap_breakdown_ = breakdown;
    }
    const double bin = std::floor(std::max(0.0, 1e3 * gap_s));
    ++gap_bins_[bin < static_cast<double>(kGapBins - 1) ? static_cast<size_t>(bin) : kGapBins - 1];
    ++closed_gaps_;
    recent_.emplace_back(now_s, gap_s);
    while (!recent_.empty() && recent_.front().first < now_s - recent_s_) recent_.pop_front();
  }
  ++updates_;
  last_s_ = now_s;
}

uint64_t UpdateGapStats::updates() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return updates_;
}

UpdateGapSummary UpdateGapStats::summary(double now_s) const {
  std::lock_guard<std::mutex> lock(mutex_);
  UpdateGapSummary s;
  s.updates = updates_;
  if (updates_ == 0) return s;
  const double open_s = std::max(0.0, now_s - last_s_);
  double recent_s = open_s;
  for (const auto& [end_s, gap_s] : recent_)
    if (end_s >= now_s - recent_s_) recent_s = std::max(recent_s, gap_s);
  s.max_gap_ms = 1e3 * std::max(max_gap_s_, open_s);
  s.recent_max_gap_ms = 1e3 * recent_s;
  s.max_gap_breakdown = max_gap_breakdown_;
  if (closed_gaps_ > 0) {
    // Nearest rank: the smallest bin whose count reaches 99 % of the gaps; its upper edge.
    const uint64_t rank = (99 * closed_gaps_ + 99) / 100;
    uint64_t seen = 0;
    size_t b = 0;
    for (; b < kGapBins; ++b) {
      seen += gap_bins_[b];
      if (seen >= rank) break;
    }
    s.p99_gap_ms = b + 1 < kGapBins ? static_cast<double>(b + 1) : 1e3 * max_gap_s_;
  }
  return s;
}

}  // namespace mme

#include "motion_model_estimation/live/update_gap_stats.h"

#include <algorithm>

namespace mme {

UpdateGapStats::UpdateGapStats(double recent_s) : recent_s_(recent_s) {}

void UpdateGapStats::onUpdate(double now_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (updates_ > 0) {
    const double gap_s = now_s - last_s_;
    max_gap_s_ = std::max(max_gap_s_, gap_s);
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
  return s;
}

}  // namespace mme

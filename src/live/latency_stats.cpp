#include "motion_model_estimation/live/latency_stats.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mme {

LatencyStats::LatencyStats(size_t window) : window_(std::max<size_t>(window, 1)) {}

void LatencyStats::add(double latency_ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++count_;
  latencies_ms_.push_back(latency_ms);
  if (latencies_ms_.size() > window_) latencies_ms_.pop_front();
}

LatencySummary LatencyStats::summary() const {
  std::vector<double> values;
  LatencySummary s;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    values.assign(latencies_ms_.begin(), latencies_ms_.end());
    s.count = count_;
  }
  s.kept = values.size();
  if (!values.empty()) {
    s.p50_ms = percentile(&values, 0.5);
    s.p99_ms = percentile(&values, 0.99);
  }
  return s;
}

double LatencyStats::percentile(std::vector<double>* values, double q) {
  if (values->empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t n = values->size();
  const size_t rank = static_cast<size_t>(std::ceil(q * static_cast<double>(n)));
  const size_t k = std::min(n - 1, rank > 0 ? rank - 1 : 0);
  std::nth_element(values->begin(), values->begin() + k, values->end());
  return (*values)[k];
}

}  // namespace mme

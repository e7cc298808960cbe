#include "motion_model_estimation/ros/island_link.h"

#include <algorithm>

#include "motion_model_estimation/ros/conversions.h"

namespace mme {

IslandLink::IslandLink(ros::NodeHandle& nh, const IslandLinkOptions& options, OnlineEstimator* estimator)
    : options_(options), estimator_(estimator) {
  publisher_ = nh.advertise<motion_model_estimation::Migrants>(options_.migration_topic, 10);
  // No Nagle delay: a batch is one small message, and it should arrive well within a period.
  subscriber_ = nh.subscribe(options_.migration_topic, 20, &IslandLink::onMigrants, this,
                             ros::TransportHints().tcpNoDelay());
}

void IslandLink::afterUpdate() {
  const uint32_t generation = estimator_->estimate().generation;
  if (generation < last_sent_generation_) last_sent_generation_ = 0;  // a new population
  if (generation < last_sent_generation_ + static_cast<uint32_t>(options_.migration_period_generations))
    return;
  MigrantBatch batch = estimator_->emigrants(options_.migrants);
  if (batch.individuals.empty()) return;
  batch.island_id = options_.island_id;
  last_sent_generation_ = batch.generation;
  // The stamp is the sender's wall clock, so that a receiver measures the trip on its own wall
  // clock whatever either uses as ROS time (sim time on a replay).
  const ros::WallTime now = ros::WallTime::now();
  publisher_.publish(toMigrantsMsg(batch, ros::Time(now.sec, now.nsec)));
  const auto sent_at = std::chrono::steady_clock::now();
  std::lock_guard<std::mutex> lock(stats_mutex_);
  if (stats_.sent > 0)
    periods_ms_.add(std::chrono::duration<double, std::milli>(sent_at - last_sent_time_).count());
  last_sent_time_ = sent_at;
  stats_.sent += batch.individuals.size();
}

void IslandLink::onMigrants(const motion_model_estimation::Migrants::ConstPtr& msg) {
  if (msg->island_id == options_.island_id) return;  // our own, back from the shared topic
  const ros::WallTime now = ros::WallTime::now();
  const double stamp_s = msg->header.stamp.toSec();
  const double latency_ms = 1e3 * (now.toSec() - stamp_s);
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.batches_from_peers;
    latencies_ms_.add(latency_ms);
    stats_.latency_max_ms = stats_.batches_from_peers == 1 ? latency_ms
                                                           : std::max(stats_.latency_max_ms, latency_ms);
    // Late: slower than the sender's own period for this batch (its previous one's stamp to
    // this one's), i.e. the next batch was already due when this one arrived.
    const auto previous = last_stamp_s_.find(msg->island_id);
    if (previous != last_stamp_s_.end() && stamp_s > previous->second &&
        latency_ms > 1e3 * (stamp_s - previous->second))
      ++stats_.batches_late;
    last_stamp_s_[msg->island_id] = stamp_s;
  }
  MigrantBatch batch;
  std::string why = fromMigrantsMsg(*msg, &batch);
  // A message that cannot be read is refused and counted like migrants of another model.
  why = why.empty() ? estimator_->receiveMigrants(std::move(batch))
                    : estimator_->refuseMigrants(msg->migrant_count, why);
  if (!why.empty())
    ROS_WARN_THROTTLE(10.0, "estimator_node: migrants of island '%s' refused: %s",
                      msg->island_id.c_str(), why.c_str());
}

IslandStats IslandLink::stats() const {
  IslandStats s;
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    s = stats_;
  }
  const LatencySummary latency = latencies_ms_.summary();  // thread-safe units
  s.latency_p50_ms = latency.p50_ms;
  s.latency_p99_ms = latency.p99_ms;
  s.period_ms = periods_ms_.summary().p50_ms;
  s.counters = estimator_->migrationCounters();
  return s;
}

}  // namespace mme

// The island model over ROS: an estimator_node with ~islands/enabled publishes its best
// individuals on one shared topic every ~migration_period_generations and hands the other
// islands' to its estimator (OnlineEstimator::receiveMigrants), which lets them compete at its
// next update. Any number of islands, on any hosts of one master, join or leave at any time: a
// peer is only a topic connection, so nothing waits for one.
#pragma once

#include <ros/ros.h>

#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

#include "motion_model_estimation/Migrants.h"
#include "motion_model_estimation/identification/online/online_estimator.h"
#include "motion_model_estimation/live/estimator_node_options.h"
#include "motion_model_estimation/live/estimator_stats.h"
#include "motion_model_estimation/live/latency_stats.h"

namespace mme {

class IslandLink {
 public:
  /// Advertises and subscribes `options.migration_topic` on `nh`; `options.island_id` must be
  /// set. `estimator` outlives the link.
  IslandLink(ros::NodeHandle& nh, const IslandLinkOptions& options, OnlineEstimator* estimator);
  /// Called by the worker after each update: emigrates when a period has passed since the last
  /// emigration (a new population, after ~reset or a new model, starts the count again).
  /// Publishing only queues the message, so the worker never waits for a peer.
  void afterUpdate();
  IslandStats stats() const;
  const std::string& islandId() const { return options_.island_id; }

 private:
  void onMigrants(const motion_model_estimation::Migrants::ConstPtr& msg);

  const IslandLinkOptions options_;
  OnlineEstimator* const estimator_;
  ros::Publisher publisher_;
  ros::Subscriber subscriber_;
  uint32_t last_sent_generation_ = 0;  // the worker's (afterUpdate only)
  mutable std::mutex stats_mutex_;     // guards the members below
  IslandStats stats_;                  // sent, batches, late, max latency (the rest on demand)
  std::chrono::steady_clock::time_point last_sent_time_;
  LatencyStats latencies_ms_;          // peers' batches: send stamp -> arrival
  LatencyStats periods_ms_;            // this island's time between two emigrations
  std::map<std::string, double> last_stamp_s_;  // per peer, its previous batch's send stamp
};

}  // namespace mme

// OnlineEstimator's island-model side: its best individuals out, other islands' in. Incoming
// batches wait in a short queue that update() empties at its start, so the worker never waits
// for a peer and a peer never waits for the worker.
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/online/online_estimator.h"

namespace mme {

MigrantBatch OnlineEstimator::emigrants(int count) const {
  MigrantBatch batch;
  batch.seed = options_.es.seed;
  std::lock_guard<std::mutex> lock(update_mutex_);
  if (!es_ || es_->population().empty()) return batch;
  for (const Gene& g : es_->space().genes()) batch.parameter_names.push_back(g.ref.name);
  batch.generation = static_cast<uint32_t>(es_->generation());
  batch.individuals = es_->emigrants(count);
  for (Individual& ind : batch.individuals) ind.local_costs.clear();  // the receiver's own count
  batch.window_start_time_s = window_start_time_s_;
  batch.window_end_time_s = window_end_time_s_;
  return batch;
}

std::string OnlineEstimator::receiveMigrants(MigrantBatch batch) {
  std::vector<std::string> ours;
  uint64_t version = 0;
  {
    std::lock_guard<std::mutex> lock(model_mutex_);
    for (const ParamRef& ref : freeParameters(model_)) ours.push_back(ref.name);
    version = model_version_;
  }
  std::string why = parameterMismatch(ours, batch.parameter_names);
  if (why.empty()) why = malformedBatch(batch);
  if (why.empty() && !options_.estimate_values) why = "this island does not search (estimate_values false)";
  std::lock_guard<std::mutex> lock(migrants_mutex_);
  if (!why.empty()) {
    migration_.refused += batch.individuals.size();
    return why;
  }
  migration_.received += batch.individuals.size();
  migrant_queue_.push_back(QueuedBatch{std::move(batch), version});
  while (static_cast<int>(migrant_queue_.size()) > options_.migrant_queue_batches) {
    migration_.dropped += migrant_queue_.front().batch.individuals.size();
    migrant_queue_.pop_front();
  }
  return "";
}

std::string OnlineEstimator::refuseMigrants(uint64_t individuals, const std::string& why) {
  std::lock_guard<std::mutex> lock(migrants_mutex_);
  migration_.refused += individuals;
  return why;
}

MigrationCounters OnlineEstimator::migrationCounters() const {
  std::lock_guard<std::mutex> lock(migrants_mutex_);
  return migration_;
}

void OnlineEstimator::applyMigrants(uint64_t version) {
  std::deque<QueuedBatch> queue;
  {
    std::lock_guard<std::mutex> lock(migrants_mutex_);
    queue.swap(migrant_queue_);
  }
  if (queue.empty()) return;
  uint64_t dropped = 0, applied = 0, accepted = 0;
  for (QueuedBatch& q : queue) {
    const size_t n = q.batch.individuals.size();
    if (q.model_version != version || es_->population().empty()) {
      dropped += n;  // checked against a model since replaced
      continue;
    }
    try {
      accepted += static_cast<uint64_t>(es_->immigrate(std::move(q.batch.individuals)));
      applied += n;
    } catch (const InputError&) {
      dropped += n;  // sizes were checked on arrival: only a replaced model gets here
    }
  }
  std::lock_guard<std::mutex> lock(migrants_mutex_);
  migration_.dropped += dropped;
  migration_.applied += applied;
  migration_.accepted += accepted;
}

}  // namespace mme

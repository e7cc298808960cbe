// Individuals travelling between islands (estimators that search the same model on the same
// stream with their own seeds, island model): what a batch carries and the check that the
// receiver searches the same parameters in the same order. No ROS here; the node converts a
// batch to and from its message (msg/Migrants.msg).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "motion_model_estimation/identification/search/evolution_strategy.h"

namespace mme {

/// One emigration: the sender's best individuals with what the receiver needs to trust them.
struct MigrantBatch {
  std::string island_id;                     ///< the sender (the receiver ignores its own)
  uint64_t seed = 0;                         ///< the sender's search seed
  uint32_t generation = 0;                   ///< the sender's generation when they left
  std::vector<std::string> parameter_names;  ///< gene order, "<bond_type>/<param>"
  /// Genes and mutabilities in search space (parameter_space.h), cost [m^2] on the sender's
  /// window (not trusted: the receiver re-evaluates on its own). Best first.
  std::vector<Individual> individuals;
  double window_start_time_s = 0.0;  ///< [s] the sender's window when they left
  double window_end_time_s = 0.0;
};

/// Counters of the migrants an estimator was offered (individuals, not batches).
struct MigrationCounters {
  uint64_t received = 0;  ///< queued: their parameters matched
  uint64_t refused = 0;   ///< other parameters (names or order) or malformed
  uint64_t dropped = 0;   ///< pushed out of the full queue, or queued for a model since replaced
  uint64_t applied = 0;   ///< re-evaluated on this island's window
  uint64_t accepted = 0;  ///< entered the population (better than its worst)
};

/// "" when `theirs` names the same parameters as `ours` in the same order, else a sentence
/// naming the first that differs (its position and both names, or the one missing).
std::string parameterMismatch(const std::vector<std::string>& ours,
                              const std::vector<std::string>& theirs);

/// A message's flat arrays (msg/Migrants.msg: migrant i's parameter k at [i * n + k], n =
/// batch->parameter_names.size()) as batch->individuals. "" when the arrays hold `count`
/// migrants exactly (count x n genes and mutabilities, count costs), else why not, and
/// batch->individuals is left empty.
std::string unflattenMigrants(uint64_t count, const std::vector<double>& genes,
                              const std::vector<double>& mutabilities, const std::vector<double>& costs,
                              MigrantBatch* batch);

/// "" when every individual of `batch` has as many finite genes and mutabilities as the batch
/// has parameter names, else why not.
std::string malformedBatch(const MigrantBatch& batch);

}  // namespace mme

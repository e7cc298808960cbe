// The island model: several evolution strategies (islands) on the same cost, each with its own
// seed, stepping in lock-step and every few generations passing their best individuals
// (emigrants) to other islands, which let them compete for the places of their worst. Separate
// populations settle in different basins (e.g. different threshold intervals of conditional
// bonds) and migration spreads the best basin's individuals. Offline islands are threads of one
// process or, with IslandOptions::processes, processes of one host (island_processes.h), with
// the same result; islands on several hosts are the online node's (ROS).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "motion_model_estimation/core/cost.h"
#include "motion_model_estimation/core/thread_pool.h"
#include "motion_model_estimation/identification/search/evolution_strategy.h"
#include "motion_model_estimation/identification/search/island_processes.h"
#include "motion_model_estimation/identification/search/parameter_space.h"

namespace mme {

/// Where an island's emigrants go.
enum class MigrationTopology {
  kRing,       ///< to the next island only (island i -> i + 1, the last -> the first)
  kBroadcast,  ///< to every other island
};
/// "ring" | "broadcast" -> the enum; false when unknown.
bool parseMigrationTopology(const std::string& name, MigrationTopology* topology);
const char* migrationTopologyName(MigrationTopology topology);

struct IslandOptions {
  int islands = 1;                        ///< populations; 1 = the single evolution strategy
  int migration_period_generations = 10;  ///< generations between migrations
  int migrants = 2;                       ///< best individuals each island sends per migration
  /// Broadcast: on the conditional objects (docs/bench/islands.md) it put the thresholds in the
  /// truth's intervals at least as often as the ring, and with a few islands the receivers
  /// re-evaluate only a few migrants. The online islands (one topic) broadcast too.
  MigrationTopology topology = MigrationTopology::kBroadcast;
  /// Each island in a child process of its own instead of a thread (islands >= 2): the same
  /// result bit for bit; a process that dies ends the run with an error naming its island.
  bool processes = false;
};

/// Empty string when the options are usable, else the reason naming the option.
std::string validateOptions(const IslandOptions& options);

/// The seed of island `island` of a run seeded `run_seed`: island 0 keeps the run's seed (so one
/// island is the plain evolution strategy), the others' are drawn from (run seed, index).
uint64_t islandSeed(uint64_t run_seed, int island);

class IslandModel {
 public:
  /// `es.threads` is the run's thread count: with several islands they step on up to that many
  /// threads at once, each island evaluating its children on its share of the rest. The result
  /// does not depend on it.
  IslandModel(const ParameterSpace& space, const EsOptions& es, const IslandOptions& islands);

  /// The cost every island minimises (see EvolutionStrategy::setCost).
  void setCost(std::shared_ptr<const Cost> cost);
  /// Individuals every island's first population holds (see EvolutionStrategy::setSeeds).
  void setSeeds(const std::vector<std::vector<double>>& seeds);
  void setDeadline(std::chrono::steady_clock::time_point deadline);
  void setCancel(const std::atomic<bool>* cancel);

  /// One generation on every island (its refinement included when due), then, every
  /// migration_period_generations, a migration at the barrier in island order. With processes,
  /// the first call starts them; throws std::runtime_error naming an island whose process died.
  void step();

  int islandCount() const { return static_cast<int>(islands_.size()); }
  /// One island's strategy (threads only: with processes it lives in the child, and this throws
  /// std::logic_error once they have started).
  const EvolutionStrategy& island(int i) const;
  /// One island, e.g. to offer it an individual found elsewhere (EvolutionStrategy::offer).
  EvolutionStrategy& island(int i);
  /// The island holding the best individual (the lowest index among equal costs).
  int bestIsland() const;
  const Individual& best() const { return islandBest(bestIsland()); }
  std::vector<double> bestValues() const;
  /// Generations of each island (lock-step: all the same).
  int generation() const;
  /// Cost evaluations of all islands, the immigrants' re-evaluations included.
  uint64_t evaluations() const;
  /// Cost evaluations of island i.
  uint64_t islandEvaluations(int i) const;
  /// Refinements run by all islands.
  int refinements() const;
  /// How the best island's last refinement ended.
  RefineStatus lastRefineStatus() const;
  /// Migrations done (each moves every island's emigrants once).
  int migrations() const { return migrations_; }
  /// Immigrants island i let into its population so far.
  uint64_t immigrantsAccepted(int i) const { return accepted_[static_cast<size_t>(i)]; }

 private:
  void migrate();
  /// Island i's best individual (from its last report when it is a process).
  const Individual& islandBest(int i) const;
  /// Calls body(i) for every island, on the island pool when there is one.
  void forEachIsland(const std::function<void(size_t)>& body);

  IslandOptions options_;
  std::vector<std::unique_ptr<EvolutionStrategy>> islands_;
  std::unique_ptr<ThreadPool> pool_;  ///< steps islands side by side (null: one at a time)
  /// The islands' processes (options_.processes, started by the first step), and what each
  /// reported last; the strategies in islands_ are then only the children's starting points.
  std::unique_ptr<IslandProcesses> processes_;
  std::vector<IslandReport> reports_;
  std::vector<uint64_t> accepted_;
  int migrations_ = 0;
};

}  // namespace mme

// The offline island model's islands as child processes of one host: each island's evolution
// strategy steps in a process of its own (fork), and the parent carries the emigrants between
// them at the same lock-step barrier and in the same order as the threaded island model, so the
// result is the same bit for bit. Islands on several hosts are the online node's (ROS); this is
// the local form, with nothing shared between islands but what the parent sends.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "motion_model_estimation/identification/search/evolution_strategy.h"

namespace mme {

/// What the parent knows of an island between generations.
struct IslandReport {
  int generation = 0;
  uint64_t evaluations = 0;  ///< the island's cost evaluations so far
  int refinements = 0;
  RefineStatus last_refine_status = RefineStatus::kNotRun;
  Individual best;  ///< the island's best individual (genes, mutabilities, local costs, cost)
};

class IslandProcesses {
 public:
  /// Forks one child per strategy (set up: cost, seeds, deadline): child i keeps its copy of
  /// islands[i] and serves the parent's requests until the parent stops it or goes away. The
  /// caller must hold no thread of its own that a child would need. Throws std::runtime_error
  /// when a process cannot be started.
  explicit IslandProcesses(const std::vector<std::unique_ptr<EvolutionStrategy>>& islands);
  /// Stops the children and waits for them (after a failure: kills them first).
  ~IslandProcesses();
  IslandProcesses(const IslandProcesses&) = delete;
  IslandProcesses& operator=(const IslandProcesses&) = delete;

  /// One generation on every island, the islands side by side; their reports in island order.
  /// Throws std::runtime_error naming the island when a child died or failed.
  std::vector<IslandReport> step();
  /// Each island's `count` best individuals (EvolutionStrategy::emigrants), in island order.
  std::vector<std::vector<Individual>> emigrants(int count);
  /// arrivals[i] immigrate into island i (EvolutionStrategy::immigrate), side by side; returns
  /// how many entered each and refreshes `reports` (its best may have changed).
  std::vector<int> immigrate(const std::vector<std::vector<Individual>>& arrivals,
                             std::vector<IslandReport>* reports);

  /// The environment variable a test sets to an island's index to make that island's process
  /// kill itself (SIGKILL) at its second generation: a child dying mid-run.
  static constexpr const char* kTestDieVariable = "MME_TEST_ISLAND_DIES";

 private:
  struct Child {
    pid_t pid = -1;
    int fd = -1;  ///< the parent's end of the child's socket pair
  };
  /// Stops (after a failure: kills) and reaps every child.
  void stopChildren();
  /// Sends one request to every child (in island order), then reads every reply.
  void sendAll(const std::vector<std::string>& requests);
  std::string receiveFrom(size_t island);
  [[noreturn]] void fail(size_t island, const std::string& what);

  std::vector<Child> children_;
  bool failed_ = false;
};

}  // namespace mme

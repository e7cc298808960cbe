#include "motion_model_estimation/identification/search/island_model.h"

#include <algorithm>
#include <functional>
#include <stdexcept>

#include "motion_model_estimation/core/random.h"

namespace mme {

bool parseMigrationTopology(const std::string& name, MigrationTopology* topology) {
  if (name == "ring") *topology = MigrationTopology::kRing;
  else if (name == "broadcast") *topology = MigrationTopology::kBroadcast;
  else return false;
  return true;
}

const char* migrationTopologyName(MigrationTopology topology) {
  switch (topology) {
    case MigrationTopology::kRing: return "ring";
    case MigrationTopology::kBroadcast: return "broadcast";
  }
  return "?";
}

std::string validateOptions(const IslandOptions& o) {
  if (o.islands < 1) return "islands must be >= 1, got " + std::to_string(o.islands);
  if (o.migration_period_generations < 1)
    return "migration_period_generations must be >= 1, got " + std::to_string(o.migration_period_generations);
  if (o.migrants < 0) return "migrants must be >= 0, got " + std::to_string(o.migrants);
  return "";
}

uint64_t islandSeed(uint64_t run_seed, int island) {
  if (island == 0) return run_seed;
  // splitmix64 of (seed, index): neighbouring run seeds and indices give unrelated streams.
  return splitMix64Mix(run_seed + kSplitMix64Step * static_cast<uint64_t>(island + 1));
}

IslandModel::IslandModel(const ParameterSpace& space, const EsOptions& es, const IslandOptions& islands)
    : options_(islands) {
  const std::string bad = validateOptions(islands);
  if (!bad.empty()) throw std::invalid_argument("IslandModel: " + bad);
  const int n = islands.islands;
  // One island is the plain evolution strategy with the run's options (its threads included).
  // Several step side by side on up to es.threads threads, each evaluating its children on its
  // share of what is left; neither changes any island's result.
  EsOptions each = es;
  if (n > 1) {
    const int stepping = std::min(n, std::max(1, es.threads));
    each.threads = std::max(1, es.threads / n);
    // Processes step side by side by themselves; a pool's threads would not survive a fork.
    if (stepping > 1 && !islands.processes) pool_ = std::make_unique<ThreadPool>(stepping);
  }
  for (int i = 0; i < n; ++i) {
    each.seed = islandSeed(es.seed, i);
    islands_.push_back(std::make_unique<EvolutionStrategy>(space, each));
  }
  accepted_.assign(static_cast<size_t>(n), 0);
}

void IslandModel::setCost(std::shared_ptr<const Cost> cost) {
  for (auto& island : islands_) island->setCost(cost);
}

void IslandModel::setSeeds(const std::vector<std::vector<double>>& seeds) {
  for (auto& island : islands_) island->setSeeds(seeds);
}

void IslandModel::setDeadline(std::chrono::steady_clock::time_point deadline) {
  for (auto& island : islands_) island->setDeadline(deadline);
}

void IslandModel::setCancel(const std::atomic<bool>* cancel) {
  for (auto& island : islands_) island->setCancel(cancel);
}

void IslandModel::forEachIsland(const std::function<void(size_t)>& body) {
  if (pool_) {
    pool_->parallelFor(islands_.size(), body);
  } else {
    for (size_t i = 0; i < islands_.size(); ++i) body(i);
  }
}

void IslandModel::step() {
  if (options_.processes && islands_.size() > 1) {
    if (!processes_) processes_ = std::make_unique<IslandProcesses>(islands_);
    reports_ = processes_->step();
  } else {
    forEachIsland([this](size_t i) { islands_[i]->step(); });
  }
  if (islands_.size() > 1 && options_.migrants > 0 &&
      generation() % options_.migration_period_generations == 0)
    migrate();
}

void IslandModel::migrate() {
  // Every island's emigrants are taken before any island receives: what an island sends does
  // not depend on the order in which the others receive.
  const size_t n = islands_.size();
  std::vector<std::vector<Individual>> sent(n);
  if (processes_) {
    sent = processes_->emigrants(options_.migrants);
  } else {
    for (size_t i = 0; i < n; ++i) sent[i] = islands_[i]->emigrants(options_.migrants);
  }
  std::vector<std::vector<Individual>> arrivals(n);
  for (size_t i = 0; i < n; ++i) {
    if (options_.topology == MigrationTopology::kRing) {
      arrivals[i] = sent[(i + n - 1) % n];
    } else {
      for (size_t j = 0; j < n; ++j)
        if (j != i) arrivals[i].insert(arrivals[i].end(), sent[j].begin(), sent[j].end());
    }
  }
  std::vector<int> entered(n, 0);
  if (processes_) {
    entered = processes_->immigrate(arrivals, &reports_);
  } else {
    forEachIsland([&](size_t i) { entered[i] = islands_[i]->immigrate(std::move(arrivals[i])); });
  }
  for (size_t i = 0; i < n; ++i) accepted_[i] += static_cast<uint64_t>(entered[i]);
  ++migrations_;
}

const EvolutionStrategy& IslandModel::island(int i) const {
  if (processes_) throw std::logic_error("IslandModel::island: the islands are processes");
  return *islands_[static_cast<size_t>(i)];
}

EvolutionStrategy& IslandModel::island(int i) {
  if (processes_) throw std::logic_error("IslandModel::island: the islands are processes");
  return *islands_[static_cast<size_t>(i)];
}

const Individual& IslandModel::islandBest(int i) const {
  return processes_ ? reports_[static_cast<size_t>(i)].best : island(i).best();
}

int IslandModel::bestIsland() const {
  int best = 0;
  for (int i = 1; i < islandCount(); ++i)
    if (islandBest(i).cost < islandBest(best).cost) best = i;
  return best;
}

std::vector<double> IslandModel::bestValues() const {
  return islands_.front()->space().toPhysical(best().genes);
}

int IslandModel::generation() const {
  return processes_ ? reports_.front().generation : islands_.front()->generation();
}

uint64_t IslandModel::islandEvaluations(int i) const {
  return processes_ ? reports_[static_cast<size_t>(i)].evaluations : island(i).evaluations();
}

uint64_t IslandModel::evaluations() const {
  uint64_t total = 0;
  for (int i = 0; i < islandCount(); ++i) total += islandEvaluations(i);
  return total;
}

int IslandModel::refinements() const {
  int total = 0;
  for (int i = 0; i < islandCount(); ++i)
    total += processes_ ? reports_[static_cast<size_t>(i)].refinements : island(i).refinements();
  return total;
}

RefineStatus IslandModel::lastRefineStatus() const {
  const int i = bestIsland();
  return processes_ ? reports_[static_cast<size_t>(i)].last_refine_status : island(i).lastRefineStatus();
}

}  // namespace mme

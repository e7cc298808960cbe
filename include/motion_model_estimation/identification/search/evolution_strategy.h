// The paper's evolution strategy on local costs (Stanciulescu & Louchet, section 3): self-adaptive
// mutabilities, four mutation types, local-cost-biased multi-parent crossover, elitist biased
// selection and a periodic local refinement (refiner.h). The caller owns the loop (step()), and the
// cost function can be swapped for a newer window while the population lives on (warm start).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "motion_model_estimation/core/cost.h"
#include "motion_model_estimation/core/random.h"
#include "motion_model_estimation/core/thread_pool.h"
#include "motion_model_estimation/identification/search/parameter_space.h"
#include "motion_model_estimation/identification/search/preset.h"
#include "motion_model_estimation/identification/search/refiner.h"

namespace mme {

struct EsOptions {
  int population = 100;          ///< individuals kept per generation
  int offspring = 100;           ///< children created per generation
  uint64_t seed = 1;             ///< the only source of randomness
  int threads = 1;               ///< threads evaluating children (result independent of it)
  // Share of children made by each operator (normalised): entirely new, partly new (one bond
  // type redrawn), mutability-scaled replica, partial replica of one bond type chosen by local
  // cost, multi-parent crossover.
  double share_new = 0.04;
  double share_partly_new = 0.06;
  double share_replica = 0.30;
  double share_partial_replica = 0.30;
  double share_crossover = 0.30;
  int tournament_size = 3;       ///< bias toward good (global or local) costs when choosing parents
  double elite_fraction = 0.2;   ///< best share of the pool always kept
  double initial_mutability = 0.05;  ///< initial mutation std as a share of each gene's range
  // The refinement of the best individual (refiner.h). The defaults are the measured best
  // (Levenberg-Marquardt from generation 5, every 5: docs/bench); Preset::kPaper gives the
  // paper's (BOBYQA from generation 400, every 100).
  RefineAlgorithm refine_algorithm = RefineAlgorithm::kLevenbergMarquardt;
  int refine_start_generation = 5;    ///< first generation with a refinement
  int refine_period = 5;              ///< generations between refinements (0 = never)
  /// A refinement stops when its last refine_window_evaluations evaluations (0 = 30 x genes
  /// + 100; LM: 3 Jacobians) did not divide the best cost by refine_stall_factor (0: after one
  /// window)...
  int refine_window_evaluations = 0;
  double refine_stall_factor = 1.01;
  int refine_max_evaluations = 0;     ///< ...or after this many (0 = 40 windows)
  /// Evaluations a refinement may bring the run's total to (0 = no limit): lets a caller with
  /// an evaluation budget keep a long refinement inside it.
  uint64_t refine_total_evaluation_cap = 0;
  /// The refinement moves only genes with a useful slope (Gene::smooth): the thresholds of
  /// conditional bonds stay with the evolution strategy.
  bool refine_smooth_genes_only = true;
};

/// Empty string when the options are usable, else the reason naming the option.
std::string validateOptions(const EsOptions& options);
/// The options of a preset: kDefault = the defaults above (the measured best), kPaper = the
/// paper's schedule (BOBYQA from generation 400, every 100, every gene refined).
EsOptions esOptionsFor(Preset preset);

struct Individual {
  std::vector<double> genes;        ///< search-space values (see ParameterSpace)
  std::vector<double> mutability;   ///< self-adaptive mutation std per gene (search space)
  std::vector<double> local_costs;  ///< per particle [m^2], from the last evaluation
  double cost = std::numeric_limits<double>::infinity();  ///< global cost [m^2]
};

/// Which operator made a child (for statistics and tests).
enum class Operator {
  kInitial, kNew, kPartlyNew, kReplica, kPartialReplica, kCrossover, kRefine,
  kImmigrant,  ///< arrived from another island (immigrate())
  kCount       ///< number of operators (size of the per-operator counters)
};

class EvolutionStrategy {
 public:
  EvolutionStrategy(ParameterSpace space, const EsOptions& options);

  /// Sets the cost to minimise. With a live population this re-evaluates it (warm start when
  /// the window slides). The cost's free parameters must match the space's genes.
  void setCost(std::shared_ptr<const Cost> cost);
  /// One generation (the first call also draws the initial population).
  void step();
  /// Forgets the population; the next step() starts from scratch.
  void reset();
  /// Makes the next initial population start at `genes` (one individual exactly there, the
  /// others around it with std spread_fraction x each gene's range): resuming a saved model.
  void setInitialGuess(const std::vector<double>& genes, double spread_fraction);
  /// Individuals the next initial population holds besides the paper's random draws (e.g. the
  /// equation-error start, or the best of a previous search): each set of genes (reflected into
  /// the bounds) replaces one random draw.
  void setSeeds(std::vector<std::vector<double>> seeds);
  /// Replaces the population (evaluated individuals: cost and local costs set), e.g. to resume
  /// from a saved model; also used by tests to set up operator situations.
  void setPopulation(std::vector<Individual> population);
  /// An individual found elsewhere (e.g. a refinement run beside the generations on an earlier
  /// window): evaluated on the current cost, it replaces the worst individual when better than
  /// it. Returns true when it became the best.
  bool offer(const std::vector<double>& genes);
  /// Island model: copies of the `count` best individuals (best first; fewer when the
  /// population is smaller, none before the first step), to send to other islands.
  std::vector<Individual> emigrants(int count) const;
  /// Island model: individuals from another island (genes and mutabilities in this space's
  /// order; their cost is the sender's and is not trusted). Each is reflected into the bounds,
  /// re-evaluated on this strategy's cost and takes the place of the worst individual when it is
  /// better than it, so the elite never gives way to a worse one. Copies are let in: the same
  /// best sent by several islands (or back to its own) takes several places, which raises its
  /// share of the parents; skipping copies slowed the conditional objects' searches
  /// (docs/benchmarks.md, "Copies among the immigrants"). Returns how many entered.
  /// Throws InputError when an individual's genes or mutabilities do not match the space.
  /// Ignored (returns 0) before the first step.
  int immigrate(std::vector<Individual> arrivals);
  /// A refinement running past this time stops there (keeping its best point); default: none.
  void setDeadline(std::chrono::steady_clock::time_point deadline) { deadline_ = deadline; }
  /// A refinement stops (keeping its best point) once `cancel` is raised; default: none.
  void setCancel(const std::atomic<bool>* cancel) { cancel_ = cancel; }

  const Individual& best() const;
  std::vector<double> bestValues() const;  ///< physical values of the best individual
  const std::vector<Individual>& population() const { return population_; }
  const ParameterSpace& space() const { return space_; }
  const EsOptions& options() const { return options_; }
  int generation() const { return generation_; }
  uint64_t evaluations() const { return evaluations_; }
  /// Children made per operator so far (index = Operator).
  const std::vector<uint64_t>& operatorCounts() const { return operator_counts_; }
  /// Children of each operator that entered the population (survived selection).
  const std::vector<uint64_t>& operatorSuccesses() const { return operator_successes_; }
  /// The settings of a refinement of the best individual now (evaluation budget with the caps
  /// applied, stall window, deadline, the genes it may move).
  RefineSettings refineSettings() const;
  /// How the last refinement ended (kNotRun before the first) and how many have run.
  RefineStatus lastRefineStatus() const { return last_refine_status_; }
  int refinements() const { return refinements_; }

  // Building blocks, public for tests (these draw from the strategy's own stream).
  Individual makeRandom() { return makeRandom(random_); }
  Individual crossover() { return crossover(random_); }
  /// Index of a parent chosen by tournament on the sum of local costs at `sites`
  /// (all particles when empty = global cost).
  int chooseParent(const std::vector<int>& sites) { return chooseParent(sites, random_); }
  void evaluate(std::vector<Individual>* individuals);

 private:
  // The operators only read the population: one generation's children are made (each from its
  // own stream, seeded from the strategy's) and evaluated in parallel.
  Individual makeRandom(FastRandom& rng) const;
  Individual crossover(FastRandom& rng) const;
  int chooseParent(const std::vector<int>& sites, FastRandom& rng) const;
  int chooseParentAt(int site, FastRandom& rng) const;
  double initialMutability(size_t k) const;
  Individual makeChild(Operator* op, FastRandom& rng) const;
  void mutateGenes(Individual* child, const std::vector<int>& genes, FastRandom& rng) const;
  void evaluateOne(Individual* individual) const;
  /// The pool of options_.threads threads, started on first use (null for one thread).
  ThreadPool* threadPool();
  void forEach(size_t count, const std::function<void(size_t)>& body);
  void select(std::vector<Individual>* children, const std::vector<Operator>& ops);
  void refineBest();
  /// Index of the first individual of lowest cost.
  int lowestCostIndex() const;
  /// Puts `candidate` (evaluated) in the place of the worst individual when it costs less than
  /// it, the best index following; returns whether it entered.
  bool replaceWorstIfBetter(Individual candidate);
  uint64_t refineWindow() const;           ///< evaluations per progress window
  uint64_t refineEvaluationLimit() const;  ///< a refinement's evaluations, caps applied
  void initialise();

  ParameterSpace space_;
  EsOptions options_;
  std::shared_ptr<const Cost> cost_;
  FastRandom random_;
  std::vector<Individual> population_;
  int best_index_ = 0;
  int generation_ = 0;
  uint64_t evaluations_ = 0;
  std::vector<uint64_t> operator_counts_;
  std::vector<uint64_t> operator_successes_;
  std::vector<double> initial_guess_;
  std::vector<std::vector<double>> seeds_;
  double initial_guess_spread_ = 0.0;
  std::unique_ptr<ThreadPool> pool_;  ///< options_.threads - 1 workers (none for 1 thread)
  std::unique_ptr<Refiner> refiner_;  ///< made from options_.refine_algorithm
  RefineStatus last_refine_status_ = RefineStatus::kNotRun;
  int refinements_ = 0;
  /// Threshold search / smooth refinement alternations per refinement at most.
  static constexpr int kThresholdRounds = 3;
  /// Refinements stop here (setDeadline); default: never.
  std::chrono::steady_clock::time_point deadline_ = std::chrono::steady_clock::time_point::max();
  const std::atomic<bool>* cancel_ = nullptr;  ///< setCancel
};

}  // namespace mme

#include "motion_model_estimation/identification/search/evolution_strategy.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <thread>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/search/threshold_search.h"

namespace mme {

std::string validateOptions(const EsOptions& o) {
  if (o.population < 2) return "population must be >= 2";
  if (o.offspring < 1) return "offspring must be >= 1";
  if (o.threads < 1) return "threads must be >= 1";
  const double shares[] = {o.share_new, o.share_partly_new, o.share_replica,
                           o.share_partial_replica, o.share_crossover};
  double total = 0.0;
  for (double s : shares) {
    if (!(s >= 0.0) || !std::isfinite(s)) return "operator shares must be >= 0";
    total += s;
  }
  if (!(total > 0.0)) return "at least one operator share must be > 0";
  if (o.tournament_size < 1) return "tournament_size must be >= 1";
  if (!(o.elite_fraction >= 0.0 && o.elite_fraction <= 1.0))
    return "elite_fraction must be in [0, 1]";
  if (!(o.initial_mutability > 0.0 && o.initial_mutability <= 1.0))
    return "initial_mutability must be in (0, 1]";
  if (o.refine_start_generation < 0 || o.refine_period < 0 || o.refine_max_evaluations < 0 ||
      o.refine_window_evaluations < 0)
    return "refinement settings must be >= 0";
  if (!(o.refine_stall_factor == 0.0 || o.refine_stall_factor > 1.0) ||
      !std::isfinite(o.refine_stall_factor))
    return "refine_stall_factor must be 0 (one window) or > 1";
  return "";
}

EsOptions esOptionsFor(Preset preset) {
  EsOptions o;
  switch (preset) {
    case Preset::kDefault:
      break;
    case Preset::kPaper:
      o.refine_algorithm = RefineAlgorithm::kBobyqa;
      o.refine_start_generation = 400;
      o.refine_period = 100;
      o.refine_smooth_genes_only = false;
      break;
  }
  return o;
}

EvolutionStrategy::EvolutionStrategy(ParameterSpace space, const EsOptions& options)
    : space_(std::move(space)), options_(options), random_(options.seed),
      refiner_(Refiner::Create(options.refine_algorithm)) {
  const std::string bad = validateOptions(options_);
  if (!bad.empty()) throw InputError("evolution strategy: " + bad);
  if (space_.size() == 0) throw InputError("the model has no free parameter to identify");
  operator_counts_.assign(static_cast<size_t>(Operator::kCount), 0);
  operator_successes_.assign(static_cast<size_t>(Operator::kCount), 0);
}

void EvolutionStrategy::setCost(std::shared_ptr<const Cost> cost) {
  if (cost->freeParameters().size() != space_.size())
    throw InputError("cost function and parameter space disagree on the free parameters");
  cost_ = std::move(cost);
  if (!population_.empty()) {
    evaluate(&population_);
    best_index_ = lowestCostIndex();
  }
}

void EvolutionStrategy::reset() {
  population_.clear();
  generation_ = 0;
  best_index_ = 0;
}

void EvolutionStrategy::setPopulation(std::vector<Individual> population) {
  population_ = std::move(population);
  best_index_ = 0;
  for (size_t i = 1; i < population_.size(); ++i)
    if (population_[i].cost < population_[best_index_].cost) best_index_ = static_cast<int>(i);
}

const Individual& EvolutionStrategy::best() const {
  if (population_.empty()) throw std::logic_error("EvolutionStrategy::best before step");
  return population_[best_index_];
}

std::vector<double> EvolutionStrategy::bestValues() const {
  return space_.toPhysical(best().genes);
}

double EvolutionStrategy::initialMutability(size_t k) const {
  // A share of the range, but never more than the initial distribution's spread: a gene the
  // data pin down (a rest length, a clamp length) is not first thrown across its range.
  const Gene& g = space_.gene(k);
  return std::min(options_.initial_mutability * (g.upper - g.lower), g.init_spread);
}

Individual EvolutionStrategy::makeRandom(FastRandom& rng) const {
  Individual ind;
  const size_t n = space_.size();
  ind.genes.resize(n);
  ind.mutability.resize(n);
  for (size_t k = 0; k < n; ++k) {
    ind.genes[k] = space_.sampleInitial(k, rng);
    ind.mutability[k] = initialMutability(k);
  }
  return ind;
}

ThreadPool* EvolutionStrategy::threadPool() {
  if (options_.threads > 1 && !pool_) pool_ = std::make_unique<ThreadPool>(options_.threads);
  return pool_.get();
}

void EvolutionStrategy::forEach(size_t count, const std::function<void(size_t)>& body) {
  if (ThreadPool* pool = threadPool()) {
    pool->parallelFor(count, body);
  } else {
    for (size_t i = 0; i < count; ++i) body(i);
  }
}

void EvolutionStrategy::evaluateOne(Individual* ind) const {
  ind->cost = cost_->evaluate(space_.toPhysical(ind->genes), &ind->local_costs);
  if (!std::isfinite(ind->cost)) ind->cost = std::numeric_limits<double>::infinity();
}

void EvolutionStrategy::evaluate(std::vector<Individual>* individuals) {
  if (!cost_) throw std::logic_error("EvolutionStrategy: no cost function set");
  // Each individual's cost depends only on its genes, so which thread evaluates it cannot
  // change the result: determinism holds for any thread count.
  forEach(individuals->size(), [this, individuals](size_t i) { evaluateOne(&(*individuals)[i]); });
  evaluations_ += individuals->size();
}

namespace {
/// Tournament of `rounds` draws among `size` individuals: the one with the lowest score(i).
template <class Score>
int tournament(int size, int rounds, FastRandom& rng, const Score& score) {
  int best = rng.index(size);
  double best_score = score(best);
  for (int k = 1; k < rounds; ++k) {
    const int c = rng.index(size);
    const double s = score(c);
    if (s < best_score) { best = c; best_score = s; }
  }
  return best;
}
}  // namespace

int EvolutionStrategy::chooseParent(const std::vector<int>& sites, FastRandom& rng) const {
  return tournament(static_cast<int>(population_.size()), options_.tournament_size, rng,
                    [&](int i) {
                      if (sites.empty()) return population_[i].cost;
                      double s = 0.0;
                      for (int p : sites) s += population_[i].local_costs[p];
                      return s;
                    });
}

int EvolutionStrategy::chooseParentAt(int site, FastRandom& rng) const {
  // chooseParent({site}) without building a vector: the crossover calls it once per site.
  return tournament(static_cast<int>(population_.size()), options_.tournament_size, rng,
                    [&](int i) { return population_[i].local_costs[site]; });
}

void EvolutionStrategy::mutateGenes(Individual* child, const std::vector<int>& genes,
                                    FastRandom& rng) const {
  // Self-adaptation (Schwefel): the mutability moves log-normally, then the gene moves with it;
  // mutabilities that produced good children survive with them.
  const double n = static_cast<double>(genes.size());
  const double tau_global = 1.0 / std::sqrt(2.0 * n);
  const double tau_local = 1.0 / std::sqrt(2.0 * std::sqrt(n));
  const double common = tau_global * rng.normal();
  for (int k : genes) {
    const Gene& g = space_.gene(k);
    const double range = g.upper - g.lower;
    double sigma = child->mutability[k] * std::exp(common + tau_local * rng.normal());
    sigma = std::min(std::max(sigma, 1e-15 * range), 0.5 * range);
    child->mutability[k] = sigma;
    child->genes[k] = space_.reflect(k, child->genes[k] + sigma * rng.normal());
  }
}

Individual EvolutionStrategy::crossover(FastRandom& rng) const {
  // Per bond type: one parent per site (particle at an extremity of a bond of that type), each
  // chosen with a bias toward a good local cost at that site; the type's genes become the mean
  // of the chosen parents' genes.
  Individual child = population_[chooseParent({}, rng)];
  std::vector<double> sum, sum_mut;
  for (int type : space_.typesWithGenes()) {
    const std::vector<int>& genes = space_.genesOfType()[type];
    const std::vector<int>& sites = space_.sitesOfType()[type];
    if (sites.empty()) continue;
    sum.assign(genes.size(), 0.0);
    sum_mut.assign(genes.size(), 0.0);
    for (int site : sites) {
      const Individual& parent = population_[chooseParentAt(site, rng)];
      for (size_t j = 0; j < genes.size(); ++j) {
        sum[j] += parent.genes[genes[j]];
        sum_mut[j] += parent.mutability[genes[j]];
      }
    }
    const double parents = static_cast<double>(sites.size());
    for (size_t j = 0; j < genes.size(); ++j) {
      child.genes[genes[j]] = sum[j] / parents;
      child.mutability[genes[j]] = sum_mut[j] / parents;
    }
  }
  return child;
}

Individual EvolutionStrategy::makeChild(Operator* op, FastRandom& rng) const {
  const double shares[] = {options_.share_new, options_.share_partly_new, options_.share_replica,
                           options_.share_partial_replica, options_.share_crossover};
  const double total = std::accumulate(std::begin(shares), std::end(shares), 0.0);
  double r = rng.uniform() * total;
  int pick = 0;
  while (pick < 4 && r >= shares[pick]) r -= shares[pick++];
  const std::vector<int>& types = space_.typesWithGenes();
  switch (pick) {
    case 0: {
      *op = Operator::kNew;
      return makeRandom(rng);
    }
    case 1: {  // partly new: one bond type's genes redrawn from the initial distribution
      *op = Operator::kPartlyNew;
      Individual child = population_[chooseParent({}, rng)];
      const int type = types[rng.index(static_cast<int>(types.size()))];
      for (int k : space_.genesOfType()[type]) {
        child.genes[k] = space_.sampleInitial(k, rng);
        child.mutability[k] = initialMutability(k);
      }
      return child;
    }
    case 2: {  // replica of a globally good individual, every gene mutated
      *op = Operator::kReplica;
      Individual child = population_[chooseParent({}, rng)];
      std::vector<int> all(space_.size());
      std::iota(all.begin(), all.end(), 0);
      mutateGenes(&child, all, rng);
      return child;
    }
    case 3: {  // partial replica: one bond type mutated, parent good at that type's sites
      *op = Operator::kPartialReplica;
      const int type = types[rng.index(static_cast<int>(types.size()))];
      Individual child = population_[chooseParent(space_.sitesOfType()[type], rng)];
      mutateGenes(&child, space_.genesOfType()[type], rng);
      return child;
    }
    default: {
      *op = Operator::kCrossover;
      return crossover(rng);
    }
  }
}

void EvolutionStrategy::setInitialGuess(const std::vector<double>& genes, double spread_fraction) {
  if (genes.size() != space_.size())
    throw InputError("initial guess has " + std::to_string(genes.size()) + " values, expected " +
                     std::to_string(space_.size()));
  initial_guess_ = genes;
  initial_guess_spread_ = spread_fraction;
}

void EvolutionStrategy::setSeeds(std::vector<std::vector<double>> seeds) {
  for (const std::vector<double>& genes : seeds)
    if (genes.size() != space_.size())
      throw InputError("seed has " + std::to_string(genes.size()) + " genes, expected " +
                       std::to_string(space_.size()));
  seeds_ = std::move(seeds);
}

void EvolutionStrategy::initialise() {
  population_.clear();
  for (int i = 0; i < options_.population; ++i) {
    Individual ind = makeRandom();
    if (static_cast<size_t>(i) < seeds_.size()) {
      for (size_t k = 0; k < space_.size(); ++k) ind.genes[k] = space_.reflect(k, seeds_[i][k]);
    }
    if (!initial_guess_.empty()) {
      for (size_t k = 0; k < space_.size(); ++k) {
        const Gene& g = space_.gene(k);
        const double sigma = initial_guess_spread_ * (g.upper - g.lower);
        ind.genes[k] = space_.reflect(k, initial_guess_[k] + (i == 0 ? 0.0 : sigma * random_.normal()));
        ind.mutability[k] = std::max(sigma, 1e-12 * (g.upper - g.lower));
      }
    }
    population_.push_back(std::move(ind));
  }
  evaluate(&population_);
  operator_counts_[static_cast<int>(Operator::kInitial)] += population_.size();
}

void EvolutionStrategy::select(std::vector<Individual>* children,
                               const std::vector<Operator>& ops) {
  // Elitist, biased random choice (the paper): the best share of parents + children is kept,
  // the rest of the places go to binary-tournament winners among the others.
  const size_t num_parents = population_.size();
  std::vector<Individual> pool = std::move(population_);
  std::vector<int> origin(pool.size(), -1);
  for (size_t c = 0; c < children->size(); ++c) {
    pool.push_back(std::move((*children)[c]));
    origin.push_back(static_cast<int>(ops[c]));
  }
  std::vector<int> order(pool.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&pool](int a, int b) { return pool[a].cost < pool[b].cost; });
  const size_t target = static_cast<size_t>(options_.population);
  const size_t elite = std::min(target, std::max<size_t>(
      1, static_cast<size_t>(std::ceil(options_.elite_fraction * target))));
  std::vector<int> chosen(order.begin(), order.begin() + elite);
  std::vector<int> rest(order.begin() + elite, order.end());
  while (chosen.size() < target && !rest.empty()) {
    const int a = random_.index(static_cast<int>(rest.size()));
    const int b = random_.index(static_cast<int>(rest.size()));
    const int w = pool[rest[a]].cost <= pool[rest[b]].cost ? a : b;
    chosen.push_back(rest[w]);
    rest[w] = rest.back();
    rest.pop_back();
  }
  population_.clear();
  for (int idx : chosen) {
    if (origin[idx] >= 0) ++operator_successes_[origin[idx]];
    population_.push_back(std::move(pool[idx]));
  }
  (void)num_parents;
  best_index_ = 0;  // chosen[0] is the best of the pool
}

uint64_t EvolutionStrategy::refineWindow() const {
  return options_.refine_window_evaluations > 0
             ? static_cast<uint64_t>(options_.refine_window_evaluations)
             : 30 * space_.size() + 100;
}

uint64_t EvolutionStrategy::refineEvaluationLimit() const {
  uint64_t max_evaluations = options_.refine_max_evaluations > 0
                                 ? static_cast<uint64_t>(options_.refine_max_evaluations)
                                 : 40 * refineWindow();
  if (options_.refine_total_evaluation_cap > 0) {
    // +1: the refined point's re-evaluation.
    const uint64_t left = options_.refine_total_evaluation_cap > evaluations_ + 1
                              ? options_.refine_total_evaluation_cap - evaluations_ - 1 : 0;
    max_evaluations = std::min(max_evaluations, left);
  }
  return max_evaluations;
}

RefineSettings EvolutionStrategy::refineSettings() const {
  RefineSettings settings;
  settings.max_evaluations = refineEvaluationLimit();
  settings.window_evaluations = refineWindow();
  settings.stall_factor = options_.refine_stall_factor;
  settings.deadline = deadline_;
  settings.cancel = cancel_;
  if (options_.refine_smooth_genes_only) {
    settings.movable.assign(space_.size(), 0);
    for (size_t k = 0; k < space_.size(); ++k) settings.movable[k] = space_.gene(k).smooth;
  }
  return settings;
}

void EvolutionStrategy::refineBest() {
  // A local search from the best individual, inside the bounds; its result joins the
  // population only when it improves the best.
  const size_t n = space_.size();
  const Individual& start = best();
  const RefineSettings settings = refineSettings();
  RefineStart from;
  from.genes = start.genes;
  from.cost = start.cost;
  from.steps = start.mutability;
  const RefineResult result =
      refineAlternating(*refiner_, *cost_, space_, from, settings, threadPool(), kThresholdRounds);
  last_refine_status_ = result.status;
  evaluations_ += result.evaluations;
  if (result.evaluations == 0) return;
  ++refinements_;
  ++operator_counts_[static_cast<int>(Operator::kRefine)];
  Individual refined = start;
  for (size_t k = 0; k < n; ++k)
    refined.genes[k] = std::min(std::max(result.genes[k], space_.gene(k).lower), space_.gene(k).upper);
  std::vector<Individual> one{refined};
  evaluate(&one);
  if (one[0].cost < start.cost) {
    ++operator_successes_[static_cast<int>(Operator::kRefine)];
    // In the worst individual's place, so the population keeps the old best too.
    replaceWorstIfBetter(std::move(one[0]));
  }
}

bool EvolutionStrategy::offer(const std::vector<double>& genes) {
  if (population_.empty() || genes.size() != space_.size()) return false;
  Individual candidate = best();
  for (size_t k = 0; k < space_.size(); ++k) candidate.genes[k] = space_.reflect(k, genes[k]);
  std::vector<Individual> one{candidate};
  evaluate(&one);
  ++operator_counts_[static_cast<int>(Operator::kRefine)];
  const bool new_best = one[0].cost < best().cost;
  if (!replaceWorstIfBetter(std::move(one[0]))) return false;
  ++operator_successes_[static_cast<int>(Operator::kRefine)];
  return new_best;
}

int EvolutionStrategy::lowestCostIndex() const {
  return static_cast<int>(std::min_element(population_.begin(), population_.end(),
                                           [](const Individual& a, const Individual& b) {
                                             return a.cost < b.cost;
                                           }) - population_.begin());
}

bool EvolutionStrategy::replaceWorstIfBetter(Individual candidate) {
  auto worst = std::max_element(population_.begin(), population_.end(),
                                [](const Individual& a, const Individual& b) { return a.cost < b.cost; });
  if (!(candidate.cost < worst->cost)) return false;
  const bool new_best = candidate.cost < best().cost;
  *worst = std::move(candidate);
  if (new_best) best_index_ = static_cast<int>(worst - population_.begin());
  return true;
}

std::vector<Individual> EvolutionStrategy::emigrants(int count) const {
  std::vector<int> order(population_.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [this](int a, int b) {
    return population_[a].cost < population_[b].cost;
  });
  const size_t n = std::min(order.size(), static_cast<size_t>(std::max(count, 0)));
  std::vector<Individual> out;
  out.reserve(n);
  for (size_t i = 0; i < n; ++i) out.push_back(population_[order[i]]);
  return out;
}

int EvolutionStrategy::immigrate(std::vector<Individual> arrivals) {
  const size_t n = space_.size();
  for (const Individual& arrival : arrivals) {
    if (arrival.genes.size() != n || arrival.mutability.size() != n)
      throw InputError("immigrant has " + std::to_string(arrival.genes.size()) + " genes and " +
                       std::to_string(arrival.mutability.size()) + " mutabilities; the space has " +
                       std::to_string(n));
  }
  if (population_.empty() || arrivals.empty()) return 0;
  for (Individual& arrival : arrivals) {
    for (size_t k = 0; k < n; ++k) {
      const Gene& g = space_.gene(k);
      arrival.genes[k] = space_.reflect(k, arrival.genes[k]);
      const double m = arrival.mutability[k];
      arrival.mutability[k] = std::isfinite(m) && m > 0.0 ? std::min(m, g.upper - g.lower)
                                                          : initialMutability(k);
    }
  }
  evaluate(&arrivals);
  operator_counts_[static_cast<int>(Operator::kImmigrant)] += arrivals.size();
  int entered = 0;
  for (Individual& arrival : arrivals)
    if (replaceWorstIfBetter(std::move(arrival))) ++entered;
  operator_successes_[static_cast<int>(Operator::kImmigrant)] += entered;
  best_index_ = lowestCostIndex();  // the first of equally good ones, whatever the arrival order
  return entered;
}

void EvolutionStrategy::step() {
  if (!cost_) throw std::logic_error("EvolutionStrategy::step without a cost function");
  if (population_.empty()) {
    initialise();
    std::vector<Individual> none;
    select(&none, {});
  }
  // Each child has its own stream (seeds drawn in order from the strategy's), so making and
  // evaluating children on any number of threads gives the same children.
  const size_t count = static_cast<size_t>(options_.offspring);
  std::vector<uint64_t> seeds(count);
  for (uint64_t& seed : seeds) seed = random_.next();
  std::vector<Individual> children(count);
  std::vector<Operator> ops(count);
  forEach(count, [&](size_t c) {
    FastRandom rng(seeds[c]);
    children[c] = makeChild(&ops[c], rng);
    evaluateOne(&children[c]);
  });
  evaluations_ += count;
  for (Operator op : ops) ++operator_counts_[static_cast<int>(op)];
  select(&children, ops);
  ++generation_;
  if (options_.refine_period > 0 && generation_ >= options_.refine_start_generation &&
      (generation_ - options_.refine_start_generation) % options_.refine_period == 0)
    refineBest();
}

}  // namespace mme

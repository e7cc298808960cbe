// The evolution strategy: convergence on a small scene, bounds, the local-cost bias of the
// crossover, determinism across runs and thread counts, warm start on a new window.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <algorithm>
#include <memory>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/search/evolution_strategy.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/scenes/scenes.h"
#include "test_helpers.h"

namespace {

using mme::test::maxRelativeError;
using mme::test::smallObject;
using mme::test::withoutValues;

using Fixture = mme::test::SmallObjectFixture;

TEST(EvolutionStrategy, ConvergesOnASmallObjectWithinTheBudget) {
  Fixture f;
  mme::IdentifyOptions options;
  options.generations = 300;
  options.es.population = 40;
  options.es.offspring = 40;
  options.es.refine_start_generation = 150;
  options.es.refine_period = 50;
  options.estimate_std = false;
  const mme::IdentifyResult r = mme::identifyModel(f.search, f.data, options);
  EXPECT_LT(maxRelativeError(r.values, f.true_values), 1e-4) << "cost " << r.global_cost;
}

// Table I of the paper in small: provot_cloth's 20 parameters (Provot clamps on two types) from
// its single equilibrium frame. Needs the clamp-length coordinate of max_elongation (with tau
// itself the population settles with the clamp off) and a refinement that runs while it pays
// (the clamp's stiffness next to the weak cubic terms makes the cost ill-conditioned).
TEST(EvolutionStrategy, IdentifiesProvotClothFromItsSingleEquilibriumFrame) {
  const mme::Scene scene = mme::makeScene("provot_cloth");
  ASSERT_EQ(scene.reference_data.numFrames(), 1);
  mme::IdentifyOptions options;
  options.generations = 50;
  options.es.refine_start_generation = 25;
  options.es.refine_period = 25;
  options.estimate_std = false;
  const mme::IdentifyResult r =
      mme::identifyModel(withoutValues(scene.model), scene.reference_data, options);
  const std::vector<double> truth = mme::getValues(scene.model, mme::freeParameters(scene.model));
  ASSERT_EQ(r.values.size(), 20u);
  EXPECT_LT(maxRelativeError(r.values, truth), 0.005) << "cost " << r.global_cost;
}

// A refinement may run for many windows; an evaluation cap or a deadline keeps it inside a
// caller's budget.
TEST(EvolutionStrategy, RefinementStaysInsideTheEvaluationCapAndTheDeadline) {
  Fixture f;
  auto evaluationsAfterRefinement = [&f](uint64_t cap, bool past_deadline,
                                         mme::RefineAlgorithm algorithm = mme::RefineAlgorithm::kBobyqa) {
    mme::EsOptions options;
    options.refine_algorithm = algorithm;
    options.population = 20;
    options.offspring = 20;
    options.refine_start_generation = 2;
    options.refine_period = 100;
    options.refine_total_evaluation_cap = cap;
    mme::EvolutionStrategy es(mme::ParameterSpace(f.search, f.data), options);
    es.setCost(f.cost);
    if (past_deadline) es.setDeadline(std::chrono::steady_clock::now());
    es.step();
    es.step();  // generation 2: 20 initial + 2 x 20 children, then the refinement
    return es.evaluations();
  };
  const uint64_t free_run = evaluationsAfterRefinement(0, false);
  const uint64_t capped = evaluationsAfterRefinement(200, false);
  EXPECT_GT(free_run, 200u);
  EXPECT_LE(capped, 200u);
  EXPECT_GT(capped, 60u);  // it did refine, up to the cap
  // Past its deadline a refinement stops at its first evaluation (+1 to re-evaluate the point).
  EXPECT_LE(evaluationsAfterRefinement(0, true), 62u);
  // Levenberg-Marquardt does not start a Jacobian that would end past the deadline.
  EXPECT_GT(evaluationsAfterRefinement(0, false, mme::RefineAlgorithm::kLevenbergMarquardt), 70u);
  EXPECT_LE(evaluationsAfterRefinement(0, true, mme::RefineAlgorithm::kLevenbergMarquardt), 62u);
}

TEST(EvolutionStrategy, OperatorsKeepEveryGeneInsideItsBounds) {
  Fixture f;
  mme::EsOptions options;
  options.population = 30;
  options.offspring = 30;
  options.share_new = 0.2;  // exercise every operator often
  options.share_partly_new = 0.2;
  options.initial_mutability = 1.0;  // big jumps hit the bounds
  mme::EvolutionStrategy es(mme::ParameterSpace(f.search, f.data), options);
  es.setCost(f.cost);
  for (int g = 0; g < 30; ++g) {
    es.step();
    for (const mme::Individual& ind : es.population())
      for (size_t k = 0; k < ind.genes.size(); ++k) {
        ASSERT_GE(ind.genes[k], es.space().gene(k).lower);
        ASSERT_LE(ind.genes[k], es.space().gene(k).upper);
      }
  }
  for (int op = 1; op <= 5; ++op) EXPECT_GT(es.operatorCounts()[op], 0u) << "operator " << op;
}

TEST(EvolutionStrategy, CrossoverTakesEachTypeFromTheParentsLocallyGoodAtItsSites) {
  Fixture f;
  mme::EsOptions options;
  options.population = 2;
  options.tournament_size = 64;  // the better parent at a site is (almost surely) drawn
  mme::EvolutionStrategy es(mme::ParameterSpace(f.search, f.data), options);
  const size_t n = es.space().size();
  // Two parents that are locally good at different particles. For each type the child's genes
  // must be the mean over its sites of the parent that is better at each site; a crossover
  // without the local-cost bias picks parents at random and misses these exact means.
  mme::Individual a, b;
  a.genes.assign(n, 0.0);
  b.genes.assign(n, 0.0);
  for (size_t k = 0; k < n; ++k) {
    a.genes[k] = es.space().gene(k).lower + 0.25 * (es.space().gene(k).upper - es.space().gene(k).lower);
    b.genes[k] = es.space().gene(k).lower + 0.75 * (es.space().gene(k).upper - es.space().gene(k).lower);
  }
  a.mutability.assign(n, 0.1);
  b.mutability.assign(n, 0.1);
  // Sites: s0 {0,1,2,4}, s1 {0,2,3}, s2 {1,2,3}.
  a.local_costs = {1, 9, 1, 1, 9};
  b.local_costs = {9, 1, 9, 9, 1};
  a.cost = b.cost = 1.0;
  es.setPopulation({a, b});
  const mme::Individual child = es.crossover();
  const auto& sites = es.space().sitesOfType();
  const auto& genes = es.space().genesOfType();
  for (int type : es.space().typesWithGenes()) {
    int from_a = 0;
    for (int s : sites[type]) from_a += a.local_costs[s] < b.local_costs[s];
    const double share_a = static_cast<double>(from_a) / sites[type].size();
    for (int k : genes[type]) {
      const double expected = share_a * a.genes[k] + (1.0 - share_a) * b.genes[k];
      EXPECT_NEAR(child.genes[k], expected, 1e-12) << "type " << type << " gene " << k;
    }
  }
}

TEST(EvolutionStrategy, SameSeedSameResultForAnyThreadCount) {
  Fixture f;
  auto run = [&](int threads, uint64_t seed) {
    mme::EsOptions options;
    options.population = 20;
    options.offspring = 20;
    options.threads = threads;
    options.seed = seed;
    options.refine_start_generation = 10;
    options.refine_period = 10;
    mme::EvolutionStrategy es(mme::ParameterSpace(f.search, f.data), options);
    es.setCost(f.cost);
    for (int g = 0; g < 25; ++g) es.step();
    return es.best().genes;
  };
  const std::vector<double> one = run(1, 5);
  EXPECT_EQ(run(1, 5), one);  // bit for bit
  EXPECT_EQ(run(2, 5), one);
  EXPECT_NE(run(1, 6), one);
}

TEST(EvolutionStrategy, WarmStartKeepsThePopulationOnANewWindow) {
  Fixture f;
  mme::EsOptions options;
  options.population = 30;
  options.offspring = 30;
  mme::EvolutionStrategy es(mme::ParameterSpace(f.search, f.data), options);
  es.setCost(f.cost);
  for (int g = 0; g < 60; ++g) es.step();
  const std::vector<double> before = es.best().genes;
  // A later window of the same motion: the population lives on and is re-evaluated.
  mme::Trajectory later = mme::simulateTrajectory(f.truth, 120, 100.0);
  later.times_s.erase(later.times_s.begin(), later.times_s.begin() + 60);
  later.frame_numbers.erase(later.frame_numbers.begin(), later.frame_numbers.begin() + 60);
  later.positions_m.erase(later.positions_m.begin(), later.positions_m.begin() + 60 * 5);
  later.occluded.erase(later.occluded.begin(), later.occluded.begin() + 60 * 5);
  auto cost2 = std::make_shared<mme::ShortTermCost>(f.search, later);
  es.setCost(cost2);
  EXPECT_EQ(es.generation(), 60);
  EXPECT_EQ(es.population().size(), 30u);
  std::vector<double> local;
  EXPECT_DOUBLE_EQ(es.best().cost, cost2->evaluate(es.space().toPhysical(es.best().genes), &local));
  // The best of the old window is still a good model of the new one.
  double err_before = maxRelativeError(es.space().toPhysical(before), f.true_values);
  double err_after = maxRelativeError(es.bestValues(), f.true_values);
  EXPECT_LT(err_after, std::max(0.5, 10 * err_before));
}

/// Two islands of 20 on the small object: `strong` after 40 generations, `weak` (another seed)
/// after one.
struct TwoIslands {
  Fixture f;
  std::unique_ptr<mme::EvolutionStrategy> strong, weak;
  TwoIslands() {
    mme::EsOptions options;
    options.population = 20;
    options.offspring = 20;
    options.refine_period = 0;
    strong = std::make_unique<mme::EvolutionStrategy>(mme::ParameterSpace(f.search, f.data), options);
    strong->setCost(f.cost);
    for (int g = 0; g < 40; ++g) strong->step();
    options.seed = 7;
    weak = std::make_unique<mme::EvolutionStrategy>(mme::ParameterSpace(f.search, f.data), options);
    weak->setCost(f.cost);
    weak->step();
  }
};

// Island model: a strong island's emigrants enter a weak island's population in place of its
// worst individuals (re-evaluated there), a worse arrival changes nothing, and an arrival of
// the wrong size is refused with a reason.
TEST(EvolutionStrategy, ImmigrantsReplaceTheWorstOnlyWhenBetter) {
  TwoIslands t;
  Fixture& f = t.f;
  mme::EvolutionStrategy& strong = *t.strong;
  mme::EvolutionStrategy& weak = *t.weak;
  ASSERT_LT(strong.best().cost, weak.best().cost);

  const std::vector<mme::Individual> out = strong.emigrants(3);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].genes, strong.best().genes);
  EXPECT_LE(out[0].cost, out[1].cost);
  EXPECT_LE(out[1].cost, out[2].cost);

  std::vector<mme::Individual> arrivals = out;
  for (mme::Individual& a : arrivals) a.cost = 0.0;  // the sender's cost is not trusted
  const double worst_before = std::max_element(weak.population().begin(), weak.population().end(),
      [](const mme::Individual& a, const mme::Individual& b) { return a.cost < b.cost; })->cost;
  EXPECT_EQ(weak.immigrate(arrivals), 3);
  EXPECT_EQ(weak.population().size(), 20u);
  EXPECT_EQ(weak.best().genes, strong.best().genes);
  std::vector<double> local;
  EXPECT_DOUBLE_EQ(weak.best().cost,
                   f.cost->evaluate(weak.space().toPhysical(weak.best().genes), &local));
  EXPECT_LT(weak.best().cost, worst_before);
  EXPECT_EQ(weak.operatorSuccesses()[static_cast<int>(mme::Operator::kImmigrant)], 3u);

  // The strong island's population is all better than a fresh random individual.
  std::vector<mme::Individual> poor{weak.makeRandom()};
  const std::vector<mme::Individual> strong_before = strong.population();
  strong.immigrate(poor);
  const double strong_worst = std::max_element(strong_before.begin(), strong_before.end(),
      [](const mme::Individual& a, const mme::Individual& b) { return a.cost < b.cost; })->cost;
  if (poor[0].cost >= strong_worst) {
    for (size_t i = 0; i < strong_before.size(); ++i)
      EXPECT_EQ(strong.population()[i].genes, strong_before[i].genes);
  }

  std::vector<mme::Individual> wrong{out[0]};
  wrong[0].genes.pop_back();
  EXPECT_THROW(weak.immigrate(wrong), mme::InputError);
}

// The same best broadcast by several islands arrives several times: each copy takes a place of
// a worse individual (a deliberate choice: the copies raise the best's share of the parents,
// docs/benchmarks.md), and is evaluated once per copy.
TEST(EvolutionStrategy, IdenticalImmigrantsEachTakeAPlace) {
  TwoIslands t;
  mme::EvolutionStrategy& strong = *t.strong;
  mme::EvolutionStrategy& weak = *t.weak;
  ASSERT_LT(strong.best().cost, weak.best().cost);

  const mme::Individual best = strong.emigrants(1).at(0);
  const uint64_t evaluations_before = weak.evaluations();
  EXPECT_EQ(weak.immigrate({best, best, best}), 3);
  const auto copies = std::count_if(weak.population().begin(), weak.population().end(),
                                    [&best](const mme::Individual& ind) { return ind.genes == best.genes; });
  EXPECT_EQ(copies, 3);
  EXPECT_EQ(weak.evaluations() - evaluations_before, 3u);
  EXPECT_EQ(weak.best().genes, best.genes);
}

// The engine with the Levenberg-Marquardt refinement from generation 5 identifies the small
// object in 10 generations; the algorithm is parsed by name.
TEST(EvolutionStrategy, LevenbergMarquardtRefinementIdentifiesTheSmallObjectEarly) {
  Fixture f;
  mme::EsOptions options;
  options.population = 40;
  options.offspring = 40;
  options.refine_algorithm = mme::RefineAlgorithm::kLevenbergMarquardt;
  options.refine_start_generation = 5;
  options.refine_period = 5;
  EXPECT_EQ(mme::validateOptions(options), "");
  mme::EvolutionStrategy es(mme::ParameterSpace(f.search, f.data), options);
  es.setCost(f.cost);
  for (int g = 0; g < 10; ++g) es.step();
  EXPECT_LT(maxRelativeError(es.bestValues(), f.true_values), 1e-6) << es.best().cost;
  // 40 + 10 x 40 children and two refinements of a few Jacobians (518 evaluations); BOBYQA in
  // the same place runs its windows of 30n + 100 evaluations (1231 in all).
  EXPECT_LT(es.evaluations(), 700u);
  EXPECT_GT(es.operatorSuccesses()[static_cast<int>(mme::Operator::kRefine)], 0u);
  mme::RefineAlgorithm parsed = mme::RefineAlgorithm::kBobyqa;
  EXPECT_TRUE(mme::parseRefineAlgorithm("levenberg_marquardt", &parsed));
  EXPECT_EQ(parsed, mme::RefineAlgorithm::kLevenbergMarquardt);
  EXPECT_FALSE(mme::parseRefineAlgorithm("levenberg-marquardt", &parsed));
}

}  // namespace

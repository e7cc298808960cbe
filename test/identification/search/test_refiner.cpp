// The refinement unit: algorithms by name through the factory, how each reports its ending, and
// that no refinement moves a gene it was told to hold.
#include <gtest/gtest.h>

#include <memory>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/search/refiner.h"
#include "test_helpers.h"

namespace {

using mme::RefineAlgorithm;
using mme::RefineStatus;

struct Fixture {
  mme::Model truth = mme::test::smallObject();
  mme::Model search = mme::test::withoutValues(truth);
  mme::Trajectory data = mme::simulateTrajectory(truth, 40, 100.0);
  mme::ShortTermCost cost{search, data};
  mme::ParameterSpace space{search, data};
  std::vector<double> truth_genes = space.toSearch(mme::getValues(truth, mme::freeParameters(truth)));

  mme::RefineStart startOff(double share) const {
    mme::RefineStart s;
    s.genes = truth_genes;
    for (size_t k = 0; k < s.genes.size(); ++k)
      s.genes[k] = space.reflect(k, s.genes[k] + (k % 2 ? share : -share) * std::abs(s.genes[k]));
    s.cost = cost.evaluate(space.toPhysical(s.genes), nullptr);
    s.steps.assign(s.genes.size(), 0.01);
    return s;
  }
};

TEST(Refiner, NamesRoundTripAndUnknownNamesAreRefused) {
  for (RefineAlgorithm a : {RefineAlgorithm::kBobyqa, RefineAlgorithm::kNewuoa, RefineAlgorithm::kPraxis,
                            RefineAlgorithm::kLevenbergMarquardt}) {
    RefineAlgorithm parsed = RefineAlgorithm::kBobyqa;
    ASSERT_TRUE(mme::parseRefineAlgorithm(mme::refineAlgorithmName(a), &parsed));
    EXPECT_EQ(parsed, a);
    EXPECT_EQ(mme::Refiner::Create(a)->algorithm(), a);
  }
  RefineAlgorithm unchanged = RefineAlgorithm::kPraxis;
  EXPECT_FALSE(mme::parseRefineAlgorithm("BOBYQA", &unchanged));
  EXPECT_FALSE(mme::parseRefineAlgorithm("", &unchanged));
  EXPECT_EQ(unchanged, RefineAlgorithm::kPraxis);
  EXPECT_STREQ(mme::refineStatusName(RefineStatus::kJacobianTooLarge), "jacobian_too_large");
}

// Every algorithm lowers the cost from a start 5 % off and ends converged or stalled; held genes
// stay where they were.
TEST(Refiner, EveryAlgorithmImprovesAndHoldsWhatItIsTold) {
  Fixture f;
  const mme::RefineStart start = f.startOff(0.05);
  for (RefineAlgorithm a : {RefineAlgorithm::kBobyqa, RefineAlgorithm::kNewuoa, RefineAlgorithm::kPraxis,
                            RefineAlgorithm::kLevenbergMarquardt}) {
    mme::RefineSettings settings;
    settings.max_evaluations = 3000;
    settings.window_evaluations = 300;
    const mme::RefineResult r = mme::Refiner::Create(a)->refine(f.cost, f.space, start, settings, nullptr);
    // NEWUOA and PRAXIS stop on their own tolerances well short of BOBYQA and LM here.
    const bool strong = a == RefineAlgorithm::kBobyqa || a == RefineAlgorithm::kLevenbergMarquardt;
    EXPECT_LT(r.cost, (strong ? 1e-3 : 0.1) * start.cost)
        << mme::refineAlgorithmName(a) << " " << mme::refineStatusName(r.status);
    EXPECT_LE(r.evaluations, settings.max_evaluations);
    EXPECT_DOUBLE_EQ(r.cost, f.cost.evaluate(f.space.toPhysical(r.genes), nullptr));

    settings.movable.assign(start.genes.size(), 1);
    settings.movable[1] = 0;
    const mme::RefineResult held = mme::Refiner::Create(a)->refine(f.cost, f.space, start, settings, nullptr);
    EXPECT_EQ(held.genes[1], start.genes[1]) << mme::refineAlgorithmName(a);
    EXPECT_LT(held.cost, start.cost) << mme::refineAlgorithmName(a);
  }
}

// The endings: an evaluation budget too small to start, a deadline already passed, and LM's
// convergence on exact data.
TEST(Refiner, ReportsWhyItStopped) {
  Fixture f;
  const mme::RefineStart start = f.startOff(0.05);
  mme::RefineSettings tiny;
  tiny.max_evaluations = 3;
  for (RefineAlgorithm a : {RefineAlgorithm::kBobyqa, RefineAlgorithm::kLevenbergMarquardt}) {
    const mme::RefineResult r = mme::Refiner::Create(a)->refine(f.cost, f.space, start, tiny, nullptr);
    EXPECT_EQ(r.status, RefineStatus::kNotRun) << mme::refineAlgorithmName(a);
    EXPECT_EQ(r.evaluations, 0u);
    EXPECT_EQ(r.genes, start.genes);
  }
  mme::RefineSettings late;
  late.max_evaluations = 3000;
  late.window_evaluations = 300;
  late.deadline = std::chrono::steady_clock::now();
  for (RefineAlgorithm a : {RefineAlgorithm::kBobyqa, RefineAlgorithm::kLevenbergMarquardt}) {
    const mme::RefineResult r = mme::Refiner::Create(a)->refine(f.cost, f.space, start, late, nullptr);
    EXPECT_EQ(r.status, RefineStatus::kDeadline) << mme::refineAlgorithmName(a);
  }
  mme::RefineSettings plenty;
  plenty.max_evaluations = 3000;
  const mme::RefineResult lm = mme::Refiner::Create(RefineAlgorithm::kLevenbergMarquardt)
                                   ->refine(f.cost, f.space, start, plenty, nullptr);
  EXPECT_EQ(lm.status, RefineStatus::kConverged);
  EXPECT_LT(mme::test::maxRelativeError(f.space.toPhysical(lm.genes), f.space.toPhysical(f.truth_genes)), 1e-8);
}

}  // namespace

// The Levenberg-Marquardt refinement on the cost's residuals, solved by Ceres: convergence in a
// few Jacobians, limits, bounds, the genes it may move, and how each ending (Ceres' termination
// or one of the package's stopping rules) is reported.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <thread>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "motion_model_estimation/identification/search/ceres_levenberg_marquardt.h"
#include "test_helpers.h"

namespace {

using mme::test::maxRelativeError;

using Fixture = mme::test::SmallObjectFixture;

/// Another cost with a hook before each residual evaluation (its 1-based count).
class HookedCost final : public mme::Cost {
 public:
  HookedCost(const mme::Cost& inner, std::function<void(uint64_t)> hook)
      : inner_(inner), hook_(std::move(hook)) {}
  const std::vector<mme::ParamRef>& freeParameters() const override { return inner_.freeParameters(); }
  double evaluate(const std::vector<double>& values, std::vector<double>* local) const override {
    return inner_.evaluate(values, local);
  }
  double residuals(const std::vector<double>& values, std::vector<double>* r) const override {
    hook_(++calls_);
    return inner_.residuals(values, r);
  }
  size_t residualCount() const override { return inner_.residualCount(); }
  uint64_t termCount() const override { return inner_.termCount(); }
  int numParticles() const override { return inner_.numParticles(); }
  const char* name() const override { return "hooked"; }

 private:
  const mme::Cost& inner_;
  std::function<void(uint64_t)> hook_;
  mutable std::atomic<uint64_t> calls_{0};
};

std::vector<double> startOff(const mme::ParameterSpace& space, const std::vector<double>& truth,
                             double share) {
  std::vector<double> start = space.toSearch(truth);
  for (size_t k = 0; k < start.size(); ++k)
    start[k] = space.reflect(k, start[k] + (k % 2 ? share : -share) * std::abs(start[k]));
  return start;
}

// From a start 20 % off it converges in a few Jacobians (a derivative-free search needs hundreds
// of evaluations here) on the step tolerance, gives the same point bit for bit on two
// threads (its Jacobian columns run in parallel), keeps to its evaluation limit, refuses a
// Jacobian over the memory cap, and stops at a bound the answer lies beyond.
TEST(CeresLevenbergMarquardt, ConvergesInAFewJacobiansInsideItsLimitsAndBounds) {
  Fixture f;
  const mme::ParameterSpace space(f.search, f.data);
  const size_t n = space.size();
  const std::vector<double> start = startOff(space, f.true_values, 0.2);
  const mme::LmResult one = mme::levenbergMarquardt(*f.cost, space, start, {}, nullptr);
  EXPECT_LT(maxRelativeError(space.toPhysical(one.genes), f.true_values), 1e-7) << one.cost;
  EXPECT_LT(one.evaluations, 30 * (n + 1));
  EXPECT_GE(one.jacobians, 2);
  // Each Jacobian costs a column per gene; the other evaluations are the start and the trials.
  EXPECT_GE(one.evaluations, static_cast<uint64_t>(one.jacobians) * n + 1);
  EXPECT_EQ(one.status, mme::RefineStatus::kConverged);
  EXPECT_DOUBLE_EQ(one.cost, f.cost->evaluate(space.toPhysical(one.genes), nullptr));

  mme::ThreadPool pool(2);
  const mme::LmResult two = mme::levenbergMarquardt(*f.cost, space, start, {}, &pool);
  EXPECT_EQ(two.genes, one.genes);
  EXPECT_EQ(two.evaluations, one.evaluations);

  mme::LmSettings few;
  few.max_evaluations = 3 * (n + 1);
  const mme::LmResult limited = mme::levenbergMarquardt(*f.cost, space, start, few, nullptr);
  EXPECT_LE(limited.evaluations, few.max_evaluations);
  EXPECT_EQ(limited.status, mme::RefineStatus::kEvaluationLimit);
  EXPECT_LT(limited.cost, f.cost->evaluate(space.toPhysical(start), nullptr));

  // A Jacobian beyond the memory cap: it stops after computing it, at the start.
  mme::LmSettings small;
  small.max_jacobian_entries = 10;
  const mme::LmResult refused = mme::levenbergMarquardt(*f.cost, space, start, small, nullptr);
  EXPECT_EQ(refused.status, mme::RefineStatus::kJacobianTooLarge);
  EXPECT_EQ(refused.genes, start);
  EXPECT_EQ(refused.evaluations, n + 1);
  EXPECT_EQ(refused.solves, 0);

  // The first type's stiffness (true 20 N/m) capped at 15: the answer sits on that bound.
  mme::Model capped = f.search;
  capped.bond_types[0].param(mme::kStiffness).max = 15.0;
  const mme::ParameterSpace capped_space(capped, f.data);
  std::vector<double> inside = start;
  for (size_t k = 0; k < n; ++k) inside[k] = capped_space.reflect(k, inside[k]);
  const mme::LmResult at_bound = mme::levenbergMarquardt(*f.cost, capped_space, inside, {}, nullptr);
  for (size_t k = 0; k < n; ++k) {
    EXPECT_GE(at_bound.genes[k], capped_space.gene(k).lower);
    EXPECT_LE(at_bound.genes[k], capped_space.gene(k).upper);
  }
  EXPECT_NEAR(capped_space.toPhysical(at_bound.genes)[0], 15.0, 1e-9);
}

// On noisy data (an ill-conditioned valley: a point 0.7 % above the optimum's cost is 40 % off
// in a parameter) the refinement stops on the optimum, not before: a second run from its answer
// lowers the cost by less than 1e-6 of it.
TEST(CeresLevenbergMarquardt, StopsOnTheNoisyOptimumNotBeforeIt) {
  Fixture f;
  mme::addGaussianNoise(&f.data, 1e-4, 7);
  f.cost = std::make_shared<mme::ShortTermCost>(f.search, f.data);
  const mme::ParameterSpace space(f.search, f.data);
  std::vector<double> start = space.toSearch(f.true_values);
  for (size_t k = 0; k < space.size(); ++k) start[k] = space.reflect(k, start[k] * (k % 2 ? 1.3 : 0.7));
  const mme::LmResult first = mme::levenbergMarquardt(*f.cost, space, start, {}, nullptr);
  EXPECT_LT(maxRelativeError(space.toPhysical(first.genes), f.true_values), 0.05);
  const mme::LmResult again = mme::levenbergMarquardt(*f.cost, space, first.genes, {}, nullptr);
  EXPECT_GT(again.cost, first.cost * (1.0 - 1e-6));
  EXPECT_LE(again.cost, first.cost);
}

// With a mask the search moves only the movable genes (the others keep their start value and
// cost no Jacobian column), and still lowers the cost along those.
TEST(CeresLevenbergMarquardt, MovesOnlyTheMovableGenes) {
  Fixture f;
  const mme::ParameterSpace space(f.search, f.data);
  const size_t n = space.size();
  const std::vector<double> start = startOff(space, f.true_values, 0.1);
  mme::LmSettings settings;
  settings.movable.assign(n, 0);
  settings.movable[0] = settings.movable[3] = 1;
  const mme::LmResult r = mme::levenbergMarquardt(*f.cost, space, start, settings, nullptr);
  for (size_t k = 0; k < n; ++k)
    if (!settings.movable[k]) {
      EXPECT_EQ(r.genes[k], start[k]) << k;
    }
  EXPECT_NE(r.genes[0], start[0]);
  EXPECT_NE(r.genes[3], start[3]);
  EXPECT_LT(r.cost, f.cost->evaluate(space.toPhysical(start), nullptr));
  EXPECT_GE(r.jacobians, 1);
  // Two columns per Jacobian.
  EXPECT_GE(r.evaluations, 2u * static_cast<uint64_t>(r.jacobians) + 1);
}

// A deadline already passed: no Jacobian is started, the start is returned with kDeadline. A
// deadline that passes during the run (the cost sleeps past it after the first Jacobian) ends it
// at the next iteration, keeping the best point so far.
TEST(CeresLevenbergMarquardt, StopsOnTheDeadline) {
  Fixture f;
  const mme::ParameterSpace space(f.search, f.data);
  const size_t n = space.size();
  const std::vector<double> start = startOff(space, f.true_values, 0.1);
  mme::LmSettings late;
  late.deadline = std::chrono::steady_clock::now();
  const mme::LmResult r = mme::levenbergMarquardt(*f.cost, space, start, late, nullptr);
  EXPECT_EQ(r.status, mme::RefineStatus::kDeadline);
  EXPECT_EQ(r.jacobians, 0);
  EXPECT_EQ(r.evaluations, 1u);
  EXPECT_EQ(r.genes, start);

  mme::LmSettings soon;
  soon.deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(200);
  const HookedCost sleepy(*f.cost, [&](uint64_t call) {
    if (call == n + 2) std::this_thread::sleep_until(soon.deadline + std::chrono::milliseconds(1));
  });
  const mme::LmResult passed = mme::levenbergMarquardt(sleepy, space, start, soon, nullptr);
  EXPECT_EQ(passed.status, mme::RefineStatus::kDeadline);
  EXPECT_GE(passed.jacobians, 1);
  EXPECT_LT(passed.cost, f.cost->evaluate(space.toPhysical(start), nullptr) * 1.000001);
  EXPECT_DOUBLE_EQ(passed.cost, f.cost->evaluate(space.toPhysical(passed.genes), nullptr));
}

// The other endings: the cancel flag raised during the run (the callback aborts the solve: the
// best point so far is kept), the stall rule (stall_factor 0: stop after 3 accepted steps,
// before the third one's Jacobian: the start's and two more), and a start where the model blows
// up (not run).
TEST(CeresLevenbergMarquardt, MapsEachEndingToItsStatus) {
  Fixture f;
  const mme::ParameterSpace space(f.search, f.data);
  const size_t n = space.size();
  const std::vector<double> start = startOff(space, f.true_values, 0.2);
  const double start_cost = f.cost->evaluate(space.toPhysical(start), nullptr);

  std::atomic<bool> cancel{false};
  const HookedCost cancelling(*f.cost, [&](uint64_t call) {
    if (call == 2 * n + 2) cancel = true;  // a Jacobian and a trial after the start
  });
  mme::LmSettings with_flag;
  with_flag.cancel = &cancel;
  const mme::LmResult cancelled = mme::levenbergMarquardt(cancelling, space, start, with_flag, nullptr);
  EXPECT_EQ(cancelled.status, mme::RefineStatus::kCancelled);
  // At the end of the iteration that raised it: at most the Jacobian after an accepted step.
  EXPECT_GE(cancelled.jacobians, 1);
  EXPECT_LE(cancelled.evaluations, 3 * n + 2);
  EXPECT_LT(cancelled.cost, start_cost);
  EXPECT_DOUBLE_EQ(cancelled.cost, f.cost->evaluate(space.toPhysical(cancelled.genes), nullptr));

  mme::LmSettings no_patience;
  no_patience.stall_factor = 0.0;
  const mme::LmResult stalled = mme::levenbergMarquardt(*f.cost, space, start, no_patience, nullptr);
  EXPECT_EQ(stalled.status, mme::RefineStatus::kStalled);
  EXPECT_EQ(stalled.jacobians, 3);
  EXPECT_LT(stalled.cost, start_cost);

  struct Blown final : public mme::Cost {
    const mme::Cost& inner;
    explicit Blown(const mme::Cost& c) : inner(c) {}
    const std::vector<mme::ParamRef>& freeParameters() const override { return inner.freeParameters(); }
    double evaluate(const std::vector<double>&, std::vector<double>*) const override {
      return std::numeric_limits<double>::quiet_NaN();
    }
    double residuals(const std::vector<double>& v, std::vector<double>* r) const override {
      inner.residuals(v, r);
      return std::numeric_limits<double>::quiet_NaN();
    }
    size_t residualCount() const override { return inner.residualCount(); }
    uint64_t termCount() const override { return inner.termCount(); }
    int numParticles() const override { return inner.numParticles(); }
    const char* name() const override { return "blown"; }
  } blown(*f.cost);
  const mme::LmResult not_run = mme::levenbergMarquardt(blown, space, start, {}, nullptr);
  EXPECT_EQ(not_run.status, mme::RefineStatus::kNotRun);
  EXPECT_EQ(not_run.jacobians, 0);
  EXPECT_EQ(not_run.evaluations, 1u);
  EXPECT_EQ(not_run.genes, start);
}

/// A model of many bond types (48 genes) whose particles' residuals move with the few types
/// bonded there: a Jacobian that is mostly absent.
struct ManyTypes {
  ManyTypes() {
    mme::RandomObjectSpec spec;
    spec.particles = 30;
    spec.bond_types = 24;
    spec.bonds = 60;
    spec.seed = 3;
    truth = mme::makeRandomObject(spec);
    data = mme::simulateTrajectory(truth, 40, spec.frame_rate_hz);
    search = mme::test::withoutValues(truth);
    cost = std::make_shared<mme::ShortTermCost>(search, data);
    want = mme::getValues(truth, mme::freeParameters(truth));
  }
  mme::Model truth, search;
  mme::Trajectory data;
  std::shared_ptr<mme::ShortTermCost> cost;
  std::vector<double> want;
};

// Ceres solves the many-type model on residual blocks over the genes that move them (the
// Jacobian's non-zeros, a sparse Cholesky), and converges to the truth from 10 % off in a few
// Jacobians, the same on two threads.
TEST(CeresLevenbergMarquardt, SolvesAManyTypeModelOnItsSparseStructure) {
  const ManyTypes p;
  const mme::ParameterSpace space(p.search, p.data);
  ASSERT_EQ(space.size(), 48u);
  const std::vector<double> start = startOff(space, p.want, 0.1);
  const mme::LmResult one = mme::levenbergMarquardt(*p.cost, space, start, {}, nullptr);
  EXPECT_TRUE(one.sparse);
  EXPECT_EQ(one.solves, 1);
  EXPECT_LT(maxRelativeError(space.toPhysical(one.genes), p.want), 1e-7) << one.cost;
  EXPECT_EQ(one.status, mme::RefineStatus::kConverged);
  EXPECT_LT(one.jacobians, 15);
  mme::ThreadPool pool(2);
  const mme::LmResult two = mme::levenbergMarquardt(*p.cost, space, start, {}, &pool);
  EXPECT_EQ(two.genes, one.genes);
  EXPECT_EQ(two.evaluations, one.evaluations);
}

// A cost whose structure changes with the point: an extra residual moves with gene 1 only once
// gene 0 has risen above its start (no slope there, so the start's Jacobian has no entry for
// it). The Jacobian that finds the new entry restarts the solve on a layout that holds it, and
// the search converges as on the model alone.
TEST(CeresLevenbergMarquardt, ASolveRestartsWhenTheStructureGrows) {
  const ManyTypes p;
  const mme::ParameterSpace space(p.search, p.data);
  std::vector<double> start = startOff(space, p.want, 0.1);
  start[0] = space.reflect(0, space.toSearch(p.want)[0] - 0.2 * std::abs(space.toSearch(p.want)[0]));
  const double gate = space.toPhysical(start)[0];
  struct Growing final : public mme::Cost {
    const mme::Cost& inner;
    double gate;
    Growing(const mme::Cost& c, double g) : inner(c), gate(g) {}
    const std::vector<mme::ParamRef>& freeParameters() const override { return inner.freeParameters(); }
    double evaluate(const std::vector<double>& v, std::vector<double>*) const override {
      std::vector<double> r;
      return residuals(v, &r);
    }
    double residuals(const std::vector<double>& v, std::vector<double>* r) const override {
      const double c = inner.residuals(v, r);
      const double extra = 1e-6 * std::max(0.0, v[0] - gate) * v[1];
      r->push_back(extra);
      return c + extra * extra;
    }
    size_t residualCount() const override { return inner.residualCount() + 1; }
    uint64_t termCount() const override { return inner.termCount(); }
    int numParticles() const override { return inner.numParticles(); }
    const char* name() const override { return "growing"; }
  } growing(*p.cost, gate);
  const mme::LmResult r = mme::levenbergMarquardt(growing, space, start, {}, nullptr);
  EXPECT_TRUE(r.sparse);
  EXPECT_GE(r.solves, 2);
  EXPECT_GT(space.toPhysical(r.genes)[0], gate);
  EXPECT_LT(maxRelativeError(space.toPhysical(r.genes), p.want), 1e-3) << r.cost;
  EXPECT_DOUBLE_EQ(r.cost, growing.evaluate(space.toPhysical(r.genes), nullptr));
}

}  // namespace

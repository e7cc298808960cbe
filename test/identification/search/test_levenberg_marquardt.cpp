// The Levenberg-Marquardt refinement on the cost's residuals: convergence in a few Jacobians,
// limits, bounds, the stopping rules, the genes it may move, and the normal equations.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <memory>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/search/levenberg_marquardt.h"
#include "test_helpers.h"

namespace {

using mme::test::maxRelativeError;
using mme::test::smallObject;
using mme::test::withoutValues;

using Fixture = mme::test::SmallObjectFixture;

// The Levenberg-Marquardt refinement on the residuals: from a start 20 % off it converges in a
// few Jacobians (a derivative-free search needs hundreds of evaluations here), gives the same
// point bit for bit on two threads (its Jacobian columns run in parallel), keeps to its
// evaluation limit, and stops at a bound the answer lies beyond.
TEST(LevenbergMarquardt, ConvergesInAFewJacobiansInsideItsLimitsAndBounds) {
  Fixture f;
  const mme::ParameterSpace space(f.search, f.data);
  const size_t n = space.size();
  std::vector<double> start = space.toSearch(f.true_values);
  for (size_t k = 0; k < n; ++k) start[k] += (k % 2 ? 0.2 : -0.2) * std::abs(start[k]);
  for (size_t k = 0; k < n; ++k) start[k] = space.reflect(k, start[k]);
  const mme::LmResult one = mme::levenbergMarquardt(*f.cost, space, start, {}, nullptr);
  EXPECT_LT(maxRelativeError(space.toPhysical(one.genes), f.true_values), 1e-7) << one.cost;
  EXPECT_LT(one.evaluations, 30 * (n + 1));
  EXPECT_GE(one.jacobians, 2);
  // It stops at the round-off floor on the step tolerance, not after stalled Jacobians.
  EXPECT_EQ(one.status, mme::RefineStatus::kConverged);
  EXPECT_DOUBLE_EQ(one.cost, f.cost->evaluate(space.toPhysical(one.genes), nullptr));

  mme::ThreadPool pool(2);
  const mme::LmResult two = mme::levenbergMarquardt(*f.cost, space, start, {}, &pool);
  EXPECT_EQ(two.genes, one.genes);
  EXPECT_EQ(two.evaluations, one.evaluations);

  mme::LmSettings few;
  few.max_evaluations = 2 * (n + 1);
  EXPECT_LE(mme::levenbergMarquardt(*f.cost, space, start, few, nullptr).evaluations,
            few.max_evaluations);

  // A Jacobian beyond the memory cap: it stops after computing it, at the start.
  mme::LmSettings small;
  small.max_jacobian_entries = 10;
  const mme::LmResult refused = mme::levenbergMarquardt(*f.cost, space, start, small, nullptr);
  EXPECT_EQ(refused.status, mme::RefineStatus::kJacobianTooLarge);
  EXPECT_EQ(refused.genes, start);
  EXPECT_EQ(refused.evaluations, n + 1);
  EXPECT_NE(one.status, mme::RefineStatus::kJacobianTooLarge);

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
TEST(LevenbergMarquardt, StopsOnTheNoisyOptimumNotBeforeIt) {
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

// J^T J and J^T r from sparse columns: the dense and the row-outer-product paths agree with a
// dense product, on a Jacobian with an empty column, empty rows and one dense row.
TEST(LevenbergMarquardt, NormalEquationsAgreeOnBothPaths) {
  const size_t m = 40, n = 6;
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(m, n);
  mme::detail::JacobianColumns jac;
  jac.rows_count = m;
  jac.rows.resize(n);
  jac.values.resize(n);
  for (size_t k = 0; k < n; ++k) {
    if (k == 3) continue;  // a gene that moved nothing
    for (size_t i = 0; i < m; ++i) {
      if (i != 17 && (i * 7 + k * 3) % 5 != 0) continue;  // row 17 dense, ~1/5 of the rest
      if (i % 11 == 10) continue;                          // rows no gene moves
      const double v = std::sin(1.0 + static_cast<double>(i * n + k));
      dense(i, k) = v;
      jac.rows[k].push_back(static_cast<uint32_t>(i));
      jac.values[k].push_back(v);
    }
  }
  Eigen::VectorXd r(m);
  for (size_t i = 0; i < m; ++i) r[i] = std::cos(0.3 * i);
  const Eigen::MatrixXd want_jtj = dense.transpose() * dense;
  const Eigen::VectorXd want_g = dense.transpose() * r;
  EXPECT_EQ(jac.nonZeros(), static_cast<size_t>((dense.array() != 0.0).count()));
  for (auto path : {mme::detail::NormalEquationsPath::kDense, mme::detail::NormalEquationsPath::kSparse,
                    mme::detail::NormalEquationsPath::kAuto}) {
    Eigen::MatrixXd jtj;
    Eigen::VectorXd g;
    mme::detail::normalEquations(jac, r, &jtj, &g, path);
    EXPECT_LT((jtj - want_jtj).cwiseAbs().maxCoeff(), 1e-12) << static_cast<int>(path);
    EXPECT_LT((g - want_g).cwiseAbs().maxCoeff(), 1e-12) << static_cast<int>(path);
    EXPECT_EQ(jtj, jtj.transpose());
    EXPECT_EQ(jtj.row(3).squaredNorm(), 0.0);
  }
}

// With a mask the search moves only the movable genes (the others keep their start value and
// cost no Jacobian column), and still lowers the cost along those.
TEST(LevenbergMarquardt, MovesOnlyTheMovableGenes) {
  Fixture f;
  const mme::ParameterSpace space(f.search, f.data);
  const size_t n = space.size();
  std::vector<double> start = space.toSearch(f.true_values);
  for (size_t k = 0; k < n; ++k) start[k] = space.reflect(k, start[k] + 0.1 * std::abs(start[k]));
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
}

// A deadline already passed: no Jacobian is started, the start is returned with kDeadline.
TEST(LevenbergMarquardt, StopsBeforeAJacobianThatWouldPassTheDeadline) {
  Fixture f;
  const mme::ParameterSpace space(f.search, f.data);
  std::vector<double> start = space.toSearch(f.true_values);
  for (size_t k = 0; k < space.size(); ++k) start[k] = space.reflect(k, start[k] * 1.1);
  mme::LmSettings settings;
  settings.deadline = std::chrono::steady_clock::now();
  const mme::LmResult r = mme::levenbergMarquardt(*f.cost, space, start, settings, nullptr);
  EXPECT_EQ(r.status, mme::RefineStatus::kDeadline);
  EXPECT_EQ(r.jacobians, 0);
  EXPECT_EQ(r.evaluations, 1u);
  EXPECT_EQ(r.genes, start);
}

}  // namespace

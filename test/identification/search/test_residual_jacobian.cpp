// The residuals' forward-difference Jacobian and the normal equations built from it (the
// Levenberg-Marquardt refinement's derivatives and the identifier's standard deviations).
#include <gtest/gtest.h>

#include <cmath>

#include "motion_model_estimation/identification/search/residual_jacobian.h"
#include "test_helpers.h"

namespace {

using Fixture = mme::test::SmallObjectFixture;

// J^T J and J^T r from sparse columns: the dense and the row-outer-product paths agree with a
// dense product, on a Jacobian with an empty column, empty rows and one dense row.
TEST(ResidualJacobian, NormalEquationsAgreeOnBothPaths) {
  const size_t m = 40, n = 6;
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(m, n);
  mme::ResidualJacobian jac;
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
  EXPECT_EQ(Eigen::MatrixXd(jac.toSparse()), dense);
  for (auto path : {mme::NormalEquationsPath::kDense, mme::NormalEquationsPath::kSparse,
                    mme::NormalEquationsPath::kAuto}) {
    Eigen::MatrixXd jtj;
    Eigen::VectorXd g;
    mme::normalEquations(jac, r, &jtj, &g, path);
    EXPECT_LT((jtj - want_jtj).cwiseAbs().maxCoeff(), 1e-12) << static_cast<int>(path);
    EXPECT_LT((g - want_g).cwiseAbs().maxCoeff(), 1e-12) << static_cast<int>(path);
    EXPECT_EQ(jtj, jtj.transpose());
    EXPECT_EQ(jtj.row(3).squaredNorm(), 0.0);
  }
}

// The forward differences of the small object's cost: each column is (r(x + h e_k) - r(x)) / h
// with the documented step, a step at the upper bound goes inward, and the result is the same
// bit for bit on two threads.
TEST(ResidualJacobian, ForwardDifferencesPerGeneInwardAtTheBound) {
  Fixture f;
  const mme::ParameterSpace space(f.search, f.data);
  const size_t n = space.size();
  std::vector<double> x = space.toSearch(f.true_values);
  x[1] = space.gene(1).upper;
  std::vector<double> r0;
  f.cost->residuals(space.toPhysical(x), &r0);
  const Eigen::VectorXd residual = Eigen::Map<const Eigen::VectorXd>(r0.data(), r0.size());
  std::vector<size_t> active(n);
  for (size_t k = 0; k < n; ++k) active[k] = k;
  mme::ResidualJacobian one, two;
  ASSERT_TRUE(mme::forwardJacobian(*f.cost, space, x, residual, active, 100000000, nullptr, &one));
  mme::ThreadPool pool(2);
  ASSERT_TRUE(mme::forwardJacobian(*f.cost, space, x, residual, active, 100000000, &pool, &two));
  EXPECT_EQ(one.rows, two.rows);
  EXPECT_EQ(one.values, two.values);
  EXPECT_LT(mme::forwardDifferenceStep(space.gene(1), x[1]), 0.0);
  for (size_t k = 0; k < n; ++k) {
    const double h = mme::forwardDifferenceStep(space.gene(k), x[k]);
    std::vector<double> moved = x, rk;
    moved[k] += h;
    f.cost->residuals(space.toPhysical(moved), &rk);
    ASSERT_FALSE(one.rows[k].empty()) << k;
    for (size_t e = 0; e < one.rows[k].size(); ++e) {
      const uint32_t i = one.rows[k][e];
      EXPECT_EQ(one.values[k][e], (rk[i] - r0[i]) / h) << k << " " << i;
    }
  }
  // A cap below the entries: reported, not silently truncated.
  mme::ResidualJacobian capped;
  EXPECT_FALSE(mme::forwardJacobian(*f.cost, space, x, residual, active, 3, nullptr, &capped));
}

}  // namespace

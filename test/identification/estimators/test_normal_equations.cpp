// solveNormalEquations: least squares from A^T A, A^T b and b^T b that stays trustworthy when
// the columns are nearly or exactly dependent (the equation error of a short real window).
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "motion_model_estimation/identification/estimators/normal_equations.h"

namespace {

struct System {
  Eigen::MatrixXd j;
  Eigen::VectorXd y;
  Eigen::MatrixXd ata() const { return j.transpose() * j; }
  Eigen::VectorXd atb() const { return j.transpose() * y; }
  double btb() const { return y.squaredNorm(); }
  double residual2(const Eigen::VectorXd& theta) const { return (j * theta - y).squaredNorm(); }
};

/// Columns t^0 .. t^(cols-1) on [0, 1): a Gram matrix far beyond double precision's condition.
System vandermonde(int cols, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1e-6);
  const int rows = 4 * cols;
  System s{Eigen::MatrixXd(rows, cols), Eigen::VectorXd(rows)};
  for (int i = 0; i < rows; ++i) {
    const double t = static_cast<double>(i) / rows;
    for (int c = 0; c < cols; ++c) s.j(i, c) = std::pow(t, c);
    s.y[i] = std::cos(7.0 * t) + noise(rng);
  }
  return s;
}

TEST(NormalEquations, AWellPosedSystemGivesTheLeastSquaresSolution) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n01;
  System s{Eigen::MatrixXd(200, 8), Eigen::VectorXd(200)};
  for (int i = 0; i < 200; ++i) {
    for (int c = 0; c < 8; ++c) s.j(i, c) = n01(rng) * (c + 1.0);  // columns of different scales
    s.y[i] = n01(rng);
  }
  const mme::NormalEquationsSolution got = mme::solveNormalEquations(s.ata(), s.atb(), s.btb());
  ASSERT_TRUE(got.trusted);
  const Eigen::VectorXd want = s.j.colPivHouseholderQr().solve(s.y);
  for (int c = 0; c < 8; ++c) EXPECT_NEAR(got.theta[c], want[c], 1e-10 * std::fabs(want[c]) + 1e-14);
  EXPECT_NEAR(got.rss, s.residual2(want), 1e-10 * s.btb());
}

// The regression: a column-pivoted QR of the scaled Gram matrix truncated at a 1e-12 pivot
// threshold returned residuals 10^2 to 10^8 times b^T b on these systems (and on a real 43-marker
// window's 1 503 springs-and-dampers unknowns, 10^13 times); the least-squares residual is at
// most b^T b, and here far below.
TEST(NormalEquations, NearlyDependentColumnsGiveABoundedTrustedSolution) {
  for (int cols : {20, 40, 80, 160}) {
    const System s = vandermonde(cols, static_cast<uint32_t>(cols));
    const mme::NormalEquationsSolution got = mme::solveNormalEquations(s.ata(), s.atb(), s.btb());
    ASSERT_TRUE(got.trusted) << cols << " columns";
    EXPECT_TRUE(got.theta.allFinite());
    const double residual2 = s.residual2(got.theta);
    EXPECT_LT(residual2, 1e-6 * s.btb()) << cols << " columns: the fit explains the smooth data";
    EXPECT_NEAR(got.rss, residual2, 1e-9 * s.btb()) << "the reported residual is the true one";
    EXPECT_LT(got.theta.cwiseAbs().maxCoeff(), 1e4) << "no blow-up along the round-off directions";
  }
}

TEST(NormalEquations, AnExactlyRepeatedColumnIsShared) {
  System s = vandermonde(4, 1);
  Eigen::MatrixXd j(s.j.rows(), 5);
  j << s.j, s.j.col(2);  // column 4 = column 2
  s.j = j;
  const mme::NormalEquationsSolution got = mme::solveNormalEquations(s.ata(), s.atb(), s.btb());
  ASSERT_TRUE(got.trusted);
  // Equal halves up to the round-off the ridge leaves in the direction no row determines.
  EXPECT_NEAR(got.theta[2], got.theta[4], 1e-3 * std::fabs(got.theta[2]));
  const Eigen::VectorXd best = s.j.bdcSvd(Eigen::ComputeThinU | Eigen::ComputeThinV).solve(s.y);
  EXPECT_NEAR(s.residual2(got.theta), s.residual2(best), 1e-9 * s.btb());
}

TEST(NormalEquations, ColumnsAbsentOrNotAskedForStayZero) {
  System s = vandermonde(5, 2);
  s.j.col(3).setZero();  // no row touches column 3
  const mme::NormalEquationsSolution got =
      mme::solveNormalEquations(s.ata(), s.atb(), s.btb(), {0, 1, 3}, true);
  ASSERT_TRUE(got.trusted);
  EXPECT_EQ(got.theta[2], 0.0);
  EXPECT_EQ(got.theta[3], 0.0);
  EXPECT_EQ(got.theta[4], 0.0);
  EXPECT_EQ(got.scale[2], 0.0) << "column 3 (third asked for) is absent";
  ASSERT_EQ(got.inverse_scaled.rows(), 3);
  // The inverse is that of the scaled, regularised system over the columns asked for.
  Eigen::MatrixXd scaled(3, 3);
  const int cols[3] = {0, 1, 3};
  const Eigen::MatrixXd ata = s.ata();
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) scaled(a, b) = got.scale[a] * ata(cols[a], cols[b]) * got.scale[b];
  scaled.diagonal().array() += got.ridge;
  EXPECT_TRUE((scaled * got.inverse_scaled).isIdentity(1e-6));
}

// Large enough that the inverse is built by its blocked recursions (several levels of halves,
// odd sizes): it must still be the symmetric inverse of the scaled, regularised system.
TEST(NormalEquations, TheInverseOfALargeSystemIsSymmetricAndExact) {
  for (int cols : {49, 97, 203}) {
    std::mt19937 rng(static_cast<uint32_t>(cols));
    std::normal_distribution<double> unit(0.0, 1.0);
    System s{Eigen::MatrixXd(3 * cols, cols), Eigen::VectorXd(3 * cols)};
    for (int i = 0; i < s.j.rows(); ++i) {
      s.y[i] = unit(rng);
      for (int c = 0; c < cols; ++c) s.j(i, c) = unit(rng) * (1.0 + c);  // columns of unequal scale
    }
    std::vector<int> all(cols);
    for (int c = 0; c < cols; ++c) all[c] = c;
    const mme::NormalEquationsSolution got = mme::solveNormalEquations(s.ata(), s.atb(), s.btb(), all, true);
    ASSERT_TRUE(got.trusted);
    ASSERT_EQ(got.inverse_scaled.rows(), cols);
    EXPECT_TRUE(got.inverse_scaled.isApprox(got.inverse_scaled.transpose(), 1e-14)) << cols;
    const Eigen::MatrixXd scaled = got.scale.asDiagonal() * s.ata() * got.scale.asDiagonal() +
                                   got.ridge * Eigen::MatrixXd::Identity(cols, cols);
    EXPECT_TRUE((scaled * got.inverse_scaled).isIdentity(1e-9)) << cols;
  }
}

TEST(NormalEquations, NoColumnsGiveZeroAndTheWholeRightHandSide) {
  const System s = vandermonde(3, 4);
  const mme::NormalEquationsSolution got = mme::solveNormalEquations(s.ata(), s.atb(), s.btb(), {});
  EXPECT_TRUE(got.trusted);
  EXPECT_TRUE(got.theta.isZero());
  EXPECT_DOUBLE_EQ(got.rss, s.btb());
  EXPECT_EQ(got.inverse_scaled.size(), 0);
}

TEST(NormalEquations, ANonFiniteSystemIsNotTrusted) {
  const System s = vandermonde(3, 5);
  Eigen::MatrixXd ata = s.ata();
  ata(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(mme::solveNormalEquations(ata, s.atb(), s.btb()).trusted);
  EXPECT_FALSE(mme::solveNormalEquations(s.ata(), s.atb(), std::numeric_limits<double>::infinity()).trusted);
}

}  // namespace

// The parameters' covariance from a Jacobian (the one computation behind the one-step and the
// output-error estimators' standard deviations): linear least squares whose covariance is known
// in closed form, with and without nuisance columns; rank deficiency flags the right parameter.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <Eigen/Dense>

#include "motion_model_estimation/identification/estimators/covariance.h"
#include "test_helpers.h"

namespace {

/// A deterministic dense m x n Jacobian of full column rank with columns of different scales
/// (units): uniform entries in [-1, 1) from a fixed generator's raw output.
Eigen::MatrixXd denseJacobian(Eigen::Index m, Eigen::Index n) {
  std::mt19937_64 generator(38);
  Eigen::MatrixXd j(m, n);
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index k = 0; k < n; ++k)
      j(i, k) = (2.0 * static_cast<double>(generator() >> 11) * 0x1.0p-53 - 1.0) *
                std::pow(10.0, static_cast<double>(k % 3) - 1.0);
  return j;
}

Eigen::SparseMatrix<double> sparse(const Eigen::MatrixXd& dense) { return dense.sparseView(); }

double maxRelativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

// Without nuisance: Cov = s^2 (J^T J)^-1, the std its diagonal's root, nothing flagged.
TEST(Covariance, LinearModelMatchesTheClosedForm) {
  const Eigen::MatrixXd j = denseJacobian(30, 4);
  mme::CovarianceOptions options;
  options.residual_variance = 2.5e-3;
  const mme::ParameterCovariance c = mme::parameterCovariance(sparse(j), 4, options);
  ASSERT_TRUE(c.ok()) << c.failure;
  const Eigen::MatrixXd want = options.residual_variance * (j.transpose() * j).inverse();
  EXPECT_LT(maxRelativeDifference(c.covariance, want), 1e-10);
  for (Eigen::Index k = 0; k < 4; ++k) {
    EXPECT_NEAR(c.std_devs[k], std::sqrt(want(k, k)), 1e-10 * std::sqrt(want(k, k))) << k;
    EXPECT_FALSE(c.undetermined[static_cast<size_t>(k)]) << k;
  }
}

// Nuisance columns marginalised: the parameters' covariance is the parameter block of the whole
// problem's covariance (not the inverse of the parameters' block of J^T J, which is smaller).
TEST(Covariance, NuisanceColumnsAreMarginalised) {
  const Eigen::MatrixXd j = denseJacobian(40, 7);  // 3 parameters, 4 nuisance unknowns
  const mme::ParameterCovariance c = mme::parameterCovariance(sparse(j), 3);
  ASSERT_TRUE(c.ok()) << c.failure;
  const Eigen::MatrixXd whole = (j.transpose() * j).inverse();
  EXPECT_LT(maxRelativeDifference(c.covariance, whole.topLeftCorner(3, 3)), 1e-9);
  const Eigen::MatrixXd conditional = (j.leftCols(3).transpose() * j.leftCols(3)).inverse();
  for (Eigen::Index k = 0; k < 3; ++k) EXPECT_GT(c.std_devs[k], 1.001 * std::sqrt(conditional(k, k))) << k;
  // The same from the information matrix the marginalisation gives (the dense entry point).
  const Eigen::MatrixXd information = whole.topLeftCorner(3, 3).inverse();
  const mme::ParameterCovariance from_information = mme::covarianceFromInformation(information);
  EXPECT_LT(maxRelativeDifference(from_information.covariance, c.covariance), 1e-9);
}

// A parameter no residual depends on, and one the data determine only together with a nuisance
// unknown (the same column), are flagged with a NaN std; the others keep the std of the problem
// without them.
TEST(Covariance, RankDeficiencyFlagsTheRightParameters) {
  Eigen::MatrixXd j = denseJacobian(30, 6);  // parameters 0..3, nuisance 4..5
  j.col(1).setZero();
  j.col(3) = 2.0 * j.col(5);
  const mme::ParameterCovariance c = mme::parameterCovariance(sparse(j), 4);
  ASSERT_TRUE(c.ok()) << c.failure;
  EXPECT_FALSE(c.undetermined[0]);
  EXPECT_TRUE(c.undetermined[1]);
  EXPECT_FALSE(c.undetermined[2]);
  EXPECT_TRUE(c.undetermined[3]);
  EXPECT_TRUE(std::isnan(c.std_devs[1]));
  EXPECT_TRUE(std::isnan(c.std_devs[3]));
  // Parameters 0 and 2 with nuisance 4 and 5: the determined problem.
  Eigen::MatrixXd kept(j.rows(), 4);
  kept << j.col(0), j.col(2), j.col(4), j.col(5);
  const Eigen::MatrixXd want = (kept.transpose() * kept).inverse();
  EXPECT_NEAR(c.std_devs[0], std::sqrt(want(0, 0)), 1e-8 * std::sqrt(want(0, 0)));
  EXPECT_NEAR(c.std_devs[2], std::sqrt(want(1, 1)), 1e-8 * std::sqrt(want(1, 1)));
}

// Two collinear parameters (only a combination determined: the undetermined direction loads
// each by a half) are both flagged; the independent one is not.
TEST(Covariance, CollinearParametersAreFlagged) {
  Eigen::MatrixXd j = denseJacobian(25, 3);
  j.col(2) = -3.0 * j.col(0);
  const mme::ParameterCovariance c = mme::parameterCovariance(sparse(j), 3);
  ASSERT_TRUE(c.ok()) << c.failure;
  EXPECT_FALSE(c.undetermined[1]);
  EXPECT_TRUE(std::isfinite(c.std_devs[1]));
  EXPECT_TRUE(c.undetermined[0]);
  EXPECT_TRUE(c.undetermined[2]);
}

// Bad numbers give a reason and NaN, not a crash; inconsistent storage is refused by name.
TEST(Covariance, NonFiniteAndInconsistentInput) {
  Eigen::MatrixXd j = denseJacobian(10, 2);
  j(3, 1) = std::numeric_limits<double>::quiet_NaN();
  const mme::ParameterCovariance c = mme::parameterCovariance(sparse(j), 2);
  EXPECT_FALSE(c.ok());
  EXPECT_TRUE(std::isnan(c.std_devs[0]) && std::isnan(c.std_devs[1]));
  EXPECT_THROW(mme::parameterCovariance(sparse(denseJacobian(10, 2)), 3), std::invalid_argument);
  EXPECT_THROW(mme::sparseFromCompressedRows(2, 2, {0, 1, 2}, {0, 5}, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(mme::sparseFromCompressedRows(2, 2, {0, 1}, {0}, {1.0}), std::invalid_argument);
  const mme::ParameterCovariance none = mme::parameterCovariance(sparse(denseJacobian(10, 2)), 0);
  EXPECT_TRUE(none.ok());
  EXPECT_EQ(none.std_devs.size(), 0);
}

// Ceres' compressed rows become the same matrix.
TEST(Covariance, CompressedRowsConvert) {
  // [1 0 2; 0 0 0; 0 3 0]
  const Eigen::SparseMatrix<double> m =
      mme::sparseFromCompressedRows(3, 3, {0, 2, 2, 3}, {0, 2, 1}, {1.0, 2.0, 3.0});
  Eigen::MatrixXd want = Eigen::MatrixXd::Zero(3, 3);
  want(0, 0) = 1.0;
  want(0, 2) = 2.0;
  want(2, 1) = 3.0;
  EXPECT_EQ(Eigen::MatrixXd(m), want);
}

// Per gene: the search-space std times the physical slope; an undetermined column or a std
// larger than the value flags the gene; a gene in no column keeps NaN and no flag.
TEST(Covariance, GeneUncertaintyReadsPhysicalUnits) {
  mme::test::SmallObjectFixture f;
  const mme::ParameterSpace space(f.search, f.data);
  ASSERT_GE(space.size(), 4u);
  const std::vector<double> genes = space.toSearch(f.true_values);
  mme::ParameterCovariance c;
  c.covariance = Eigen::MatrixXd::Zero(3, 3);
  c.std_devs = Eigen::VectorXd(3);
  c.std_devs << 1e-3, std::numeric_limits<double>::quiet_NaN(), 1e6;
  c.undetermined = {0, 1, 0};
  const mme::GeneUncertainty u = mme::geneUncertainty(c, space, genes, {0, 1, 2});
  EXPECT_DOUBLE_EQ(u.std_devs[0], std::abs(space.physicalSlope(0, genes)) * 1e-3);
  EXPECT_FALSE(u.unidentifiable[0]);
  EXPECT_TRUE(std::isnan(u.std_devs[1]));
  EXPECT_TRUE(u.unidentifiable[1]);
  EXPECT_TRUE(u.unidentifiable[2]);  // std far above the value
  EXPECT_TRUE(std::isnan(u.std_devs[3]));
  EXPECT_FALSE(u.unidentifiable[3]);
  c.failure = "why";
  const mme::GeneUncertainty failed = mme::geneUncertainty(c, space, genes, {0, 1, 2});
  EXPECT_EQ(failed.failure, "why");
  EXPECT_TRUE(std::isnan(failed.std_devs[0]));
  EXPECT_FALSE(failed.unidentifiable[1]);
}

}  // namespace

// The sensor muscles' least squares (an internal unit of the muscle fit): the block-sparse
// factorisation, made once per pattern and reused, gives the dense solve's answer at every ridge,
// with the sign constraints' active set, and when rows are added to the same blocks.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "../../../src/identification/muscles/muscle_least_squares.h"

namespace {

using mme::sensor_muscles::SignConstraints;
using mme::sensor_muscles::System;

constexpr int kPerMuscle = 5;  // unknowns per muscle: 1 sensor (2 inputs) + 3
constexpr int kMuscles = 7;

/// Which muscles act on each particle: a chain with a few long links, as a body's bonds are.
const std::vector<std::vector<int>> kAtParticle = {{0, 1, 5}, {1, 2}, {2, 3, 6}, {3, 4, 5}, {4, 0, 6}};

/// The blocks the particles couple.
std::vector<std::vector<int>> coupledBelow() {
  std::vector<std::vector<int>> below(kMuscles);
  for (const std::vector<int>& muscles : kAtParticle)
    for (int m : muscles)
      for (int m2 : muscles)
        if (m2 <= m) below[m].push_back(m2);
  return below;
}

/// Adds `rows` random equations per particle, each touching only that particle's muscles.
/// (`dense`, when given: the same rows' whole normal matrix, accumulated densely.)
void addRows(int rows, unsigned seed, System* sys, Eigen::MatrixXd* dense = nullptr) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int n = kMuscles * kPerMuscle;
  mme::sensor_muscles::sizeSystem(mme::sensor_muscles::makeBlockPattern(kMuscles, kPerMuscle, coupledBelow()),
                                  sys);
  for (const std::vector<int>& muscles : kAtParticle)
    for (int r = 0; r < rows; ++r) {
      Eigen::VectorXd row = Eigen::VectorXd::Zero(n);
      for (int m : muscles)
        for (int j = 0; j < kPerMuscle; ++j) row(m * kPerMuscle + j) = normal(rng);
      // The truth alternates signs so that some own stiffnesses and dampings would be negative.
      double y = normal(rng);
      for (int j = 0; j < n; ++j) y += (j % 3 == 0 ? -1.0 : 1.0) * row(j);
      for (int m : muscles)
        for (int m2 : muscles)
          if (m2 <= m)
            sys->block(m, m2) += row.segment(m * kPerMuscle, kPerMuscle) *
                                 row.segment(m2 * kPerMuscle, kPerMuscle).transpose();
      if (dense) {
        if (dense->rows() == 0) *dense = Eigen::MatrixXd::Zero(n, n);
        *dense += row * row.transpose();
      }
      sys->atb += y * row;
      sys->btb += y * y;
      ++sys->rows;
    }
}

SignConstraints denseConstraints() {
  SignConstraints c;
  c.muscles = kMuscles;
  c.per_muscle = kPerMuscle;
  c.own_stiffness = 3;
  c.held_at_zero = {2 * kPerMuscle + 3};
  return c;
}

/// The same constraints solved as a sparse matrix: the sparse path.
SignConstraints sparseConstraints() {
  SignConstraints c = denseConstraints();
  c.sparse = true;
  c.cache = mme::sensor_muscles::makeSparseRidgeCache();
  return c;
}

TEST(MuscleLeastSquares, TheSparseFactorisationGivesTheDenseAnswerAtEveryRidge) {
  System sys;
  addRows(40, 1, &sys);
  const SignConstraints dense = denseConstraints(), sparse = sparseConstraints();
  int clamped_somewhere = 0;
  for (double ridge : {10.0, 1.0, 1e-2, 1e-4}) {
    Eigen::VectorXd a, b;
    ASSERT_TRUE(mme::sensor_muscles::solveRidge(sys, ridge, dense, &a));
    ASSERT_TRUE(mme::sensor_muscles::solveRidge(sys, ridge, sparse, &b));
    EXPECT_LT((a - b).norm(), 1e-9 * (1.0 + a.norm())) << "ridge " << ridge;
    EXPECT_EQ(b(2 * kPerMuscle + 3), 0.0);  // held at zero
    for (int m = 0; m < kMuscles; ++m) {
      EXPECT_GE(b(m * kPerMuscle + 3), 0.0);
      EXPECT_GE(b(m * kPerMuscle + 4), 0.0);
      clamped_somewhere += b(m * kPerMuscle + 3) == 0.0 || b(m * kPerMuscle + 4) == 0.0;
    }
  }
  EXPECT_GT(clamped_somewhere, 4);  // the active set was exercised, not only the plain solve
  // More rows on the same blocks (a rollout round): the kept factorisation still answers.
  addRows(10, 2, &sys);
  Eigen::VectorXd a, b;
  ASSERT_TRUE(mme::sensor_muscles::solveRidge(sys, 0.3, dense, &a));
  ASSERT_TRUE(mme::sensor_muscles::solveRidge(sys, 0.3, sparse, &b));
  EXPECT_LT((a - b).norm(), 1e-9 * (1.0 + a.norm()));
}

TEST(MuscleLeastSquares, TheBlocksHoldTheWholeNormalMatrixAndOnlyItsCoupledBlocks) {
  System sys;
  Eigen::MatrixXd dense;
  addRows(20, 3, &sys, &dense);
  // Stored: the coupled blocks on and below the diagonal, not the 28 of a dense lower triangle.
  EXPECT_EQ(sys.pattern->blocks, 20);
  EXPECT_EQ(static_cast<int>(sys.blocks.size()), sys.pattern->blocks);
  EXPECT_EQ(sys.pattern->find(2, 0), -1);  // muscles 0 and 2 never meet at a particle
  EXPECT_LT((sys.dense() - dense).norm(), 1e-12 * dense.norm());
  EXPECT_DOUBLE_EQ(sys.at(5, 30), dense(5, 30));
  EXPECT_DOUBLE_EQ(sys.at(30, 5), dense(30, 5));
  std::mt19937 rng(4);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd theta(kMuscles * kPerMuscle);
  for (int j = 0; j < theta.size(); ++j) theta(j) = normal(rng);
  EXPECT_LT((sys.times(theta) - dense * theta).norm(), 1e-12 * (dense * theta).norm());
  const double squares = sys.btb - 2.0 * theta.dot(sys.atb) + theta.dot(dense * theta);
  EXPECT_NEAR(mme::sensor_muscles::residualSquares(sys, theta), squares, 1e-10 * squares);
  EXPECT_NEAR(mme::sensor_muscles::meanDiagonal(sys), dense.diagonal().mean(), 1e-12 * dense.diagonal().mean());
}

}  // namespace

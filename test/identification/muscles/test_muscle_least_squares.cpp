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

/// Adds `rows` random equations per particle, each touching only that particle's muscles.
void addRows(int rows, unsigned seed, System* sys) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int n = kMuscles * kPerMuscle;
  if (sys->ata.rows() == 0) {
    sys->ata = Eigen::MatrixXd::Zero(n, n);
    sys->atb = Eigen::VectorXd::Zero(n);
  }
  for (const std::vector<int>& muscles : kAtParticle)
    for (int r = 0; r < rows; ++r) {
      Eigen::VectorXd row = Eigen::VectorXd::Zero(n);
      for (int m : muscles)
        for (int j = 0; j < kPerMuscle; ++j) row(m * kPerMuscle + j) = normal(rng);
      // The truth alternates signs so that some own stiffnesses and dampings would be negative.
      double y = normal(rng);
      for (int j = 0; j < n; ++j) y += (j % 3 == 0 ? -1.0 : 1.0) * row(j);
      sys->ata += row * row.transpose();
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

/// The same constraints with the blocks the particles couple: the sparse path.
SignConstraints sparseConstraints() {
  SignConstraints c = denseConstraints();
  c.coupled_below.assign(kMuscles, {});
  for (const std::vector<int>& muscles : kAtParticle)
    for (int m : muscles)
      for (int m2 : muscles)
        if (m2 <= m) c.coupled_below[m].push_back(m2);
  for (std::vector<int>& below : c.coupled_below) {
    std::sort(below.begin(), below.end());
    below.erase(std::unique(below.begin(), below.end()), below.end());
  }
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

}  // namespace

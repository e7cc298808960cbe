#include "muscle_least_squares.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace mme::sensor_muscles {

namespace {

constexpr int kMaxClampRounds = 6;

/// One ridge solve with the `clamped` columns held at 0; false when it fails.
bool solveClamped(const System& sys, double absolute_ridge, const std::vector<int>& clamped,
                  Eigen::VectorXd* theta) {
  Eigen::MatrixXd a = sys.ata;
  a.diagonal().array() += absolute_ridge;
  Eigen::VectorXd b = sys.atb;
  for (int j : clamped) {
    a.row(j).setZero();
    a.col(j).setZero();
    a(j, j) = 1.0;
    b(j) = 0.0;
  }
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(a);  // in place: one copy of the matrix
  if (llt.info() != Eigen::Success) return false;
  *theta = llt.solve(b);
  return theta->allFinite();
}

/// Adds the negative own stiffnesses and dampings to `clamped` (on the last round, sets them to
/// 0 instead); true when there was one.
bool clampNegatives(const SignConstraints& c, int round, Eigen::VectorXd* theta, std::vector<int>* clamped) {
  bool changed = false;
  for (int m = 0; m < c.muscles; ++m)
    for (int j = m * c.per_muscle + c.own_stiffness; j <= m * c.per_muscle + c.own_stiffness + 1; ++j)
      if ((*theta)(j) < 0.0) {
        if (round + 1 < kMaxClampRounds) clamped->push_back(j);
        else (*theta)(j) = 0.0;
        changed = true;
      }
  return changed;
}

}  // namespace

void sizeSystem(int unknowns, System* sys) {
  if (sys->ata.rows() != 0) return;
  sys->ata = Eigen::MatrixXd::Zero(unknowns, unknowns);
  sys->atb = Eigen::VectorXd::Zero(unknowns);
}

double meanDiagonal(const System& sys) { return std::max(sys.ata.diagonal().mean(), 1e-300); }

double residualRms(const System& sys, const Eigen::VectorXd& theta) {
  if (sys.rows == 0) return 0.0;
  const double r2 = sys.btb - 2.0 * theta.dot(sys.atb) + theta.dot(sys.ata * theta);
  return std::sqrt(std::max(0.0, r2) / static_cast<double>(sys.rows));
}

bool solveRidge(const System& sys, double ridge, const SignConstraints& constraints, Eigen::VectorXd* theta,
                double reference_diagonal) {
  const double mean_diagonal = reference_diagonal > 0.0 ? reference_diagonal : meanDiagonal(sys);
  std::vector<int> clamped = constraints.held_at_zero;
  for (int round = 0;; ++round) {
    if (!solveClamped(sys, ridge * mean_diagonal, clamped, theta)) return false;
    if (!constraints.nonnegative_own_spring) return true;
    const bool changed = clampNegatives(constraints, round, theta, &clamped);
    if (!changed || round + 1 >= kMaxClampRounds) return true;
  }
}

}  // namespace mme::sensor_muscles

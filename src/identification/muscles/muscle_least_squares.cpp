#include "muscle_least_squares.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>

namespace mme::sensor_muscles {

/// The sparse normal matrix's pattern (lower triangle of the coupled blocks) and its Cholesky
/// factor, whose ordering and symbolic analysis are kept across solves.
struct SparseRidgeCache {
  Eigen::SparseMatrix<double> lower;
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
  bool analysed = false;
};

std::shared_ptr<SparseRidgeCache> makeSparseRidgeCache() { return std::make_shared<SparseRidgeCache>(); }

namespace {

constexpr int kMaxClampRounds = 6;

/// The lower triangle of the blocks `c.coupled_below` names, values unset.
Eigen::SparseMatrix<double> blockPattern(const SignConstraints& c) {
  const int k = c.per_muscle;
  std::vector<Eigen::Triplet<double>> entries;
  for (int m = 0; m < static_cast<int>(c.coupled_below.size()); ++m)
    for (int m2 : c.coupled_below[m])
      for (int col = m2 * k; col < (m2 + 1) * k; ++col)
        for (int row = std::max(m * k, col); row < (m + 1) * k; ++row) entries.emplace_back(row, col, 0.0);
  const int n = c.muscles * k;
  Eigen::SparseMatrix<double> lower(n, n);
  lower.setFromTriplets(entries.begin(), entries.end());
  lower.makeCompressed();
  return lower;
}

/// The sparse twin of solveClamped: the normal matrix's coupled blocks copied into the cached
/// pattern, the ridge on the diagonal, the clamped rows and columns replaced by the identity's.
bool solveClampedSparse(const System& sys, double absolute_ridge, const std::vector<int>& clamped,
                        const SignConstraints& c, Eigen::VectorXd* theta) {
  SparseRidgeCache& cache = *c.cache;
  if (cache.lower.rows() == 0) cache.lower = blockPattern(c);
  std::vector<char> is_clamped(sys.atb.size(), 0);
  for (int j : clamped) is_clamped[j] = 1;
  Eigen::SparseMatrix<double>& a = cache.lower;
  for (int col = 0; col < a.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, col); it; ++it) {
      const int row = static_cast<int>(it.row());
      if (is_clamped[row] || is_clamped[col]) it.valueRef() = row == col ? 1.0 : 0.0;
      else it.valueRef() = sys.ata(row, col) + (row == col ? absolute_ridge : 0.0);
    }
  if (!cache.analysed) {
    cache.llt.analyzePattern(a);
    cache.analysed = true;
  }
  cache.llt.factorize(a);
  if (cache.llt.info() != Eigen::Success) return false;
  Eigen::VectorXd b = sys.atb;
  for (int j : clamped) b(j) = 0.0;
  *theta = cache.llt.solve(b);
  return theta->allFinite();
}

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
  const bool sparse = !constraints.coupled_below.empty() && constraints.cache &&
                      static_cast<int>(sys.atb.size()) == constraints.muscles * constraints.per_muscle;
  for (int round = 0;; ++round) {
    const bool solved = sparse ? solveClampedSparse(sys, ridge * mean_diagonal, clamped, constraints, theta)
                               : solveClamped(sys, ridge * mean_diagonal, clamped, theta);
    if (!solved) return false;
    if (!constraints.nonnegative_own_spring) return true;
    const bool changed = clampNegatives(constraints, round, theta, &clamped);
    if (!changed || round + 1 >= kMaxClampRounds) return true;
  }
}

}  // namespace mme::sensor_muscles

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

/// The lower triangle of the pattern's blocks, values unset.
Eigen::SparseMatrix<double> blockPattern(const BlockPattern& p) {
  const int k = p.per_muscle;
  std::vector<Eigen::Triplet<double>> entries;
  for (int m = 0; m < p.muscles; ++m)
    for (int m2 : p.coupled_below[m])
      for (int col = m2 * k; col < (m2 + 1) * k; ++col)
        for (int row = std::max(m * k, col); row < (m + 1) * k; ++row) entries.emplace_back(row, col, 0.0);
  const int n = p.muscles * k;
  Eigen::SparseMatrix<double> lower(n, n);
  lower.setFromTriplets(entries.begin(), entries.end());
  lower.makeCompressed();
  return lower;
}

/// The sparse twin of solveClamped: the system's blocks copied into the cached pattern, the
/// ridge on the diagonal, the clamped rows and columns replaced by the identity's.
bool solveClampedSparse(const System& sys, double absolute_ridge, const std::vector<int>& clamped,
                        const SignConstraints& c, Eigen::VectorXd* theta) {
  SparseRidgeCache& cache = *c.cache;
  const BlockPattern& p = *sys.pattern;
  const int k = p.per_muscle;
  if (cache.lower.rows() == 0) cache.lower = blockPattern(p);
  std::vector<char> is_clamped(sys.atb.size(), 0);
  for (int j : clamped) is_clamped[j] = 1;
  Eigen::SparseMatrix<double>& a = cache.lower;
  for (int col = 0; col < a.outerSize(); ++col) {
    const int m2 = col / k;
    int m = -1;
    const Eigen::MatrixXd* block = nullptr;
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, col); it; ++it) {
      const int row = static_cast<int>(it.row());
      if (row / k != m) {  // rows run down the column: one lookup per block
        m = row / k;
        block = &sys.blocks[p.find(m, m2)];
      }
      if (is_clamped[row] || is_clamped[col]) it.valueRef() = row == col ? 1.0 : 0.0;
      else it.valueRef() = (*block)(row - m * k, col - m2 * k) + (row == col ? absolute_ridge : 0.0);
    }
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
  Eigen::MatrixXd a = sys.dense();
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

int BlockPattern::find(int m, int m2) const {
  const std::vector<int>& below = coupled_below[m];
  const auto it = std::lower_bound(below.begin(), below.end(), m2);
  if (it == below.end() || *it != m2) return -1;
  return slot[m][it - below.begin()];
}

std::shared_ptr<const BlockPattern> makeBlockPattern(int muscles, int per_muscle,
                                                     std::vector<std::vector<int>> coupled_below) {
  auto p = std::make_shared<BlockPattern>();
  p->muscles = muscles;
  p->per_muscle = per_muscle;
  coupled_below.resize(muscles);
  p->slot.assign(muscles, {});
  for (int m = 0; m < muscles; ++m) {
    std::vector<int>& below = coupled_below[m];
    std::sort(below.begin(), below.end());
    below.erase(std::unique(below.begin(), below.end()), below.end());
    for (size_t j = 0; j < below.size(); ++j) p->slot[m].push_back(p->blocks++);
  }
  p->coupled_below = std::move(coupled_below);
  return p;
}

double System::at(int row, int col) const {
  if (row < col) std::swap(row, col);
  const int k = pattern->per_muscle;
  const int slot = pattern->find(row / k, col / k);
  return slot < 0 ? 0.0 : blocks[slot](row % k, col % k);
}

Eigen::VectorXd System::times(const Eigen::VectorXd& theta) const {
  const BlockPattern& p = *pattern;
  const int k = p.per_muscle;
  Eigen::VectorXd out = Eigen::VectorXd::Zero(theta.size());
  for (int m = 0; m < p.muscles; ++m)
    for (size_t j = 0; j < p.coupled_below[m].size(); ++j) {
      const int m2 = p.coupled_below[m][j];
      const Eigen::MatrixXd& b = blocks[p.slot[m][j]];
      out.segment(m * k, k).noalias() += b * theta.segment(m2 * k, k);
      if (m2 != m) out.segment(m2 * k, k).noalias() += b.transpose() * theta.segment(m * k, k);
    }
  return out;
}

Eigen::MatrixXd System::dense() const {
  const BlockPattern& p = *pattern;
  const int k = p.per_muscle;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(unknowns(), unknowns());
  for (int m = 0; m < p.muscles; ++m)
    for (size_t j = 0; j < p.coupled_below[m].size(); ++j) {
      const int m2 = p.coupled_below[m][j];
      a.block(m * k, m2 * k, k, k) = blocks[p.slot[m][j]];
      if (m2 != m) a.block(m2 * k, m * k, k, k) = blocks[p.slot[m][j]].transpose();
    }
  return a;
}

void sizeSystem(const std::shared_ptr<const BlockPattern>& pattern, System* sys) {
  if (sys->pattern) return;
  sys->pattern = pattern;
  const int k = pattern->per_muscle;
  sys->blocks.assign(pattern->blocks, Eigen::MatrixXd::Zero(k, k));
  sys->atb = Eigen::VectorXd::Zero(pattern->muscles * k);
}

double meanDiagonal(const System& sys) {
  if (!sys.pattern || sys.unknowns() == 0) return 1e-300;
  const int k = sys.pattern->per_muscle;
  double sum = 0.0;
  for (int m = 0; m < sys.pattern->muscles; ++m) {
    const int slot = sys.pattern->find(m, m);
    if (slot >= 0) sum += sys.blocks[slot].trace();
  }
  return std::max(sum / (static_cast<double>(sys.pattern->muscles) * k), 1e-300);
}

double residualSquares(const System& sys, const Eigen::VectorXd& theta) {
  if (sys.rows == 0) return 0.0;
  return std::max(0.0, sys.btb - 2.0 * theta.dot(sys.atb) + theta.dot(sys.times(theta)));
}

double residualRms(const System& sys, const Eigen::VectorXd& theta) {
  if (sys.rows == 0) return 0.0;
  return std::sqrt(residualSquares(sys, theta) / static_cast<double>(sys.rows));
}

bool solveRidge(const System& sys, double ridge, const SignConstraints& constraints, Eigen::VectorXd* theta,
                double reference_diagonal) {
  const double mean_diagonal = reference_diagonal > 0.0 ? reference_diagonal : meanDiagonal(sys);
  std::vector<int> clamped = constraints.held_at_zero;
  const bool sparse = constraints.sparse && constraints.cache;
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

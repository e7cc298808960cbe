#include "motion_model_estimation/identification/estimators/normal_equations.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace mme {

namespace {

/// Ridges tried in turn, relative to the unit diagonal. The first sits above the round-off of
/// a Gram matrix of a few thousand columns (n eps ~ 1e-13) and far below any direction a
/// window's data determine; the later ones only serve systems whose first solve is rejected.
constexpr double kRidges[] = {1e-12, 1e-10, 1e-8, 1e-6, 1e-4};
/// Refinement steps toward the unregularised solution (iterated Tikhonov): a direction of
/// eigenvalue w keeps a relative bias of (ridge / (w + ridge))^(steps + 1).
constexpr int kRefinementSteps = 2;
/// A column whose diagonal is below this share of the largest is absent (its scaling would
/// overflow).
constexpr double kAbsentColumn = 1e-30;
/// A trusted residual is at most the right-hand side's, within the round-off of forming it.
constexpr double kResidualSlack = 1e-6;
/// Blocks at most this size are inverted directly by the recursions below.
constexpr Eigen::Index kDirectBlock = 48;

/// Replaces the lower-triangular `l` by its inverse (the strict upper part set to 0), by halves:
/// inv([L11 0; L21 L22]) = [L11^-1 0; -L22^-1 L21 L11^-1 L22^-1]. A sixth of n^3 multiply-adds,
/// where solving L X = I column by column costs half of n^3.
void invertLowerInPlace(Eigen::Ref<Eigen::MatrixXd> l) {
  const Eigen::Index n = l.rows();
  if (n <= kDirectBlock) {
    Eigen::MatrixXd inv = Eigen::MatrixXd::Identity(n, n);
    l.triangularView<Eigen::Lower>().solveInPlace(inv);
    l = inv.triangularView<Eigen::Lower>();
    return;
  }
  const Eigen::Index n1 = n / 2, n2 = n - n1;
  invertLowerInPlace(l.topLeftCorner(n1, n1));
  invertLowerInPlace(l.bottomRightCorner(n2, n2));
  l.topRightCorner(n1, n2).setZero();
  const Eigen::MatrixXd t = l.bottomRightCorner(n2, n2).triangularView<Eigen::Lower>() * l.bottomLeftCorner(n2, n1);
  l.bottomLeftCorner(n2, n1).noalias() = -(t * l.topLeftCorner(n1, n1).triangularView<Eigen::Lower>());
}

/// The lower triangle of U^T U for a lower-triangular `u`, in place of `u` (by halves:
/// [U11^T U11 + U21^T U21, .; U22^T U21, U22^T U22]), a sixth of n^3 multiply-adds.
void lowerGramInPlace(Eigen::Ref<Eigen::MatrixXd> u) {
  const Eigen::Index n = u.rows();
  if (n <= kDirectBlock) {
    const Eigen::MatrixXd lower = u.triangularView<Eigen::Lower>();
    u.noalias() = lower.transpose() * lower;
    return;
  }
  const Eigen::Index n1 = n / 2, n2 = n - n1;
  lowerGramInPlace(u.topLeftCorner(n1, n1));
  u.topLeftCorner(n1, n1).selfadjointView<Eigen::Lower>().rankUpdate(u.bottomLeftCorner(n2, n1).transpose());
  u.bottomLeftCorner(n2, n1) =
      u.bottomRightCorner(n2, n2).triangularView<Eigen::Lower>().transpose() * u.bottomLeftCorner(n2, n1);
  lowerGramInPlace(u.bottomRightCorner(n2, n2));
}

/// The inverse of the matrix `llt` factorised, (L L^T)^-1 = L^-T L^-1: a third of the work of
/// solving for the identity, which dominated structure selection's solves of a thousand
/// columns.
Eigen::MatrixXd inverseFromCholesky(const Eigen::LLT<Eigen::MatrixXd>& llt) {
  Eigen::MatrixXd inv = llt.matrixL();
  invertLowerInPlace(inv);
  lowerGramInPlace(inv);
  return inv.selfadjointView<Eigen::Lower>();
}

}  // namespace

NormalEquationsSolution solveNormalEquations(const Eigen::MatrixXd& ata, const Eigen::VectorXd& atb,
                                             double btb, const std::vector<int>& columns,
                                             bool want_inverse) {
  const int m = static_cast<int>(columns.size());
  NormalEquationsSolution out;
  out.theta = Eigen::VectorXd::Zero(atb.size());
  out.scale = Eigen::VectorXd::Zero(m);
  out.rss = std::max(0.0, btb);
  if (m == 0) {
    out.trusted = std::isfinite(btb);
    out.inverse_scaled.resize(0, 0);
    return out;
  }
  double largest = 0.0;
  for (int c : columns) largest = std::max(largest, ata(c, c));
  for (int i = 0; i < m; ++i) {
    const double d = ata(columns[i], columns[i]);
    out.scale[i] = d > kAbsentColumn * largest ? 1.0 / std::sqrt(d) : 0.0;
  }
  Eigen::MatrixXd a(m, m);
  Eigen::VectorXd b(m);
  for (int j = 0; j < m; ++j) {
    b[j] = out.scale[j] * atb[columns[j]];
    for (int i = 0; i < m; ++i) a(i, j) = out.scale[i] * ata(columns[i], columns[j]) * out.scale[j];
  }
  if (!a.allFinite() || !b.allFinite() || !std::isfinite(btb)) return out;
  for (double ridge : kRidges) {
    Eigen::MatrixXd regularised = a;
    regularised.diagonal().array() += ridge;
    const Eigen::LLT<Eigen::MatrixXd> llt(regularised);
    if (llt.info() != Eigen::Success) continue;  // round-off made it indefinite: a larger ridge
    Eigen::VectorXd theta_s = llt.solve(b);
    for (int step = 0; step < kRefinementSteps; ++step) theta_s += llt.solve(b - a * theta_s);
    const double rss = btb - 2.0 * theta_s.dot(b) + theta_s.dot(a * theta_s);
    if (!theta_s.allFinite() || !std::isfinite(rss) || rss > btb * (1.0 + kResidualSlack)) continue;
    out.ridge = ridge;
    out.rss = std::max(0.0, rss);
    out.trusted = true;
    for (int i = 0; i < m; ++i) out.theta[columns[i]] = out.scale[i] * theta_s[i];
    if (want_inverse) out.inverse_scaled = inverseFromCholesky(llt);
    return out;
  }
  return out;
}

NormalEquationsSolution solveNormalEquations(const Eigen::MatrixXd& ata, const Eigen::VectorXd& atb,
                                             double btb) {
  std::vector<int> all(static_cast<size_t>(atb.size()));
  std::iota(all.begin(), all.end(), 0);
  return solveNormalEquations(ata, atb, btb, all, false);
}

}  // namespace mme

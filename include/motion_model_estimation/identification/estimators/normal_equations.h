// Linear least squares from its normal equations (A^T A, A^T b, b^T b), solved so that a
// system the data do not fully determine still gives a bounded answer that can be trusted.
//
// The equation error's systems (structure selection, the identifier's seeds) hold hundreds to
// thousands of columns, many nearly collinear on a short real window. A column-pivoted QR of
// such a Gram matrix is not reliably rank-revealing: truncated at a pivot threshold it returned
// solutions whose residual was 10^13 times the right-hand side's. Here every column is scaled
// to a unit diagonal and the system is solved by Cholesky with a small ridge (Tikhonov), then
// refined toward the unregularised solution; directions the data determine come out as the
// exact least squares, directions at round-off level stay near zero. A solve whose residual
// exceeds the right-hand side's (impossible for a least-squares solution, so round-off) is
// rejected and solved again with a larger ridge.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace mme {

struct NormalEquationsSolution {
  /// The solution per column of the system (0 for columns not solved or absent).
  Eigen::VectorXd theta;
  /// Per solved column (in the order of `columns`): 1 / sqrt(A^T A's diagonal), 0 for a column
  /// no row touches (held at 0).
  Eigen::VectorXd scale;
  /// (D A D + ridge I)^-1 over the solved columns, D = diag(scale), when asked for.
  Eigen::MatrixXd inverse_scaled;
  /// The ridge that gave a trusted solve, relative to the scaled unit diagonal.
  double ridge = 0.0;
  /// |A theta - b|^2 from the normal equations (b^T b - 2 theta^T A^T b + theta^T A^T A theta).
  double rss = 0.0;
  /// False when no ridge gave a finite solution with a residual at most the right-hand side's;
  /// theta is then 0.
  bool trusted = false;
};

/// Solves the columns `columns` (indices into the system) of the normal equations; the other
/// columns stay 0. An empty `columns` gives theta = 0, rss = b^T b. `want_inverse` also returns
/// the scaled inverse (for covariances and downdates).
NormalEquationsSolution solveNormalEquations(const Eigen::MatrixXd& ata, const Eigen::VectorXd& atb,
                                             double btb, const std::vector<int>& columns,
                                             bool want_inverse = false);

/// The same over every column.
NormalEquationsSolution solveNormalEquations(const Eigen::MatrixXd& ata, const Eigen::VectorXd& atb,
                                             double btb);

}  // namespace mme

// The Jacobian of the cost's residuals with respect to the search-space genes, by forward
// differences, and the Gauss-Newton normal equations built from it. Two users need the same
// derivatives: the Levenberg-Marquardt refinement (ceres_levenberg_marquardt.h, which hands the
// columns to Ceres) and the identifier's parameter standard deviations (covariance.h at the answer).
// One residual evaluation per gene, columns computed in parallel (each column is independent: the
// result does not depend on the thread count). A gene moves only the terms near its bond type's
// sites, and the other entries of a forward difference are exactly zero, so the Jacobian is kept
// by sparse columns: that bounds memory on large models and makes J^T J cost the sum over terms
// of (genes moving the term)^2 instead of terms x genes^2.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "motion_model_estimation/core/cost.h"
#include "motion_model_estimation/core/thread_pool.h"
#include "motion_model_estimation/identification/search/parameter_space.h"

namespace mme {

/// A Jacobian (m rows x n genes) by sparse columns: the row indices of each column ascending and
/// its non-zero values.
struct ResidualJacobian {
  size_t rows_count = 0;                      ///< m
  std::vector<std::vector<uint32_t>> rows;    ///< per gene
  std::vector<std::vector<double>> values;    ///< per gene, same length as rows[k]
  size_t nonZeros() const;
  /// J^T r.
  Eigen::VectorXd gradient(const Eigen::VectorXd& residual) const;
  /// J as an Eigen sparse matrix (m x n).
  Eigen::SparseMatrix<double> toSparse() const;
};

/// The forward-difference step of a gene at x (search space): relative to the gene, or to its
/// range near 0; negative (inward) when a forward step would leave the upper bound.
double forwardDifferenceStep(const Gene& gene, double x);

/// Forward-difference Jacobian of cost.residuals() (in search space) at genes x, whose residuals
/// are `residual`, over the genes `active` (column j = gene active[j]); one residual evaluation
/// per column, columns in parallel on `pool` (may be null). A column whose model blew up is left
/// empty (that gene is held for the step). False when the stored entries exceeded max_entries
/// (the columns are then incomplete).
bool forwardJacobian(const Cost& cost, const ParameterSpace& space, const std::vector<double>& x,
                     const Eigen::VectorXd& residual, const std::vector<size_t>& active,
                     uint64_t max_entries, ThreadPool* pool, ResidualJacobian* jac);

enum class NormalEquationsPath { kAuto, kDense, kSparse };

/// J^T J (dense n x n, symmetric) and J^T r. kAuto: a dense m x n matrix and Eigen's blocked
/// product when at least a quarter of J is stored (and m x n fits in 64 MB), else the outer
/// products of J's rows (cost: the sum over rows of their non-zeros squared).
void normalEquations(const ResidualJacobian& jac, const Eigen::VectorXd& residual,
                     Eigen::MatrixXd* jtj, Eigen::VectorXd* g,
                     NormalEquationsPath path = NormalEquationsPath::kAuto);

}  // namespace mme

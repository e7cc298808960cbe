// The parameters' covariance at a least-squares optimum, one computation for every estimator that
// reports standard deviations: the one-step cost (its forward-difference Jacobian over the genes)
// and the output error (Ceres' Jacobian over the genes and the shooting segments' start states).
//
// Gauss-Newton: Cov = s^2 I^+, I the parameters' Fisher information J^T J with the nuisance
// unknowns marginalised (the Schur complement I = A - B C^-1 B^T of J^T J = [A B; B^T C], so that
// their uncertainty propagates into the parameters'), s^2 the residual variance the caller knows
// (from the residuals at the optimum, or a given noise for a Cramer-Rao bound). The information is
// scaled to a unit diagonal before its eigen-decomposition, so that parameters of different units
// compare; a direction whose relative eigenvalue is below a floor is one the data do not
// determine: it is left out of the pseudo-inverse, and a parameter that takes part in such a
// direction is flagged instead of being given an enormous or meaningless std.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "motion_model_estimation/identification/search/parameter_space.h"

namespace mme {

struct CovarianceOptions {
  /// s^2, the residuals' variance the covariance is scaled by (the residuals' unit squared;
  /// 1 when the residuals are already whitened by the noise the bound assumes).
  double residual_variance = 1.0;
  /// A direction of the unit-diagonal information whose eigenvalue is below this share of the
  /// largest is undetermined by the data.
  double relative_eigenvalue_floor = 1e-10;
  /// A parameter whose unit vector puts more than this share of its weight (squared components)
  /// in the undetermined directions is undetermined itself. Exactly undetermined combinations
  /// load only the parameters in them (two collinear parameters: a half each), and round-off
  /// mixes the others in far below this share.
  double undetermined_loading = 0.01;
};

struct ParameterCovariance {
  /// Empty when computed; else why not (every std is then NaN).
  std::string failure;
  /// Over the parameter columns, in the Jacobian's column units (undetermined directions out).
  Eigen::MatrixXd covariance;
  /// 1-sigma per parameter column: the covariance diagonal's root; NaN where undetermined.
  Eigen::VectorXd std_devs;
  /// Per parameter column: no residual depends on it, or it takes part in a combination the data
  /// do not determine (CovarianceOptions::undetermined_loading).
  std::vector<uint8_t> undetermined;
  bool ok() const { return failure.empty(); }
};

/// From a Jacobian (rows: residuals) whose first `parameter_columns` columns are the parameters
/// and whose other columns are nuisance unknowns, marginalised.
ParameterCovariance parameterCovariance(const Eigen::SparseMatrix<double>& jacobian,
                                        Eigen::Index parameter_columns,
                                        const CovarianceOptions& options = {});

/// From the parameters' information matrix (symmetric; any nuisance already marginalised).
ParameterCovariance covarianceFromInformation(const Eigen::MatrixXd& information,
                                              const CovarianceOptions& options = {});

/// A matrix in compressed-row storage (the fields of Ceres' CRSMatrix) as an Eigen sparse matrix;
/// inconsistent storage (indices outside the matrix, row starts not ascending) throws
/// std::invalid_argument.
Eigen::SparseMatrix<double> sparseFromCompressedRows(int rows, int cols, const std::vector<int>& row_starts,
                                                     const std::vector<int>& column_indices,
                                                     const std::vector<double>& values);

/// The covariance read per gene of a parameter space.
struct GeneUncertainty {
  std::vector<double> std_devs;         ///< physical units; NaN where not defined
  std::vector<uint8_t> unidentifiable;  ///< 1: the data do not determine it
  std::string failure;                  ///< why every std is NaN; empty when computed
};

/// Column j of `covariance` is gene column_genes[j] (search space, at `genes`). A gene's physical
/// std is its search-space std times the gene's physical slope there (a log gene's value, a
/// clamp length's 1 + tau). A gene is unidentifiable when its column is undetermined or its std
/// exceeds its value's magnitude (the data cannot tell it from zero). Genes in no column: NaN std,
/// not flagged; a failed covariance: NaN everywhere, nothing flagged.
GeneUncertainty geneUncertainty(const ParameterCovariance& covariance, const ParameterSpace& space,
                                const std::vector<double>& genes, const std::vector<size_t>& column_genes);

}  // namespace mme

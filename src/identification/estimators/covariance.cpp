#include "motion_model_estimation/identification/estimators/covariance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>

namespace mme {

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

bool allFinite(const Eigen::SparseMatrix<double>& m) {
  for (Eigen::Index c = 0; c < m.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(m, c); it; ++it)
      if (!std::isfinite(it.value())) return false;
  return true;
}

ParameterCovariance failed(Eigen::Index parameters, const std::string& why) {
  ParameterCovariance out;
  out.failure = why;
  out.covariance = Eigen::MatrixXd::Constant(parameters, parameters, kNan);
  out.std_devs = Eigen::VectorXd::Constant(parameters, kNan);
  out.undetermined.assign(static_cast<size_t>(parameters), 0);
  return out;
}

}  // namespace

ParameterCovariance parameterCovariance(const Eigen::SparseMatrix<double>& jacobian,
                                        Eigen::Index parameter_columns, const CovarianceOptions& options) {
  const Eigen::Index np = parameter_columns;
  if (np < 0 || np > jacobian.cols())
    throw std::invalid_argument("parameterCovariance: " + std::to_string(np) + " parameter columns of " +
                                std::to_string(jacobian.cols()));
  if (!allFinite(jacobian)) return failed(np, "the Jacobian has a non-finite entry");
  const Eigen::Index nuisance = jacobian.cols() - np;
  const Eigen::SparseMatrix<double> jtj = Eigen::SparseMatrix<double>(jacobian.transpose() * jacobian);
  Eigen::MatrixXd information = Eigen::MatrixXd(jtj.topLeftCorner(np, np));
  if (nuisance > 0) {
    // Marginalise: I = A - B C^-1 B^T. C is sparse (a shooting segment's states meet only their
    // neighbours'), B dense enough to keep as a matrix of parameter rows.
    const Eigen::MatrixXd b = Eigen::MatrixXd(jtj.topRightCorner(np, nuisance));
    const Eigen::SparseMatrix<double> c = jtj.bottomRightCorner(nuisance, nuisance);
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(c);
    if (ldlt.info() != Eigen::Success)
      return failed(np, "the nuisance unknowns' information could not be factorised "
                        "(the data do not determine them)");
    information -= b * ldlt.solve(Eigen::MatrixXd(b.transpose()));
  }
  return covarianceFromInformation(information, options);
}

ParameterCovariance covarianceFromInformation(const Eigen::MatrixXd& information,
                                              const CovarianceOptions& options) {
  const Eigen::Index np = information.rows();
  if (information.cols() != np)
    throw std::invalid_argument("covarianceFromInformation: the information matrix is not square");
  if (!information.allFinite()) return failed(np, "the information matrix has a non-finite entry");
  ParameterCovariance out;
  out.covariance = Eigen::MatrixXd::Zero(np, np);
  out.std_devs = Eigen::VectorXd::Constant(np, kNan);
  out.undetermined.assign(static_cast<size_t>(np), 0);
  if (np == 0) return out;
  // Unit diagonal: d_k = 1 / sqrt(I_kk), 0 for a column no residual depends on.
  Eigen::VectorXd d = information.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (Eigen::Index k = 0; k < np; ++k) d[k] = d[k] > 0.0 ? 1.0 / d[k] : 0.0;
  const Eigen::MatrixXd scaled = d.asDiagonal() * information * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
  if (eig.info() != Eigen::Success) return failed(np, "the information matrix's eigen-decomposition failed");
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const double top = std::max(lambda.maxCoeff(), 1e-300);
  Eigen::MatrixXd pseudo_inverse = Eigen::MatrixXd::Zero(np, np);
  Eigen::VectorXd null_loading = Eigen::VectorXd::Zero(np);
  for (Eigen::Index q = 0; q < np; ++q) {
    const Eigen::VectorXd v = eig.eigenvectors().col(q);
    if (lambda[q] > options.relative_eigenvalue_floor * top) pseudo_inverse += v * v.transpose() / lambda[q];
    else null_loading += v.cwiseProduct(v);
  }
  out.covariance = options.residual_variance * (d.asDiagonal() * pseudo_inverse * d.asDiagonal());
  for (Eigen::Index k = 0; k < np; ++k) {
    if (null_loading[k] > options.undetermined_loading || !(d[k] > 0.0)) {
      out.undetermined[static_cast<size_t>(k)] = 1;
      continue;
    }
    out.std_devs[k] = std::sqrt(std::max(out.covariance(k, k), 0.0));
  }
  return out;
}

Eigen::SparseMatrix<double> sparseFromCompressedRows(int rows, int cols, const std::vector<int>& row_starts,
                                                     const std::vector<int>& column_indices,
                                                     const std::vector<double>& values) {
  if (rows < 0 || cols < 0 || row_starts.size() != static_cast<size_t>(rows) + 1 || row_starts.front() != 0 ||
      column_indices.size() != values.size() || static_cast<size_t>(row_starts.back()) != values.size())
    throw std::invalid_argument("sparseFromCompressedRows: the row starts do not match the entries");
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(values.size());
  for (int row = 0; row < rows; ++row) {
    if (row_starts[row + 1] < row_starts[row])
      throw std::invalid_argument("sparseFromCompressedRows: row starts not ascending at row " +
                                  std::to_string(row));
    for (int e = row_starts[row]; e < row_starts[row + 1]; ++e) {
      if (column_indices[e] < 0 || column_indices[e] >= cols)
        throw std::invalid_argument("sparseFromCompressedRows: column " + std::to_string(column_indices[e]) +
                                    " outside " + std::to_string(cols) + " columns");
      entries.emplace_back(row, column_indices[e], values[e]);
    }
  }
  Eigen::SparseMatrix<double> m(rows, cols);
  m.setFromTriplets(entries.begin(), entries.end());
  return m;
}

GeneUncertainty geneUncertainty(const ParameterCovariance& covariance, const ParameterSpace& space,
                                const std::vector<double>& genes, const std::vector<size_t>& column_genes) {
  GeneUncertainty out;
  out.std_devs.assign(genes.size(), kNan);
  out.unidentifiable.assign(genes.size(), 0);
  out.failure = covariance.failure;
  if (!covariance.ok()) return out;
  const std::vector<double> values = space.toPhysical(genes);
  for (size_t j = 0; j < column_genes.size(); ++j) {
    const size_t gene = column_genes[j];
    if (covariance.undetermined[j]) {
      out.unidentifiable[gene] = 1;
      continue;
    }
    const double sd =
        std::abs(space.physicalSlope(gene, genes)) * covariance.std_devs[static_cast<Eigen::Index>(j)];
    out.std_devs[gene] = sd;
    if (sd > std::abs(values[gene])) out.unidentifiable[gene] = 1;
  }
  return out;
}

}  // namespace mme

#include "motion_model_estimation/identification/search/residual_jacobian.h"

#include <Eigen/Dense>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace mme {

double forwardDifferenceStep(const Gene& gene, double x) {
  const double h = 1e-7 * std::max({std::fabs(x), 1e-3 * (gene.upper - gene.lower), 1e-8});
  return x + h > gene.upper ? -h : h;
}

size_t ResidualJacobian::nonZeros() const {
  size_t stored = 0;
  for (const auto& column : rows) stored += column.size();
  return stored;
}

Eigen::VectorXd ResidualJacobian::gradient(const Eigen::VectorXd& residual) const {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(rows.size()));
  for (size_t k = 0; k < rows.size(); ++k)
    for (size_t e = 0; e < rows[k].size(); ++e)
      g[static_cast<Eigen::Index>(k)] += values[k][e] * residual[rows[k][e]];
  return g;
}

Eigen::SparseMatrix<double> ResidualJacobian::toSparse() const {
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(nonZeros());
  for (size_t k = 0; k < rows.size(); ++k)
    for (size_t e = 0; e < rows[k].size(); ++e)
      entries.emplace_back(static_cast<Eigen::Index>(rows[k][e]), static_cast<Eigen::Index>(k), values[k][e]);
  Eigen::SparseMatrix<double> j(static_cast<Eigen::Index>(rows_count),
                                static_cast<Eigen::Index>(rows.size()));
  j.setFromTriplets(entries.begin(), entries.end());
  return j;
}

void normalEquations(const ResidualJacobian& jac, const Eigen::VectorXd& residual,
                     Eigen::MatrixXd* jtj, Eigen::VectorXd* g, NormalEquationsPath path) {
  const size_t n = jac.rows.size();
  const size_t m = jac.rows_count;
  const auto ni = static_cast<Eigen::Index>(n);
  *g = jac.gradient(residual);
  const size_t stored = jac.nonZeros();
  jtj->setZero(ni, ni);
  constexpr size_t kDenseEntryLimit = size_t{1} << 23;  // 64 MB of doubles
  if (path == NormalEquationsPath::kAuto)
    path = 4 * stored >= m * n && m * n <= kDenseEntryLimit ? NormalEquationsPath::kDense
                                                             : NormalEquationsPath::kSparse;
  if (path == NormalEquationsPath::kDense) {
    Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(m), ni);
    for (size_t k = 0; k < n; ++k)
      for (size_t e = 0; e < jac.rows[k].size(); ++e)
        dense(jac.rows[k][e], static_cast<Eigen::Index>(k)) = jac.values[k][e];
    jtj->selfadjointView<Eigen::Lower>().rankUpdate(dense.transpose());
  } else {
    // Transpose the columns into rows (a counting sort: each row's genes stay ascending),
    // then add each row's outer product to the lower triangle.
    std::vector<size_t> start(m + 1, 0);
    for (const auto& column : jac.rows)
      for (uint32_t i : column) ++start[i + 1];
    for (size_t i = 0; i < m; ++i) start[i + 1] += start[i];
    std::vector<uint32_t> gene(stored);
    std::vector<double> value(stored);
    std::vector<size_t> fill(start.begin(), start.end() - 1);
    for (size_t k = 0; k < n; ++k)
      for (size_t e = 0; e < jac.rows[k].size(); ++e) {
        const size_t slot = fill[jac.rows[k][e]]++;
        gene[slot] = static_cast<uint32_t>(k);
        value[slot] = jac.values[k][e];
      }
    for (size_t i = 0; i < m; ++i)
      for (size_t a = start[i]; a < start[i + 1]; ++a)
        for (size_t b = start[i]; b <= a; ++b) (*jtj)(gene[a], gene[b]) += value[a] * value[b];
  }
  Eigen::MatrixXd full = jtj->selfadjointView<Eigen::Lower>();
  *jtj = std::move(full);
}

bool forwardJacobian(const Cost& cost, const ParameterSpace& space, const std::vector<double>& x,
                     const Eigen::VectorXd& residual, const std::vector<size_t>& active,
                     uint64_t max_entries, ThreadPool* pool, ResidualJacobian* jac) {
  const size_t n = active.size();
  const size_t m = static_cast<size_t>(residual.size());
  jac->rows_count = m;
  jac->rows.resize(n);
  jac->values.resize(n);
  std::vector<double> steps(n);
  for (size_t j = 0; j < n; ++j) steps[j] = forwardDifferenceStep(space.gene(active[j]), x[active[j]]);
  std::atomic<uint64_t> stored{0};
  std::atomic<bool> too_large{false};
  const auto column = [&](size_t j) {
    thread_local std::vector<double> genes, rk;
    genes = x;
    genes[active[j]] += steps[j];
    std::vector<uint32_t>& rows = jac->rows[j];
    std::vector<double>& values = jac->values[j];
    rows.clear();
    values.clear();
    // A column whose model blew up is left empty: that gene is held this iteration.
    const double cj = cost.residuals(space.toPhysical(genes), &rk);
    if (!std::isfinite(cj)) return;
    for (size_t i = 0; i < m; ++i) {
      const double d = rk[i] - residual[static_cast<Eigen::Index>(i)];
      if (d == 0.0) continue;
      rows.push_back(static_cast<uint32_t>(i));
      values.push_back(d / steps[j]);
    }
    if ((stored += rows.size()) > max_entries) too_large = true;
  };
  if (pool) pool->parallelFor(n, column);
  else for (size_t j = 0; j < n; ++j) column(j);
  return !too_large;
}

}  // namespace mme

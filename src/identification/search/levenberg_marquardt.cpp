#include "motion_model_estimation/identification/search/levenberg_marquardt.h"

#include <Eigen/Dense>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

namespace mme {

namespace {

/// Residuals at genes (finite or flagged): false when the model blew up there.
bool residualsAt(const Cost& cost, const ParameterSpace& space,
                 const std::vector<double>& genes, std::vector<double>* r, double* c) {
  *c = cost.residuals(space.toPhysical(genes), r);
  return std::isfinite(*c);
}

/// The damped Gauss-Newton step for gradient g = J^T r: (J^T J + diag(damping)) dx = -g.
Eigen::VectorXd dampedStep(const Eigen::MatrixXd& jtj, const Eigen::VectorXd& damping,
                           const Eigen::VectorXd& g) {
  Eigen::MatrixXd a = jtj;
  a.diagonal() += damping;
  return a.ldlt().solve(-g);
}

}  // namespace

namespace detail {

size_t JacobianColumns::nonZeros() const {
  size_t stored = 0;
  for (const auto& column : rows) stored += column.size();
  return stored;
}

Eigen::VectorXd JacobianColumns::gradient(const Eigen::VectorXd& residual) const {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(rows.size()));
  for (size_t k = 0; k < rows.size(); ++k)
    for (size_t e = 0; e < rows[k].size(); ++e)
      g[static_cast<Eigen::Index>(k)] += values[k][e] * residual[rows[k][e]];
  return g;
}

void normalEquations(const JacobianColumns& jac, const Eigen::VectorXd& residual,
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
                     uint64_t max_entries, ThreadPool* pool, JacobianColumns* jac) {
  const size_t n = active.size();
  const size_t m = static_cast<size_t>(residual.size());
  jac->rows_count = m;
  jac->rows.resize(n);
  jac->values.resize(n);
  // Steps relative to the gene, or to its range near 0, inward at a bound.
  std::vector<double> steps(n);
  for (size_t j = 0; j < n; ++j) {
    const Gene& g = space.gene(active[j]);
    const double xj = x[active[j]];
    double h = 1e-7 * std::max({std::fabs(xj), 1e-3 * (g.upper - g.lower), 1e-8});
    if (xj + h > g.upper) h = -h;
    steps[j] = h;
  }
  std::atomic<uint64_t> stored{0};
  std::atomic<bool> too_large{false};
  const auto column = [&](size_t j) {
    thread_local std::vector<double> genes, rk;
    genes = x;
    genes[active[j]] += steps[j];
    double cj = 0.0;
    std::vector<uint32_t>& rows = jac->rows[j];
    std::vector<double>& values = jac->values[j];
    rows.clear();
    values.clear();
    // A column whose model blew up is left empty: that gene is held this iteration.
    if (!residualsAt(cost, space, genes, &rk, &cj)) return;
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

}  // namespace detail

LmResult levenbergMarquardt(const Cost& cost, const ParameterSpace& space,
                            const std::vector<double>& start, const LmSettings& settings,
                            ThreadPool* pool) {
  const auto began = std::chrono::steady_clock::now();
  const size_t m = cost.residualCount();
  // The genes this search moves (the others keep their start value): column j of the Jacobian
  // and component j of a step belong to gene active[j].
  std::vector<size_t> active;
  for (size_t k = 0; k < space.size(); ++k)
    if (settings.movable.empty() || (k < settings.movable.size() && settings.movable[k]))
      active.push_back(k);
  const size_t n = active.size();
  const uint64_t max_evaluations =
      settings.max_evaluations > 0 ? settings.max_evaluations : 50 * (n + 1);
  LmResult out;
  out.genes = start;
  std::vector<double> r0;
  if (!residualsAt(cost, space, start, &r0, &out.cost)) out.cost = std::numeric_limits<double>::infinity();
  out.evaluations = 1;
  if (n == 0 || m == 0 || !std::isfinite(out.cost)) return out;
  if (m > std::numeric_limits<uint32_t>::max()) {  // row indices are stored in 32 bits
    out.status = RefineStatus::kJacobianTooLarge;
    return out;
  }

  std::vector<double> lo(n), hi(n);
  for (size_t j = 0; j < n; ++j) {
    lo[j] = space.gene(active[j]).lower;
    hi[j] = space.gene(active[j]).upper;
  }
  // The Jacobian is stored by sparse columns: a gene moves only the terms of particles near its
  // bond type's sites (the local-cost structure), and the other entries of a forward difference
  // are exactly zero (the same arithmetic). That bounds memory on large models, and J^T J costs
  // the sum over terms of (genes moving the term)^2 instead of terms x genes^2.
  detail::JacobianColumns jac;
  jac.rows_count = m;
  jac.rows.resize(n);
  jac.values.resize(n);
  bool too_large = false;
  Eigen::VectorXd residual =
      Eigen::Map<const Eigen::VectorXd>(r0.data(), static_cast<Eigen::Index>(m));
  std::vector<double> x = start, trial = start, r_trial;
  std::vector<double> cost_after{out.cost};  // the start, then after each Jacobian's step
  double mu = -1.0, nu = 2.0;
  const auto now = []() { return std::chrono::steady_clock::now(); };
  // A Jacobian costs n evaluations: when the time they take (at the mean evaluation time so far)
  // would run past the deadline, stop before starting it rather than throw it away half done.
  const auto jacobian_fits = [&]() {
    const auto elapsed = now() - began;
    return now() + elapsed / static_cast<double>(out.evaluations) * static_cast<double>(n) <=
           settings.deadline;
  };
  out.status = RefineStatus::kEvaluationLimit;
  while (true) {
    if (out.evaluations + n > max_evaluations) {
      out.status = RefineStatus::kEvaluationLimit;
      break;
    }
    if (settings.cancel && settings.cancel->load(std::memory_order_relaxed)) {
      out.status = RefineStatus::kCancelled;
      break;
    }
    if (settings.deadline != std::chrono::steady_clock::time_point::max() && !jacobian_fits()) {
      out.status = RefineStatus::kDeadline;
      break;
    }
    if (!(out.cost > 0.0)) {
      out.status = RefineStatus::kConverged;  // an exact fit
      break;
    }
    if (!detail::forwardJacobian(cost, space, x, residual, active, settings.max_jacobian_entries,
                                 pool, &jac))
      too_large = true;
    out.evaluations += n;
    ++out.jacobians;
    if (too_large) {
      out.status = RefineStatus::kJacobianTooLarge;
      break;
    }
    Eigen::MatrixXd jtj;
    Eigen::VectorXd g;
    detail::normalEquations(jac, residual, &jtj, &g);
    Eigen::VectorXd scale = jtj.diagonal().cwiseMax(1e-30 * std::max(jtj.diagonal().maxCoeff(), 1e-300));
    if (mu < 0.0) mu = 1e-3;
    // Damped steps until one lowers the cost (Nielsen's update of the damping).
    bool accepted = false;
    double rho = 0.0;
    out.status = RefineStatus::kNoProgress;
    while (!accepted) {
      if (out.evaluations >= max_evaluations) {
        out.status = RefineStatus::kEvaluationLimit;
        break;
      }
      if (now() > settings.deadline) {
        out.status = RefineStatus::kDeadline;
        break;
      }
      if (settings.cancel && settings.cancel->load(std::memory_order_relaxed)) {
        out.status = RefineStatus::kCancelled;
        break;
      }
      const Eigen::VectorXd dx = dampedStep(jtj, mu * scale, g);
      if (!dx.allFinite()) {
        mu *= nu;
        nu *= 2.0;
        if (nu > 1e15) break;
        continue;
      }
      bool moved = false;
      for (size_t j = 0; j < n; ++j) {
        const size_t k = active[j];
        trial[k] = std::min(std::max(x[k] + dx[static_cast<Eigen::Index>(j)], lo[j]), hi[j]);
        moved = moved || trial[k] != x[k];
      }
      if (!moved) break;  // the step vanished (round-off floor)
      double c_trial = 0.0;
      const bool ok = residualsAt(cost, space, trial, &r_trial, &c_trial);
      ++out.evaluations;
      if (ok && c_trial < out.cost) {
        // Gain ratio against the linear model's predicted decrease.
        const double predicted = dx.dot(mu * scale.cwiseProduct(dx) - g);
        rho = predicted > 0.0 ? (out.cost - c_trial) / predicted : 0.0;
        mu *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
        nu = 2.0;
        x = trial;
        out.cost = c_trial;
        residual = Eigen::Map<const Eigen::VectorXd>(r_trial.data(), static_cast<Eigen::Index>(m));
        accepted = true;
      } else {
        trial = x;
        mu *= nu;
        nu *= 2.0;
        if (nu > 1e15) break;  // no damping helps: at the floor of what the data allow
      }
    }
    if (!accepted) break;
    if (settings.step_tolerance > 0.0 && std::fabs(rho - 1.0) < 0.25) {
      // The linear model predicted this step well; if the step it predicts next (with this
      // Jacobian, at the new point) moves no gene by more than the tolerance, the search has
      // converged (to round-off on exact data, to the optimum on noisy data): stop without
      // paying for another Jacobian to find out.
      const Eigen::VectorXd next = dampedStep(jtj, mu * scale, jac.gradient(residual));
      bool small = next.allFinite();
      for (size_t j = 0; j < n && small; ++j)
        small = std::fabs(next[static_cast<Eigen::Index>(j)]) <= settings.step_tolerance * (hi[j] - lo[j]);
      if (small) {
        out.status = RefineStatus::kConverged;
        break;
      }
    }
    cost_after.push_back(out.cost);
    const size_t iterations = cost_after.size() - 1;
    const size_t w = static_cast<size_t>(std::max(settings.stall_iterations, 1));
    if (iterations >= w && (!(settings.stall_factor > 0.0) ||
                            !(out.cost * settings.stall_factor <= cost_after[iterations - w]))) {
      out.status = RefineStatus::kStalled;
      break;
    }
  }
  out.genes = x;
  return out;
}

}  // namespace mme

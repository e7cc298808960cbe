#include "motion_model_estimation/identification/search/ceres_levenberg_marquardt.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

#include "motion_model_estimation/identification/search/residual_jacobian.h"

namespace mme {

namespace {

/// How the problem is laid out for Ceres. Parameter blocks: the movable genes of each bond type
/// (gravity's last), contiguous in Ceres' parameter vector. Residual blocks: the cost's residual
/// groups (a particle's residuals), each over the parameter blocks that can change it, so the
/// Jacobian is block-sparse and J^T J costs the sum over groups of their rows x (their genes)^2;
/// a cost without groups is one block over every gene.
struct Layout {
  std::vector<size_t> active;            ///< Ceres' parameter j = gene active[j]
  std::vector<size_t> block_begin;       ///< parameter block p = parameters [begin[p], begin[p+1])
  std::vector<int> block_of;             ///< per parameter j
  std::vector<std::vector<uint32_t>> rows;    ///< per residual block: the cost's residuals
  std::vector<std::vector<int>> blocks;       ///< per residual block: its parameter blocks
  std::vector<int64_t> offset;  ///< (residual block, parameter block) -> its Jacobian in the cache
  std::vector<int> row_block, row_index;  ///< per residual: its residual block (-1: none), row
  uint64_t entries = 0;                   ///< Jacobian entries Ceres holds

  size_t numBlocks() const { return block_begin.size() - 1; }
  size_t blockSize(int p) const { return block_begin[p + 1] - block_begin[p]; }
};

Layout makeLayout(const Cost& cost, const ParameterSpace& space, const LmSettings& settings,
                  bool use_groups) {
  Layout l;
  const int types = static_cast<int>(space.genesOfType().size());
  const auto type_of = [&](size_t k) {
    const int t = space.gene(k).ref.bond_type;
    return t < 0 ? types : t;
  };
  for (size_t k = 0; k < space.size(); ++k)
    if (settings.movable.empty() || (k < settings.movable.size() && settings.movable[k]))
      l.active.push_back(k);
  std::stable_sort(l.active.begin(), l.active.end(),
                   [&](size_t a, size_t b) { return type_of(a) < type_of(b); });
  std::vector<int> block_of_gene(space.size(), -1);
  for (size_t j = 0; j < l.active.size(); ++j) {
    if (j == 0 || type_of(l.active[j]) != type_of(l.active[j - 1])) l.block_begin.push_back(j);
    l.block_of.push_back(static_cast<int>(l.block_begin.size()) - 1);
    block_of_gene[l.active[j]] = l.block_of.back();
  }
  l.block_begin.push_back(l.active.size());
  const size_t m = cost.residualCount();
  const size_t num_blocks = l.numBlocks();
  ResidualGroups groups;
  if (use_groups) groups = cost.residualGroups();
  if (groups.residuals.empty()) {
    groups.residuals.assign(1, {});
    for (size_t i = 0; i < m; ++i) groups.residuals[0].push_back(static_cast<uint32_t>(i));
    groups.parameters.assign(1, {});
    for (size_t k = 0; k < space.size(); ++k)
      groups.parameters[0].push_back(static_cast<uint32_t>(k));
  }
  l.row_block.assign(m, -1);
  l.row_index.assign(m, 0);
  for (size_t g = 0; g < groups.residuals.size(); ++g) {
    std::vector<int> blocks;
    for (uint32_t k : groups.parameters[g])
      if (k < block_of_gene.size() && block_of_gene[k] >= 0) blocks.push_back(block_of_gene[k]);
    std::sort(blocks.begin(), blocks.end());
    blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
    if (blocks.empty() || groups.residuals[g].empty()) continue;  // constant residuals
    const int b = static_cast<int>(l.rows.size());
    for (size_t r = 0; r < groups.residuals[g].size(); ++r) {
      l.row_block[groups.residuals[g][r]] = b;
      l.row_index[groups.residuals[g][r]] = static_cast<int>(r);
    }
    l.rows.push_back(groups.residuals[g]);
    l.blocks.push_back(std::move(blocks));
  }
  l.offset.assign(l.rows.size() * num_blocks, -1);
  for (size_t b = 0; b < l.rows.size(); ++b)
    for (int p : l.blocks[b]) {
      l.offset[b * num_blocks + p] = static_cast<int64_t>(l.entries);
      l.entries += l.rows[b].size() * l.blockSize(p);
    }
  return l;
}

/// What one solve shares between its residual blocks, the evaluation callback and the stopping
/// rules: the evaluation count, the best point Ceres evaluated, and the residuals and Jacobian
/// at the last point. Ceres evaluates every residual block at one point in a row: the callback
/// computes the cost's residuals (and, when asked, its Jacobian) once there, and each block copies
/// its rows; the Jacobian at an accepted candidate reuses the candidate's residuals, so an
/// iteration costs one evaluation per gene plus the candidate.
struct LmRun : public ceres::EvaluationCallback {
  const Cost* cost = nullptr;
  const ParameterSpace* space = nullptr;
  ThreadPool* pool = nullptr;
  const Layout* layout = nullptr;
  std::vector<double> x;           ///< Ceres' parameters (Ceres writes each point here)
  std::vector<double> genes;       ///< the full point (held genes at their start)
  uint64_t max_jacobian_entries = 0;
  uint64_t evaluations = 0;
  int jacobians = 0;
  uint64_t outside = 0;            ///< Jacobian entries outside the layout (a wrong structure)
  std::vector<double> best_genes;  ///< lowest cost among the points Ceres evaluated
  double best_cost = std::numeric_limits<double>::infinity();
  std::vector<double> last_x;      ///< the last point evaluated (Ceres' parameters) ...
  std::vector<double> last_residuals;  ///< ... its residuals ...
  double last_cost = 0.0;              ///< ... and their squared sum
  bool jacobian_current = false;       ///< cache holds the Jacobian at last_x
  std::vector<double> cache;           ///< the blocks' Jacobians (Layout::offset)
  ResidualJacobian jacobian;
  std::vector<double> jacobian_x;          ///< where `jacobian` was taken (Ceres' parameters)
  Eigen::VectorXd jacobian_residuals;      ///< and the residuals there
  Eigen::VectorXd jacobi_scale;  ///< Ceres' column scaling (from the first Jacobian)

  // The stopping rules (see stopBeforeJacobian).
  const LmSettings* settings = nullptr;
  uint64_t max_evaluations = 0;
  std::chrono::steady_clock::time_point began;
  std::vector<double> cost_after;  ///< the cost at the start, then after each accepted step
  double radius = 0.0;             ///< Ceres' trust region radius before the current step
  RefineStatus reason = RefineStatus::kNotRun;  ///< why a rule ended the solve

  void setActive(const double* p) {
    for (size_t j = 0; j < layout->active.size(); ++j) genes[layout->active[j]] = p[j];
  }

  /// Residuals at Ceres' point p (reused when p is the last point); false when the model blew up.
  bool residualsAt(const double* p) {
    const size_t n = layout->active.size();
    if (last_x.size() == n && std::equal(p, p + n, last_x.begin())) return std::isfinite(last_cost);
    setActive(p);
    last_x.assign(p, p + n);
    jacobian_current = false;
    last_cost = cost->residuals(space->toPhysical(genes), &last_residuals);
    ++evaluations;
    if (std::isfinite(last_cost) && last_cost < best_cost) {
      best_cost = last_cost;
      best_genes = genes;
    }
    return std::isfinite(last_cost);
  }

  /// The forward-difference Jacobian at the last point, scattered into the blocks' cache.
  void jacobianAtLast() {
    const Layout& l = *layout;
    const size_t n = l.active.size();
    const size_t num_blocks = l.numBlocks();
    setActive(last_x.data());
    const Eigen::VectorXd residual = Eigen::Map<const Eigen::VectorXd>(
        last_residuals.data(), static_cast<Eigen::Index>(last_residuals.size()));
    forwardJacobian(*cost, *space, genes, residual, l.active, max_jacobian_entries, pool,
                    &jacobian);
    evaluations += n;
    ++jacobians;
    jacobian_x = last_x;
    jacobian_residuals = residual;
    if (jacobi_scale.size() == 0) {
      jacobi_scale.resize(static_cast<Eigen::Index>(n));
      for (size_t j = 0; j < n; ++j) {
        double norm2 = 0.0;
        for (double v : jacobian.values[j]) norm2 += v * v;
        jacobi_scale[static_cast<Eigen::Index>(j)] = 1.0 / (1.0 + std::sqrt(norm2));
      }
    }
    cache.assign(l.entries, 0.0);
    for (size_t j = 0; j < n; ++j) {
      const int p = l.block_of[j];
      const size_t width = l.blockSize(p);
      const size_t column = j - l.block_begin[p];
      for (size_t e = 0; e < jacobian.rows[j].size(); ++e) {
        const uint32_t i = jacobian.rows[j][e];
        const int b = l.row_block[i];
        const int64_t at = b < 0 ? -1 : l.offset[b * num_blocks + p];
        if (at < 0) {
          ++outside;
          continue;
        }
        cache[at + l.row_index[i] * width + column] = jacobian.values[j][e];
      }
    }
    jacobian_current = true;
  }

  /// The mean evaluation time so far, projected over `count` more: would it pass the deadline?
  bool pastDeadline(uint64_t count) const {
    if (settings->deadline == std::chrono::steady_clock::time_point::max()) return false;
    const auto now = std::chrono::steady_clock::now();
    const auto per_evaluation =
        (now - began) / static_cast<double>(std::max<uint64_t>(evaluations, 1));
    return now + per_evaluation * static_cast<double>(count) > settings->deadline;
  }

  /// The rules that can end the solve at an accepted point, checked before its Jacobian (n
  /// evaluations) is paid for: an exact fit, the stall rule, the budget, the deadline, the
  /// cancel flag, and the convergence test (predicted()).
  RefineStatus stopBeforeJacobian() {
    const uint64_t n = layout->active.size();
    cost_after.push_back(last_cost);
    const size_t steps = cost_after.size() - 1;
    const size_t w = static_cast<size_t>(std::max(settings->stall_iterations, 1));
    if (!(last_cost > 0.0)) return RefineStatus::kConverged;
    if (predictedConvergence()) return RefineStatus::kConverged;
    if (steps >= w && (!(settings->stall_factor > 0.0) ||
                       !(last_cost * settings->stall_factor <= cost_after[steps - w])))
      return RefineStatus::kStalled;
    if (evaluations + n > max_evaluations) return RefineStatus::kEvaluationLimit;
    if (settings->cancel && settings->cancel->load(std::memory_order_relaxed))
      return RefineStatus::kCancelled;
    if (pastDeadline(n)) return RefineStatus::kDeadline;
    return RefineStatus::kNotRun;
  }

  /// Ceres learns that its parameter tolerance is met from the step it computes with the
  /// Jacobian at the accepted point. When the linear model predicted the accepted step well
  /// (gain ratio within 0.25 of 1), the Jacobian at hand predicts that next step as well: it is
  /// computed with it (Ceres' damping: Jacobi-scaled diagonal over the radius after this step)
  /// and the solve ends when it is within the tolerance, without the Jacobian it would cost.
  bool predictedConvergence() {
    if (!(settings->step_tolerance > 0.0) || jacobian_x.size() != last_x.size()) return false;
    const size_t n = last_x.size();
    const auto ni = static_cast<Eigen::Index>(n);
    const Eigen::Map<const Eigen::VectorXd> r_new(
        last_residuals.data(), static_cast<Eigen::Index>(last_residuals.size()));
    Eigen::VectorXd step(ni);
    for (size_t j = 0; j < n; ++j) step[static_cast<Eigen::Index>(j)] = last_x[j] - jacobian_x[j];
    Eigen::VectorXd model = jacobian_residuals;  // r + J step
    for (size_t j = 0; j < n; ++j)
      for (size_t e = 0; e < jacobian.rows[j].size(); ++e)
        model[jacobian.rows[j][e]] += jacobian.values[j][e] * step[static_cast<Eigen::Index>(j)];
    const double before = jacobian_residuals.squaredNorm();
    const double predicted = before - model.squaredNorm();
    const double rho = predicted > 0.0 ? (before - r_new.squaredNorm()) / predicted : 0.0;
    if (!(std::fabs(rho - 1.0) < 0.25)) return false;
    const double next_radius =
        radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
    Eigen::MatrixXd jtj;
    Eigen::VectorXd g;
    normalEquations(jacobian, r_new, &jtj, &g, NormalEquationsPath::kSparse);  // no m x n copy
    constexpr double kMinDiagonal = 1e-6, kMaxDiagonal = 1e32;  // Ceres' LM diagonal clamp
    for (Eigen::Index j = 0; j < ni; ++j) {
      const double s2 = jacobi_scale[j] * jacobi_scale[j];
      jtj(j, j) += std::min(std::max(s2 * jtj(j, j), kMinDiagonal), kMaxDiagonal) /
                   (next_radius * s2);
    }
    const Eigen::VectorXd next = jtj.ldlt().solve(-g);
    const double x_norm = Eigen::Map<const Eigen::VectorXd>(last_x.data(), ni).norm();
    const double tolerance = settings->step_tolerance;
    return next.allFinite() && next.norm() <= tolerance * (x_norm + tolerance);
  }

  void PrepareForEvaluation(bool evaluate_jacobians, bool /*new_evaluation_point*/) override {
    if (!residualsAt(x.data()) || !evaluate_jacobians || jacobian_current) return;
    if (jacobians > 0 && reason == RefineStatus::kNotRun) {
      // An accepted step: a rule that ends the solve here leaves the cache as it is (Ceres
      // computes its gradient from it, then the iteration callback stops before any step).
      reason = stopBeforeJacobian();
      if (reason != RefineStatus::kNotRun) return;
    }
    jacobianAtLast();
  }
};

/// One residual group of the cost as a Ceres residual block: copies what LmRun computed at the
/// point (the parameters Ceres passes are the ones LmRun read from its buffer).
class ResidualBlock final : public ceres::CostFunction {
 public:
  ResidualBlock(const LmRun* run, size_t block) : run_(run), block_(block) {
    const Layout& l = *run->layout;
    for (int p : l.blocks[block])
      mutable_parameter_block_sizes()->push_back(static_cast<int32_t>(l.blockSize(p)));
    set_num_residuals(static_cast<int>(l.rows[block].size()));
  }

  bool Evaluate(double const* const* /*parameters*/, double* residuals,
                double** jacobians) const override {
    if (!std::isfinite(run_->last_cost)) return false;
    const Layout& l = *run_->layout;
    const std::vector<uint32_t>& rows = l.rows[block_];
    for (size_t r = 0; r < rows.size(); ++r) residuals[r] = run_->last_residuals[rows[r]];
    if (!jacobians) return true;
    const std::vector<int>& blocks = l.blocks[block_];
    for (size_t q = 0; q < blocks.size(); ++q) {
      if (!jacobians[q]) continue;
      const double* from = run_->cache.data() + l.offset[block_ * l.numBlocks() + blocks[q]];
      std::copy(from, from + rows.size() * l.blockSize(blocks[q]), jacobians[q]);
    }
    return true;
  }

 private:
  const LmRun* run_;
  size_t block_;
};

/// The package's stopping rules, after each Ceres iteration (after the start's Jacobian, after
/// each rejected trial step, and after an accepted one: its rules ran in LmRun before its
/// Jacobian). The next thing Ceres does is a trial step. Records why it stopped the solve.
class StopRules final : public ceres::IterationCallback {
 public:
  StopRules(LmRun* run) : run_(run) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    run_->radius = summary.trust_region_radius;
    if (run_->outside > 0) {  // the cost's residual groups missed a derivative
      run_->reason = RefineStatus::kNoProgress;
      return ceres::SOLVER_ABORT;
    }
    if (run_->reason == RefineStatus::kNotRun) {
      if (!(run_->best_cost > 0.0)) run_->reason = RefineStatus::kConverged;  // an exact fit
      else if (run_->evaluations + 1 > run_->max_evaluations)
        run_->reason = RefineStatus::kEvaluationLimit;
      else if (run_->settings->cancel && run_->settings->cancel->load(std::memory_order_relaxed))
        run_->reason = RefineStatus::kCancelled;
      else if (run_->pastDeadline(1))
        run_->reason = RefineStatus::kDeadline;
    }
    if (run_->reason == RefineStatus::kNotRun) return ceres::SOLVER_CONTINUE;
    return run_->reason == RefineStatus::kCancelled ? ceres::SOLVER_ABORT
                                                    : ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }

 private:
  LmRun* run_;
};

/// Levenberg-Marquardt as the package ran it: the damping starts at 1e-3 (trust region radius
/// 1e3) and scales with diag(J^T J) (Jacobi scaling); any step that lowers the cost is taken
/// (min_relative_decrease 0); a step leaving the box is clamped onto it, no line search; the
/// stopping rules are StopRules' and the parameter tolerance.
ceres::Solver::Options solverOptions(const LmSettings& settings, bool block_sparse) {
  ceres::Solver::Options o;
  o.minimizer_type = ceres::TRUST_REGION;
  o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  o.linear_solver_type = ceres::DENSE_QR;
  if (block_sparse) {
    // The normal equations from the blocks (J^T J over each group's genes only), factorised
    // by Eigen's sparse LDL^T: the damping keeps it positive definite, and a pivot that
    // rounds to a tiny value (a gene the data do not identify) does not make it fail.
    if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE)) {
      o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
      o.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
    }
  }
  o.initial_trust_region_radius = 1e3;
  o.min_relative_decrease = 0.0;
  o.max_num_line_search_step_size_iterations = 0;
  o.function_tolerance = 0.0;
  o.gradient_tolerance = 0.0;
  o.parameter_tolerance = std::max(settings.step_tolerance, 0.0);
  o.max_num_iterations = std::numeric_limits<int>::max();
  o.max_solver_time_in_seconds = 1e9;
  o.num_threads = 1;  // the Jacobian's columns run on the caller's pool
  o.logging_type = ceres::SILENT;
  o.minimizer_progress_to_stdout = false;
  return o;
}

/// How the solve ended, as a RefineStatus: the stopping rule that ended it, else Ceres'
/// termination type.
RefineStatus statusFor(const ceres::Solver::Summary& summary, RefineStatus rule,
                       double min_trust_region_radius) {
  if (rule != RefineStatus::kNotRun) return rule;
  switch (summary.termination_type) {
    case ceres::CONVERGENCE:
      // The radius floor: no damping lowered the cost.
      if (!summary.iterations.empty() &&
          summary.iterations.back().trust_region_radius <= min_trust_region_radius)
        return RefineStatus::kNoProgress;
      return RefineStatus::kConverged;
    case ceres::NO_CONVERGENCE:
      return RefineStatus::kEvaluationLimit;
    case ceres::FAILURE:       // no valid step (the linear solver kept failing)
    case ceres::USER_FAILURE:  // (the rules record a reason whenever they abort)
      return RefineStatus::kNoProgress;
    case ceres::USER_SUCCESS:
      return RefineStatus::kStalled;
  }
  return RefineStatus::kNoProgress;
}

}  // namespace

namespace {

/// One Ceres solve from `start` on `layout`; `run` carries the evaluations across solves.
RefineStatus solve(const Layout& layout, const std::vector<double>& start,
                   const LmSettings& settings, LmRun* run) {
  const size_t n = layout.active.size();
  run->layout = &layout;
  run->genes = start;
  run->x.resize(n);
  for (size_t j = 0; j < n; ++j) run->x[j] = start[layout.active[j]];
  run->last_x.clear();  // the parameter order may have changed
  run->jacobian_current = false;
  run->outside = 0;
  // A start where the model blows up is not run (Ceres would log a failed first evaluation).
  if (!run->residualsAt(run->x.data())) return RefineStatus::kNotRun;
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.evaluation_callback = run;
  ceres::Problem problem(problem_options);
  std::vector<double*> blocks(layout.numBlocks());
  for (size_t p = 0; p < blocks.size(); ++p) blocks[p] = run->x.data() + layout.block_begin[p];
  std::deque<ResidualBlock> residual_blocks;  // Ceres keeps pointers: blocks must not move
  std::vector<double*> parameters;
  for (size_t b = 0; b < layout.rows.size(); ++b) {
    residual_blocks.emplace_back(run, b);
    parameters.clear();
    for (int p : layout.blocks[b]) parameters.push_back(blocks[p]);
    problem.AddResidualBlock(&residual_blocks.back(), nullptr, parameters);
  }
  for (size_t p = 0; p < blocks.size(); ++p) {
    if (!problem.HasParameterBlock(blocks[p])) continue;  // no residual depends on it
    for (size_t j = layout.block_begin[p]; j < layout.block_begin[p + 1]; ++j) {
      const Gene& g = run->space->gene(layout.active[j]);
      const int at = static_cast<int>(j - layout.block_begin[p]);
      problem.SetParameterLowerBound(blocks[p], at, g.lower);
      problem.SetParameterUpperBound(blocks[p], at, g.upper);
    }
  }
  ceres::Solver::Options options = solverOptions(settings, layout.rows.size() > 1);
  run->settings = &settings;
  run->max_evaluations = settings.max_evaluations > 0 ? settings.max_evaluations : 50 * (n + 1);
  run->cost_after.assign(1, run->last_cost);
  run->radius = options.initial_trust_region_radius;
  run->reason = RefineStatus::kNotRun;
  run->jacobian_x.clear();
  run->jacobi_scale.resize(0);
  StopRules rules(run);
  options.callbacks.push_back(&rules);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return statusFor(summary, run->reason, options.min_trust_region_radius);
}

}  // namespace

LmResult levenbergMarquardt(const Cost& cost, const ParameterSpace& space,
                            const std::vector<double>& start, const LmSettings& settings,
                            ThreadPool* pool) {
  LmResult out;
  out.genes = start;
  out.cost = std::numeric_limits<double>::infinity();
  const size_t m = cost.residualCount();
  Layout layout = makeLayout(cost, space, settings, true);
  if (layout.active.empty() || m == 0) return out;
  if (settings.cancel && settings.cancel->load(std::memory_order_relaxed)) {
    out.status = RefineStatus::kCancelled;
    return out;
  }
  if (std::chrono::steady_clock::now() > settings.deadline) {
    out.status = RefineStatus::kDeadline;
    return out;
  }
  if (layout.entries > settings.max_jacobian_entries ||
      m > static_cast<size_t>(std::numeric_limits<int>::max())) {
    out.status = RefineStatus::kJacobianTooLarge;
    return out;
  }

  LmRun run;
  run.began = std::chrono::steady_clock::now();
  run.cost = &cost;
  run.space = &space;
  run.pool = pool;
  run.max_jacobian_entries = settings.max_jacobian_entries;
  RefineStatus status = solve(layout, start, settings, &run);
  if (run.outside > 0) {
    // The cost's residual groups left out a non-zero derivative: solve again from the best
    // point with one residual block over every gene (correct whatever the structure).
    const Layout dense = makeLayout(cost, space, settings, false);
    if (dense.entries > settings.max_jacobian_entries) status = RefineStatus::kJacobianTooLarge;
    else status = solve(dense, run.best_genes.empty() ? start : run.best_genes, settings, &run);
  }
  out.evaluations = run.evaluations;
  out.jacobians = run.jacobians;
  out.status = status;
  if (std::isfinite(run.best_cost)) {
    out.genes = run.best_genes;
    out.cost = run.best_cost;
  }
  return out;
}

}  // namespace mme

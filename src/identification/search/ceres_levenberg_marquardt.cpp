#include "motion_model_estimation/identification/search/ceres_levenberg_marquardt.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <deque>
#include <iterator>
#include <limits>
#include <map>

#include "motion_model_estimation/identification/search/residual_jacobian.h"

namespace mme {

namespace {

/// Trial steps in a row that may fail before the search gives up: the damping has then grown by
/// 2^(1 + 2 + ... + 49) (Nielsen's factor past 1e15), far past any step that still moves a gene.
constexpr int kMaxFailedSteps = 49;
/// The damping's start (Ceres' trust region radius is its inverse).
constexpr double kInitialDamping = 1e-3;
/// Up to this many movable genes the Jacobian is one dense block whatever its sparsity: the
/// dense normal equations cost little there, less than a sparse Cholesky's analysis per solve.
constexpr size_t kDenseParameters = 32;

/// A point Ceres evaluated: its movable genes, residuals and their squared sum.
struct Point {
  std::vector<double> x;
  std::vector<double> r;
  double cost = std::numeric_limits<double>::infinity();
  bool at(const double* p) const { return !x.empty() && std::equal(x.begin(), x.end(), p); }
};

/// Where the Jacobian's non-zeros may be, as Ceres' residual blocks: the residuals grouped by the
/// parameters (movable genes) that move them. A gene moves only the terms near its bond type's
/// sites, so a large model's Jacobian is mostly absent and Ceres forms the damped normal
/// equations from the blocks (sparse Cholesky) at the cost of the sum over residuals of their
/// parameters squared; one block over every parameter when a quarter of the Jacobian is there
/// or the genes are few.
struct Layout {
  std::vector<std::vector<uint32_t>> rows;    ///< per residual block: its residuals
  std::vector<std::vector<uint32_t>> params;  ///< per residual block: its parameters, ascending
  std::vector<uint32_t> block_of_row;         ///< per residual
  std::vector<uint32_t> local_row;            ///< per residual: its row in its block
  std::vector<size_t> offset;  ///< per residual block: its Jacobian (rows x params) in the cache
  size_t entries = 0;
  /// One block over every residual and parameter: Ceres' columns are copied from the Jacobian's
  /// sparse columns directly (no cache).
  bool dense = false;
};

/// The dense layout: one block over every residual and parameter.
Layout denseLayout(size_t m, size_t n) {
  Layout l;
  l.dense = true;
  l.block_of_row.assign(m, 0);
  l.local_row.resize(m);
  l.rows.emplace_back(m);
  l.params.emplace_back(n);
  for (size_t i = 0; i < m; ++i) l.rows[0][i] = l.local_row[i] = static_cast<uint32_t>(i);
  for (size_t j = 0; j < n; ++j) l.params[0][j] = static_cast<uint32_t>(j);
  l.offset.push_back(0);
  l.entries = m * n;
  return l;
}

/// The layout of a Jacobian `jac` (m residuals, n parameters), each residual also keeping the
/// parameters it had in `widen` (may be null); dense (one block) when at least a quarter of the
/// entries are there or n is small, and the dense Jacobian fits in `max_entries`.
Layout makeLayout(const ResidualJacobian& jac, size_t m, size_t n, const Layout* widen,
                  uint64_t max_entries) {
  const double dense_entries = static_cast<double>(m) * static_cast<double>(n);
  const auto dense = [&](size_t stored) {
    return (4.0 * static_cast<double>(stored) >= dense_entries || n <= kDenseParameters) &&
           dense_entries <= static_cast<double>(max_entries);
  };
  if (!widen && dense(jac.nonZeros())) return denseLayout(m, n);
  std::vector<std::vector<uint32_t>> of_row(m);
  size_t stored = 0;
  for (size_t j = 0; j < n; ++j)
    for (uint32_t i : jac.rows[j]) of_row[i].push_back(static_cast<uint32_t>(j));
  for (size_t i = 0; i < m; ++i) {
    if (widen) {
      const std::vector<uint32_t>& before = widen->params[widen->block_of_row[i]];
      std::vector<uint32_t> both;
      std::set_union(of_row[i].begin(), of_row[i].end(), before.begin(), before.end(),
                     std::back_inserter(both));
      of_row[i] = std::move(both);
    }
    stored += of_row[i].size();
  }
  if (dense(stored)) return denseLayout(m, n);
  Layout l;
  l.block_of_row.resize(m);
  l.local_row.resize(m);
  std::map<std::vector<uint32_t>, uint32_t> block_of;
  for (size_t i = 0; i < m; ++i) {
    // A residual no parameter moves (here) still belongs to Ceres' cost: it joins parameter 0.
    if (of_row[i].empty()) of_row[i].push_back(0);
    const auto found = block_of.emplace(of_row[i], static_cast<uint32_t>(l.rows.size()));
    if (found.second) {
      l.rows.emplace_back();
      l.params.push_back(of_row[i]);
    }
    const uint32_t b = found.first->second;
    l.block_of_row[i] = b;
    l.local_row[i] = static_cast<uint32_t>(l.rows[b].size());
    l.rows[b].push_back(static_cast<uint32_t>(i));
  }
  for (size_t b = 0; b < l.rows.size(); ++b) {
    l.offset.push_back(l.entries);
    l.entries += l.rows[b].size() * l.params[b].size();
  }
  return l;
}

/// What one search shares between Ceres' evaluations, the iteration callback and the result:
/// the evaluations, the best point, the point of the last Jacobian and the stopping rules.
/// Ceres evaluates every residual block at one point in a row: PrepareForEvaluation computes
/// the cost's residuals (and, when asked, the Jacobian) once there, and each block copies its
/// part.
struct LmRun : public ceres::EvaluationCallback {
  const Cost* cost = nullptr;
  const ParameterSpace* space = nullptr;
  const LmSettings* settings = nullptr;
  ThreadPool* pool = nullptr;
  std::vector<size_t> active;  ///< Ceres' parameter j = gene active[j]
  size_t m = 0;                ///< residuals
  uint64_t max_evaluations = 0;
  std::chrono::steady_clock::time_point began;

  /// Ceres' parameters (Ceres writes each point here): the movable genes' displacements from
  /// `origin`, the solve's start. Ceres judges convergence by its projected gradient
  /// x - P(x - g), which rounds to exactly zero when the gradient is below the genes' round-off
  /// (an ill-conditioned cost near its optimum, where the Gauss-Newton step is still far larger);
  /// displacements from the start keep that test at the gradient's own scale.
  std::vector<double> x;
  std::vector<double> origin;  ///< the movable genes at the solve's start
  std::vector<double> genes;  ///< the full point (held genes at their start)
  std::vector<double> moved;  ///< the movable genes at Ceres' point
  uint64_t evaluations = 0;
  int jacobians = 0;
  std::vector<double> best_genes;
  double best_cost = std::numeric_limits<double>::infinity();
  Point last;                 ///< the last point evaluated
  Point current;              ///< where the last Jacobian was taken (Ceres' current point)
  ResidualJacobian jacobian;  ///< at `current`
  const Layout* layout = nullptr;
  std::vector<double> cache;  ///< the Jacobian at `current` by residual blocks (Layout::offset)
  bool outside = false;       ///< it has a non-zero the layout has no place for
  bool zero_jacobian = false;  ///< Ceres gets a zero Jacobian (a rule ended the search there)
  const Point* prepared = nullptr;  ///< the point Ceres evaluates now (null: the model blew up)
  std::vector<double> cost_after;  ///< the start's cost, then after each accepted step
  double radius = 1.0 / kInitialDamping;  ///< Ceres' radius for the next step (1 / damping)
  int failed_steps = 0;                   ///< trial steps in a row that did not lower the cost
  RefineStatus reason = RefineStatus::kNotRun;  ///< the rule that ended the search

  size_t n() const { return active.size(); }

  /// The residuals at Ceres' point p (displacements from `origin`; the last or the current point
  /// again costs nothing); null when the model blew up there.
  const Point* pointAt(const double* p) {
    for (size_t j = 0; j < n(); ++j) {
      const Gene& g = space->gene(active[j]);
      moved[j] = std::min(std::max(origin[j] + p[j], g.lower), g.upper);
    }
    if (current.at(moved.data())) return std::isfinite(current.cost) ? &current : nullptr;
    if (!last.at(moved.data())) {
      for (size_t j = 0; j < n(); ++j) genes[active[j]] = moved[j];
      last.x = moved;
      last.cost = cost->residuals(space->toPhysical(genes), &last.r);
      ++evaluations;
      if (std::isfinite(last.cost) && last.cost < best_cost) {
        best_cost = last.cost;
        best_genes = genes;
      }
    }
    return std::isfinite(last.cost) ? &last : nullptr;
  }

  void PrepareForEvaluation(bool evaluate_jacobians, bool /*new_evaluation_point*/) override {
    prepared = pointAt(x.data());
    if (prepared && evaluate_jacobians) jacobianAt(*prepared);
  }

  /// The Jacobian at p (the start, or an accepted step's point). The rules that can end the
  /// search there are checked first, so no Jacobian is paid for that would not be used (Ceres
  /// then gets zeros, and the iteration callback ends the solve before any step). At the point
  /// of the last Jacobian (a solve restarted there) that Jacobian is used again.
  void jacobianAt(const Point& p) {
    if (!(current.at(p.x.data()) && !jacobian.rows.empty())) {
      if (reason == RefineStatus::kNotRun) reason = beforeJacobian(p);
      if (reason != RefineStatus::kNotRun) {
        zero_jacobian = true;
        if (layout && !layout->dense) cache.assign(layout->entries, 0.0);
        return;
      }
      current = p;
      for (size_t j = 0; j < n(); ++j) genes[active[j]] = p.x[j];
      const Eigen::Map<const Eigen::VectorXd> residual(p.r.data(), static_cast<Eigen::Index>(m));
      const bool fits = forwardJacobian(*cost, *space, genes, residual, active,
                                        settings->max_jacobian_entries, pool, &jacobian);
      evaluations += n();
      ++jacobians;
      if (!fits) {
        reason = RefineStatus::kJacobianTooLarge;
        jacobian.rows.clear();
      }
    }
    if (layout) scatter();
  }

  /// The Jacobian into the blocks' cache; a non-zero outside the layout is flagged.
  void scatter() {
    const Layout& l = *layout;
    zero_jacobian = reason != RefineStatus::kNotRun || jacobian.rows.size() != n();
    if (l.dense) return;  // ResidualBlock copies the columns
    cache.assign(l.entries, 0.0);
    if (zero_jacobian) return;
    for (size_t j = 0; j < jacobian.rows.size(); ++j)
      for (size_t e = 0; e < jacobian.rows[j].size(); ++e) {
        const uint32_t i = jacobian.rows[j][e];
        const uint32_t b = l.block_of_row[i];
        const std::vector<uint32_t>& params = l.params[b];
        const auto q = std::lower_bound(params.begin(), params.end(), static_cast<uint32_t>(j));
        if (q == params.end() || *q != j) {
          outside = true;
          continue;
        }
        cache[l.offset[b] + l.local_row[i] * params.size() +
              static_cast<size_t>(q - params.begin())] = jacobian.values[j][e];
      }
  }

  /// The rules checked before a Jacobian at p: the step tolerance and the stall rule (after an
  /// accepted step), the budget, the cancel flag, the deadline and an exact fit.
  RefineStatus beforeJacobian(const Point& p) {
    if (!current.x.empty()) {
      cost_after.push_back(p.cost);
      if (nextStepIsSmall(p)) return RefineStatus::kConverged;
      const size_t steps = cost_after.size() - 1;
      const size_t w = static_cast<size_t>(std::max(settings->stall_iterations, 1));
      if (steps >= w && (!(settings->stall_factor > 0.0) ||
                         !(p.cost * settings->stall_factor <= cost_after[steps - w])))
        return RefineStatus::kStalled;
    }
    if (evaluations + n() > max_evaluations) return RefineStatus::kEvaluationLimit;
    if (settings->cancel && settings->cancel->load(std::memory_order_relaxed))
      return RefineStatus::kCancelled;
    if (!jacobianFits()) return RefineStatus::kDeadline;
    if (!(p.cost > 0.0)) return RefineStatus::kConverged;  // an exact fit
    return RefineStatus::kNotRun;
  }

  /// A Jacobian costs n evaluations: when they would run past the deadline (at the mean
  /// evaluation time so far), stop before starting it rather than throw it away half done.
  bool jacobianFits() const {
    if (settings->deadline == std::chrono::steady_clock::time_point::max()) return true;
    const auto now = std::chrono::steady_clock::now();
    const auto per_evaluation =
        (now - began) / static_cast<double>(std::max<uint64_t>(evaluations, 1));
    return now + per_evaluation * static_cast<double>(n()) <= settings->deadline;
  }

  /// The convergence test at the accepted point p, with the Jacobian at hand (taken at the point
  /// the step left): when the linear model predicted that step well (gain ratio within 0.25 of
  /// 1), it predicts the next one as well; if that moves no gene by more than the step tolerance
  /// (a share of its range), the search has converged (to round-off on exact data, to the
  /// optimum on noisy data) without paying for another Jacobian to find out. The next step is
  /// Ceres' own: the damping after this step (Nielsen's update of 1 / radius) on diag(J^T J).
  bool nextStepIsSmall(const Point& p) {
    if (!(settings->step_tolerance > 0.0) || jacobian.rows.empty()) return false;
    const auto ni = static_cast<Eigen::Index>(n());
    const auto mi = static_cast<Eigen::Index>(m);
    const Eigen::Map<const Eigen::VectorXd> r_before(current.r.data(), mi);
    const Eigen::Map<const Eigen::VectorXd> r_after(p.r.data(), mi);
    Eigen::VectorXd model = r_before;  // r + J step
    for (size_t j = 0; j < n(); ++j) {
      const double step = p.x[j] - current.x[j];
      for (size_t e = 0; e < jacobian.rows[j].size(); ++e)
        model[jacobian.rows[j][e]] += jacobian.values[j][e] * step;
    }
    const double before = r_before.squaredNorm();
    const double predicted = before - model.squaredNorm();
    const double rho = predicted > 0.0 ? (before - r_after.squaredNorm()) / predicted : 0.0;
    if (!(std::fabs(rho - 1.0) < 0.25)) return false;
    const double damping = std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)) / radius;
    Eigen::MatrixXd jtj;
    Eigen::VectorXd g;
    const Eigen::VectorXd r = r_after;
    normalEquations(jacobian, r, &jtj, &g);
    const double floor = 1e-30 * std::max(jtj.diagonal().maxCoeff(), 1e-300);
    for (Eigen::Index j = 0; j < ni; ++j) jtj(j, j) += damping * std::max(jtj(j, j), floor);
    const Eigen::VectorXd next = jtj.ldlt().solve(-g);
    if (!next.allFinite()) return false;
    for (size_t j = 0; j < n(); ++j) {
      const Gene& gene = space->gene(active[j]);
      if (std::fabs(next[static_cast<Eigen::Index>(j)]) >
          settings->step_tolerance * (gene.upper - gene.lower))
        return false;
    }
    return true;
  }
};

/// One residual block of the layout: copies what LmRun computed at the point.
class ResidualBlock final : public ceres::CostFunction {
 public:
  ResidualBlock(const LmRun* run, const Layout* layout, size_t block)
      : run_(run), layout_(layout), block_(block) {
    for (size_t q = 0; q < layout->params[block].size(); ++q)
      mutable_parameter_block_sizes()->push_back(1);
    set_num_residuals(static_cast<int>(layout->rows[block].size()));
  }

  bool Evaluate(double const* const* /*parameters*/, double* residuals,
                double** jacobians) const override {
    const Point* p = run_->prepared;
    if (!p) return false;  // Ceres takes the step as failed
    const std::vector<uint32_t>& rows = layout_->rows[block_];
    for (size_t k = 0; k < rows.size(); ++k) residuals[k] = p->r[rows[k]];
    if (!jacobians) return true;
    if (layout_->dense) {
      const ResidualJacobian& jac = run_->jacobian;
      for (size_t q = 0; q < layout_->params[block_].size(); ++q) {
        if (!jacobians[q]) continue;
        std::fill(jacobians[q], jacobians[q] + rows.size(), 0.0);
        if (run_->zero_jacobian) continue;
        for (size_t e = 0; e < jac.rows[q].size(); ++e)
          jacobians[q][jac.rows[q][e]] = jac.values[q][e];
      }
      return true;
    }
    const size_t width = layout_->params[block_].size();
    const double* from = run_->cache.data() + layout_->offset[block_];
    for (size_t q = 0; q < width; ++q) {
      if (!jacobians[q]) continue;
      for (size_t k = 0; k < rows.size(); ++k) jacobians[q][k] = from[k * width + q];
    }
    return true;
  }

 private:
  const LmRun* run_;
  const Layout* layout_;
  size_t block_;
};

/// The rules checked before each trial step (Ceres calls this after every iteration, and a trial
/// step comes next): an ending decided before the Jacobian, a Jacobian the layout cannot hold,
/// too many failed steps in a row, the budget, the deadline and the cancel flag. It also reads
/// the radius the next step will use.
class StopRules final : public ceres::IterationCallback {
 public:
  explicit StopRules(LmRun* run) : run_(run) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    LmRun& run = *run_;
    run.radius = summary.trust_region_radius;
    run.failed_steps =
        summary.iteration > 0 && !summary.step_is_successful ? run.failed_steps + 1 : 0;
    if (run.reason == RefineStatus::kNotRun && !run.outside) {
      if (run.failed_steps >= kMaxFailedSteps)
        run.reason = RefineStatus::kNoProgress;
      else if (run.evaluations >= run.max_evaluations)
        run.reason = RefineStatus::kEvaluationLimit;
      else if (std::chrono::steady_clock::now() > run.settings->deadline)
        run.reason = RefineStatus::kDeadline;
      else if (run.settings->cancel && run.settings->cancel->load(std::memory_order_relaxed))
        run.reason = RefineStatus::kCancelled;
    }
    return run.reason == RefineStatus::kNotRun && !run.outside
               ? ceres::SOLVER_CONTINUE
               : ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }

 private:
  LmRun* run_;
};

/// Levenberg-Marquardt as the package runs it: the damping starts at 1e-3 (or where the last
/// solve left it: `radius`) and scales with diag(J^T J) (Ceres' Jacobi scaling with its diagonal
/// floor out of the way); any step that lowers the cost is taken (min_relative_decrease 0); a
/// step leaving the box is clamped onto it (no line search); Ceres' own tolerances are off (0:
/// only a step or cost change of exactly zero ends it), the package's rules end the search.
ceres::Solver::Options solverOptions(double radius, bool dense) {
  ceres::Solver::Options o;
  o.minimizer_type = ceres::TRUST_REGION;
  o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  o.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  if (!dense) {
    for (ceres::SparseLinearAlgebraLibraryType library : {ceres::SUITE_SPARSE, ceres::EIGEN_SPARSE})
      if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(library)) {
        o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
        o.sparse_linear_algebra_library_type = library;
        break;
      }
  }
  o.max_trust_region_radius = 1e16;
  o.initial_trust_region_radius = std::min(std::max(radius, 1e-290), o.max_trust_region_radius);
  o.min_trust_region_radius = 1e-300;
  o.min_lm_diagonal = 1e-30;
  o.min_relative_decrease = 0.0;
  o.max_num_line_search_step_size_iterations = 0;
  o.max_num_consecutive_invalid_steps = kMaxFailedSteps + 1;
  o.function_tolerance = 0.0;
  o.gradient_tolerance = 0.0;
  o.parameter_tolerance = 0.0;
  o.max_num_iterations = std::numeric_limits<int>::max();
  o.max_solver_time_in_seconds = 1e9;  // the deadline is the package's rule
  o.num_threads = 1;                   // the Jacobian's columns run on the caller's pool
  o.logging_type = ceres::SILENT;
  o.minimizer_progress_to_stdout = false;
  return o;
}

/// How a solve ended: the package's rule that ended it, else Ceres' termination. Ceres
/// converges (with its tolerances at 0) when a step or a cost change was exactly zero or the
/// radius hit its floor (no damping lowers the cost), or when the projected gradient is
/// exactly zero after a step (a stationary point).
RefineStatus statusFor(const ceres::Solver::Summary& summary, RefineStatus rule) {
  if (rule != RefineStatus::kNotRun) return rule;
  if (summary.termination_type == ceres::CONVERGENCE && !summary.iterations.empty() &&
      summary.iterations.back().step_is_successful &&
      summary.iterations.back().gradient_max_norm == 0.0)
    return RefineStatus::kConverged;
  if (summary.termination_type == ceres::NO_CONVERGENCE) return RefineStatus::kEvaluationLimit;
  return RefineStatus::kNoProgress;
}

/// One Ceres solve on `layout` from the point of the last Jacobian.
RefineStatus solve(const Layout& layout, LmRun* run) {
  const size_t n = run->n();
  run->layout = &layout;
  run->outside = false;
  run->origin = run->current.x;
  run->x.assign(n, 0.0);
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.evaluation_callback = run;
  ceres::Problem problem(problem_options);
  for (size_t j = 0; j < n; ++j) problem.AddParameterBlock(run->x.data() + j, 1);
  std::deque<ResidualBlock> blocks;  // Ceres keeps pointers: the blocks must not move
  std::vector<double*> parameters;
  for (size_t b = 0; b < layout.rows.size(); ++b) {
    blocks.emplace_back(run, &layout, b);
    parameters.clear();
    for (uint32_t j : layout.params[b]) parameters.push_back(run->x.data() + j);
    problem.AddResidualBlock(&blocks.back(), nullptr, parameters);
  }
  for (size_t j = 0; j < n; ++j) {
    const Gene& g = run->space->gene(run->active[j]);
    problem.SetParameterLowerBound(run->x.data() + j, 0, g.lower - run->origin[j]);
    problem.SetParameterUpperBound(run->x.data() + j, 0, g.upper - run->origin[j]);
  }
  ceres::Solver::Options options = solverOptions(run->radius, layout.rows.size() == 1);
  StopRules rules(run);
  options.callbacks.push_back(&rules);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return statusFor(summary, run->reason);
}

}  // namespace

LmResult levenbergMarquardt(const Cost& cost, const ParameterSpace& space,
                            const std::vector<double>& start, const LmSettings& settings,
                            ThreadPool* pool) {
  LmRun run;
  run.cost = &cost;
  run.space = &space;
  run.settings = &settings;
  run.pool = pool;
  run.began = std::chrono::steady_clock::now();
  run.m = cost.residualCount();
  for (size_t k = 0; k < space.size(); ++k)
    if (settings.movable.empty() || (k < settings.movable.size() && settings.movable[k]))
      run.active.push_back(k);
  const size_t n = run.n();
  run.max_evaluations = settings.max_evaluations > 0 ? settings.max_evaluations : 50 * (n + 1);
  run.genes = start;
  run.moved.resize(n);
  run.origin.resize(n);
  for (size_t j = 0; j < n; ++j) run.origin[j] = start[run.active[j]];
  const std::vector<double> x0(n, 0.0);

  LmResult out;
  out.genes = start;
  const Point* at_start = run.pointAt(x0.data());
  out.cost = at_start ? at_start->cost : std::numeric_limits<double>::infinity();
  out.evaluations = run.evaluations;
  if (n == 0 || run.m == 0 || !at_start) return out;
  if (run.m > std::numeric_limits<uint32_t>::max()) {  // rows are indexed in 32 bits
    out.status = RefineStatus::kJacobianTooLarge;
    return out;
  }
  // The start's Jacobian, taken here: its non-zeros give the layout Ceres solves on.
  run.cost_after.assign(1, out.cost);
  run.jacobianAt(*at_start);
  RefineStatus status = run.reason;
  std::vector<Layout> layouts;
  layouts.reserve(1);
  while (run.reason == RefineStatus::kNotRun) {
    Layout next = makeLayout(run.jacobian, run.m, n, layouts.empty() ? nullptr : &layouts.back(),
                             settings.max_jacobian_entries);
    if (next.entries > settings.max_jacobian_entries) {
      status = RefineStatus::kJacobianTooLarge;
      break;
    }
    layouts.clear();  // the previous layout is no longer referenced
    layouts.push_back(std::move(next));
    status = solve(layouts.back(), &run);
    ++out.solves;
    out.sparse = layouts.back().rows.size() > 1;
    // A Jacobian with a non-zero the layout had no place for (the cost's structure changed with
    // the point): solve again from its point on a layout that holds it.
    if (!run.outside) break;
  }
  out.evaluations = run.evaluations;
  out.jacobians = run.jacobians;
  out.status = status;
  if (run.best_cost < out.cost) {
    out.genes = run.best_genes;
    out.cost = run.best_cost;
  }
  return out;
}

}  // namespace mme

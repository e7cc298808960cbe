#include "motion_model_estimation/identification/search/ceres_levenberg_marquardt.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

#include "motion_model_estimation/identification/search/residual_jacobian.h"

namespace mme {

namespace {

/// Trial steps in a row that may fail before the search gives up: the damping has then grown by
/// 2^(1 + 2 + ... + 49) (Nielsen's factor past 1e15), far past any step that still moves a gene.
constexpr int kMaxFailedSteps = 49;
/// The damping's start (Ceres' trust region radius is its inverse).
constexpr double kInitialDamping = 1e-3;

/// A point Ceres evaluated: its parameters (the movable genes), residuals and their squared sum.
struct Point {
  std::vector<double> x;
  std::vector<double> r;
  double cost = std::numeric_limits<double>::infinity();
  bool at(const double* p) const { return !x.empty() && std::equal(x.begin(), x.end(), p); }
};

/// What one solve shares between the residual block, the iteration callback and the result:
/// the evaluations, the best point, the point of the last Jacobian and the stopping rules.
struct LmRun {
  const Cost* cost = nullptr;
  const ParameterSpace* space = nullptr;
  const LmSettings* settings = nullptr;
  ThreadPool* pool = nullptr;
  std::vector<size_t> active;  ///< Ceres' parameter j = gene active[j]
  size_t m = 0;                ///< residuals
  uint64_t max_evaluations = 0;
  std::chrono::steady_clock::time_point began;

  std::vector<double> genes;  ///< the full point (held genes at their start)
  uint64_t evaluations = 0;
  int jacobians = 0;
  std::vector<double> best_genes;
  double best_cost = std::numeric_limits<double>::infinity();
  Point last;                 ///< the last point evaluated
  Point current;              ///< where the last Jacobian was taken (Ceres' current point)
  ResidualJacobian jacobian;  ///< at `current`
  std::vector<double> cost_after;  ///< the start's cost, then after each accepted step
  double radius = 1.0 / kInitialDamping;  ///< Ceres' radius for the next step (1 / damping)
  int failed_steps = 0;                   ///< trial steps in a row that did not lower the cost
  RefineStatus reason = RefineStatus::kNotRun;  ///< the rule that ended the solve

  size_t n() const { return active.size(); }

  /// The residuals at Ceres' point p (the last or the current point again costs nothing); null
  /// when the model blew up there.
  const Point* pointAt(const double* p) {
    if (current.at(p)) return std::isfinite(current.cost) ? &current : nullptr;
    if (!last.at(p)) {
      for (size_t j = 0; j < n(); ++j) genes[active[j]] = p[j];
      last.x.assign(p, p + n());
      last.cost = cost->residuals(space->toPhysical(genes), &last.r);
      ++evaluations;
      if (std::isfinite(last.cost) && last.cost < best_cost) {
        best_cost = last.cost;
        best_genes = genes;
      }
    }
    return std::isfinite(last.cost) ? &last : nullptr;
  }

  /// Ceres asks for the Jacobian at the start and after each accepted step: the rules that can
  /// end the search there are checked first, so no Jacobian is paid for that would not be used
  /// (Ceres then gets zeros, and the iteration callback ends the solve before any step).
  void jacobianAt(const Point& p, double* dense) {
    std::fill(dense, dense + m * n(), 0.0);
    if (reason == RefineStatus::kNotRun) reason = beforeJacobian(p);
    if (reason != RefineStatus::kNotRun) return;
    current = p;
    for (size_t j = 0; j < n(); ++j) genes[active[j]] = p.x[j];
    const Eigen::Map<const Eigen::VectorXd> residual(p.r.data(), static_cast<Eigen::Index>(m));
    forwardJacobian(*cost, *space, genes, residual, active, std::numeric_limits<uint64_t>::max(),
                    pool, &jacobian);
    evaluations += n();
    ++jacobians;
    for (size_t j = 0; j < n(); ++j)
      for (size_t e = 0; e < jacobian.rows[j].size(); ++e)
        dense[jacobian.rows[j][e] * n() + j] = jacobian.values[j][e];
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
    if (!(settings->step_tolerance > 0.0)) return false;
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
    const double damping =
        std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)) / radius;
    Eigen::MatrixXd jtj;
    Eigen::VectorXd g;
    Eigen::VectorXd r = r_after;
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

/// The cost's residuals over the movable genes as one Ceres residual block.
class ResidualBlock final : public ceres::CostFunction {
 public:
  explicit ResidualBlock(LmRun* run) : run_(run) {
    mutable_parameter_block_sizes()->push_back(static_cast<int32_t>(run->n()));
    set_num_residuals(static_cast<int>(run->m));
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Point* p = run_->pointAt(parameters[0]);
    if (!p) return false;  // Ceres takes the step as failed
    std::copy(p->r.begin(), p->r.end(), residuals);
    if (jacobians && jacobians[0]) run_->jacobianAt(*p, jacobians[0]);
    return true;
  }

 private:
  LmRun* run_;
};

/// The rules checked before each trial step (Ceres calls this after every iteration, and a trial
/// step comes next): an ending decided before the Jacobian, too many failed steps in a row, the
/// budget, the deadline and the cancel flag. It also reads the radius the next step will use.
class StopRules final : public ceres::IterationCallback {
 public:
  explicit StopRules(LmRun* run) : run_(run) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    LmRun& run = *run_;
    run.radius = summary.trust_region_radius;
    run.failed_steps = summary.iteration > 0 && !summary.step_is_successful ? run.failed_steps + 1 : 0;
    if (run.reason == RefineStatus::kNotRun) {
      if (run.failed_steps >= kMaxFailedSteps)
        run.reason = RefineStatus::kNoProgress;
      else if (run.evaluations >= run.max_evaluations)
        run.reason = RefineStatus::kEvaluationLimit;
      else if (std::chrono::steady_clock::now() > run.settings->deadline)
        run.reason = RefineStatus::kDeadline;
      else if (run.settings->cancel && run.settings->cancel->load(std::memory_order_relaxed))
        run.reason = RefineStatus::kCancelled;
    }
    return run.reason == RefineStatus::kNotRun ? ceres::SOLVER_CONTINUE
                                               : ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }

 private:
  LmRun* run_;
};

/// Levenberg-Marquardt as the package runs it: the damping starts at 1e-3 and scales with
/// diag(J^T J) (Ceres' Jacobi scaling with its diagonal floor out of the way); any step that
/// lowers the cost is taken (min_relative_decrease 0); a step leaving the box is clamped onto it
/// (no line search); Ceres' own tolerances are off (0: only a step or cost change of exactly zero
/// ends it), the package's rules end the search.
ceres::Solver::Options solverOptions() {
  ceres::Solver::Options o;
  o.minimizer_type = ceres::TRUST_REGION;
  o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  // The damped normal equations, as n x n: m is large and n small.
  o.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  o.initial_trust_region_radius = 1.0 / kInitialDamping;
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

/// How the solve ended: the package's rule that ended it, else Ceres' termination. Ceres
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
  std::vector<double> x(n);
  for (size_t j = 0; j < n; ++j) x[j] = start[run.active[j]];

  LmResult out;
  out.genes = start;
  const Point* at_start = run.pointAt(x.data());
  out.cost = at_start ? at_start->cost : std::numeric_limits<double>::infinity();
  out.evaluations = run.evaluations;
  if (n == 0 || run.m == 0 || !at_start) return out;
  if (static_cast<double>(run.m) * static_cast<double>(n) >
          static_cast<double>(settings.max_jacobian_entries) ||
      run.m > static_cast<size_t>(std::numeric_limits<int>::max())) {
    out.status = RefineStatus::kJacobianTooLarge;
    return out;
  }

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ResidualBlock block(&run);
  problem.AddResidualBlock(&block, nullptr, x.data());
  for (size_t j = 0; j < n; ++j) {
    const Gene& g = space.gene(run.active[j]);
    problem.SetParameterLowerBound(x.data(), static_cast<int>(j), g.lower);
    problem.SetParameterUpperBound(x.data(), static_cast<int>(j), g.upper);
  }
  ceres::Solver::Options options = solverOptions();
  StopRules rules(&run);
  options.callbacks.push_back(&rules);
  run.cost_after.assign(1, out.cost);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);

  out.evaluations = run.evaluations;
  out.jacobians = run.jacobians;
  out.status = statusFor(summary, run.reason);
  if (run.best_cost < out.cost) {
    out.genes = run.best_genes;
    out.cost = run.best_cost;
  }
  return out;
}

}  // namespace mme

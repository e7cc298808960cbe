#include "motion_model_estimation/identification/search/ceres_levenberg_marquardt.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "motion_model_estimation/identification/search/residual_jacobian.h"

namespace mme {

namespace {

/// What one solve shares between its residual block and its stopping rules: the evaluation
/// count, the best point Ceres evaluated, and the last point's residuals (Ceres asks for the
/// Jacobian at an accepted candidate it has just evaluated: its residuals are reused, so an
/// iteration costs one evaluation per gene plus the candidate, as a hand-written LM's would).
struct LmRun {
  const Cost* cost = nullptr;
  const ParameterSpace* space = nullptr;
  ThreadPool* pool = nullptr;
  std::vector<size_t> active;      ///< Ceres' parameter j = gene active[j]
  std::vector<double> genes;       ///< the full point (held genes at their start)
  uint64_t max_jacobian_entries = 0;
  uint64_t evaluations = 0;
  int jacobians = 0;
  std::vector<double> best_genes;  ///< lowest cost among the points Ceres evaluated
  double best_cost = std::numeric_limits<double>::infinity();
  std::vector<double> last_x;      ///< the last point evaluated (Ceres' parameters) ...
  std::vector<double> last_residuals;  ///< ... its residuals ...
  double last_cost = 0.0;              ///< ... and their squared sum
  ResidualJacobian jacobian;

  void setActive(const double* x) {
    for (size_t j = 0; j < active.size(); ++j) genes[active[j]] = x[j];
  }

  /// Residuals at Ceres' point x (reused when x is the last point); false when the model blew up.
  bool residualsAt(const double* x) {
    const size_t n = active.size();
    if (last_x.size() == n && std::equal(x, x + n, last_x.begin())) return std::isfinite(last_cost);
    setActive(x);
    last_x.assign(x, x + n);
    last_cost = cost->residuals(space->toPhysical(genes), &last_residuals);
    ++evaluations;
    if (std::isfinite(last_cost) && last_cost < best_cost) {
      best_cost = last_cost;
      best_genes = genes;
    }
    return std::isfinite(last_cost);
  }

  /// The forward-difference Jacobian at the last point, row-major into Ceres' block.
  void jacobianAt(double* out) {
    const size_t n = active.size();
    const size_t m = last_residuals.size();
    setActive(last_x.data());
    const Eigen::VectorXd residual =
        Eigen::Map<const Eigen::VectorXd>(last_residuals.data(), static_cast<Eigen::Index>(m));
    forwardJacobian(*cost, *space, genes, residual, active, max_jacobian_entries, pool, &jacobian);
    evaluations += n;
    ++jacobians;
    std::fill(out, out + m * n, 0.0);
    for (size_t j = 0; j < n; ++j)
      for (size_t e = 0; e < jacobian.rows[j].size(); ++e)
        out[jacobian.rows[j][e] * n + j] = jacobian.values[j][e];
  }
};

/// The cost's residuals as one Ceres residual block over the movable genes.
class ResidualBlock final : public ceres::DynamicCostFunction {
 public:
  ResidualBlock(LmRun* run, size_t residuals) : run_(run) {
    AddParameterBlock(static_cast<int>(run->active.size()));
    SetNumResiduals(static_cast<int>(residuals));
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    if (!run_->residualsAt(parameters[0])) return false;
    std::copy(run_->last_residuals.begin(), run_->last_residuals.end(), residuals);
    if (jacobians && jacobians[0]) run_->jacobianAt(jacobians[0]);
    return true;
  }

 private:
  LmRun* run_;
};

/// The package's stopping rules, after each Ceres iteration (the first after the start's
/// Jacobian, then after each trial step, and after the Jacobian at an accepted one). Records why
/// it stopped the solve.
class StopRules final : public ceres::IterationCallback {
 public:
  StopRules(const LmRun* run, const LmSettings& settings, uint64_t max_evaluations)
      : run_(run), settings_(settings), max_evaluations_(max_evaluations),
        began_(std::chrono::steady_clock::now()) {}

  RefineStatus reason() const { return reason_; }

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    const uint64_t n = run_->active.size();
    if (summary.step_is_successful) cost_after_.push_back(run_->best_cost);
    // An iteration costs a trial step and, when it is accepted, a Jacobian.
    if (stalled()) return stop(RefineStatus::kStalled);
    if (!(run_->best_cost > 0.0)) return stop(RefineStatus::kConverged);  // an exact fit
    if (run_->evaluations + n + 1 > max_evaluations_) return stop(RefineStatus::kEvaluationLimit);
    if (settings_.cancel && settings_.cancel->load(std::memory_order_relaxed)) {
      reason_ = RefineStatus::kCancelled;
      return ceres::SOLVER_ABORT;
    }
    if (settings_.deadline != std::chrono::steady_clock::time_point::max()) {
      // Stop before an iteration that would run past the deadline (at the mean evaluation time
      // so far) rather than throw it away half done.
      const auto now = std::chrono::steady_clock::now();
      const auto per_evaluation =
          (now - began_) / static_cast<double>(std::max<uint64_t>(run_->evaluations, 1));
      if (now + per_evaluation * static_cast<double>(n + 1) > settings_.deadline)
        return stop(RefineStatus::kDeadline);
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  /// `stall_iterations` accepted steps in a row did not divide the cost by stall_factor.
  bool stalled() const {
    if (cost_after_.empty()) return false;
    const size_t steps = cost_after_.size() - 1;  // the first entry is the start
    const size_t w = static_cast<size_t>(std::max(settings_.stall_iterations, 1));
    return steps >= w && (!(settings_.stall_factor > 0.0) ||
                          !(cost_after_.back() * settings_.stall_factor <= cost_after_[steps - w]));
  }

  ceres::CallbackReturnType stop(RefineStatus reason) {
    reason_ = reason;
    return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }

  const LmRun* run_;
  const LmSettings& settings_;
  uint64_t max_evaluations_;
  std::chrono::steady_clock::time_point began_;
  std::vector<double> cost_after_;  ///< the cost at the start, then after each accepted step
  RefineStatus reason_ = RefineStatus::kNotRun;
};

/// Levenberg-Marquardt as the package ran it: the damping starts at 1e-3 (trust region radius
/// 1e3) and scales with diag(J^T J) (Jacobi scaling); any step that lowers the cost is taken
/// (min_relative_decrease 0); a step leaving the box is clamped onto it, no line search; the
/// stopping rules are StopRules' and the parameter tolerance.
ceres::Solver::Options solverOptions(const LmSettings& settings) {
  ceres::Solver::Options o;
  o.minimizer_type = ceres::TRUST_REGION;
  o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  o.linear_solver_type = ceres::DENSE_QR;
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

LmResult levenbergMarquardt(const Cost& cost, const ParameterSpace& space,
                            const std::vector<double>& start, const LmSettings& settings,
                            ThreadPool* pool) {
  LmRun run;
  run.cost = &cost;
  run.space = &space;
  run.pool = pool;
  run.genes = start;
  run.max_jacobian_entries = settings.max_jacobian_entries;
  for (size_t k = 0; k < space.size(); ++k)
    if (settings.movable.empty() || (k < settings.movable.size() && settings.movable[k]))
      run.active.push_back(k);
  const size_t n = run.active.size();
  const size_t m = cost.residualCount();
  LmResult out;
  out.genes = start;
  out.cost = std::numeric_limits<double>::infinity();
  if (n == 0 || m == 0) return out;
  if (settings.cancel && settings.cancel->load(std::memory_order_relaxed)) {
    out.status = RefineStatus::kCancelled;
    return out;
  }
  if (std::chrono::steady_clock::now() > settings.deadline) {
    out.status = RefineStatus::kDeadline;
    return out;
  }
  const double entries = static_cast<double>(m) * static_cast<double>(n);
  if (entries > static_cast<double>(settings.max_jacobian_entries) ||
      m > static_cast<size_t>(std::numeric_limits<int>::max())) {
    out.status = RefineStatus::kJacobianTooLarge;
    return out;
  }

  std::vector<double> x(n);
  for (size_t j = 0; j < n; ++j) x[j] = start[run.active[j]];
  // A start where the model blows up is not run (Ceres would log a failed first evaluation);
  // else Ceres' first evaluation reuses these residuals.
  if (!run.residualsAt(x.data())) {
    out.evaluations = run.evaluations;
    return out;
  }
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ResidualBlock block(&run, m);
  problem.AddResidualBlock(&block, nullptr, x.data());
  for (size_t j = 0; j < n; ++j) {
    const Gene& g = space.gene(run.active[j]);
    problem.SetParameterLowerBound(x.data(), static_cast<int>(j), g.lower);
    problem.SetParameterUpperBound(x.data(), static_cast<int>(j), g.upper);
  }
  const uint64_t max_evaluations =
      settings.max_evaluations > 0 ? settings.max_evaluations : 50 * (n + 1);
  StopRules rules(&run, settings, max_evaluations);
  ceres::Solver::Options options = solverOptions(settings);
  options.callbacks.push_back(&rules);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);

  out.evaluations = run.evaluations;
  out.jacobians = run.jacobians;
  out.status = statusFor(summary, rules.reason(), options.min_trust_region_radius);
  if (std::isfinite(run.best_cost)) {
    out.genes = run.best_genes;
    out.cost = run.best_cost;
  }
  return out;
}

}  // namespace mme

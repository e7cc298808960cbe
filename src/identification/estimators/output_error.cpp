// Multiple shooting with Ceres. Two residual blocks per segment: its observed samples (weighted by
// 1 / sigma) and its continuity to the next segment's start (weighted continuity_weight / sigma),
// both read from the segment's one simulation.
// Parameter blocks: the smooth genes (theta, shared by every segment, bounded as the search space)
// and one state per segment (positions and velocity x h of the free particles, metres both). A
// segment's Jacobian comes from forward sensitivities through the motion law (one simulation
// carrying the derivatives, motion_sensitivity.h), or by forward differences through the
// simulator (one short simulation per column) for a model they do not cover or when asked; it
// is shared by the segment's two blocks; the continuity's derivative along the next state is -I
// exactly. The linear solver is sparse Cholesky of the normal equations (block-tridiagonal states
// bordered by theta).
#include "motion_model_estimation/identification/estimators/output_error.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <Eigen/Sparse>

#include <algorithm>
#include <chrono>
#include <functional>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/observations.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/covariance.h"
#include "motion_model_estimation/identification/estimators/motion_sensitivity.h"
#include "output_error_segments.h"

namespace mme {

double estimateMarkerNoise(const Trajectory& trajectory) {
  const int frames = trajectory.numFrames(), n = trajectory.numMarkers();
  std::vector<double> squares;
  for (int i = 0; i < n; ++i)
    for (int t = 2; t + 2 < frames; ++t) {
      bool seen = true;
      for (int j = -2; j <= 2 && seen; ++j) seen = !trajectory.isOccluded(t + j, i);
      if (!seen) continue;
      const Eigen::Vector3d d4 = trajectory.position(t - 2, i) - 4.0 * trajectory.position(t - 1, i) +
                                 6.0 * trajectory.position(t, i) - 4.0 * trajectory.position(t + 1, i) +
                                 trajectory.position(t + 2, i);
      for (int c = 0; c < 3; ++c) squares.push_back(d4[c] * d4[c]);
    }
  if (squares.size() < 10) return 0.0;
  std::nth_element(squares.begin(), squares.begin() + squares.size() / 2, squares.end());
  // The median of a chi-square with one degree of freedom is 0.4549 of its mean.
  return std::sqrt(squares[squares.size() / 2] / 0.4549 / 70.0);
}

namespace {

using output_error_detail::dataState;
using output_error_detail::Problem;
using output_error_detail::SegmentCost;
using output_error_detail::SegmentSimulation;

/// Stops the solve when the caller's flag is raised.
class CancelCallback final : public ceres::IterationCallback {
 public:
  explicit CancelCallback(const std::atomic<bool>* flag) : flag_(flag) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return flag_ && flag_->load() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  const std::atomic<bool>* flag_;
};

/// Hands every iteration to the caller's progress hook.
class ProgressCallback final : public ceres::IterationCallback {
 public:
  ProgressCallback(const OutputErrorOptions& options, const std::function<double()>& elapsed_s)
      : options_(options), elapsed_s_(elapsed_s) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration > 0) options_.progress(summary.iteration, options_.max_iterations, elapsed_s_());
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const OutputErrorOptions& options_;
  const std::function<double()>& elapsed_s_;
};


}  // namespace

namespace {

/// Segments of K frames over `frames`; the last one takes the remainder (at least 2 frames).
std::vector<std::pair<int, int>> segmentsOf(int frames, int K) {
  std::vector<std::pair<int, int>> segments;
  for (int first = 0; first < frames - 1; first += K) {
    int last = std::min(first + K, frames - 1);
    if (frames - 1 - last < 2 && last < frames - 1) last = frames - 1;
    segments.emplace_back(first, last);
    if (last == frames - 1) break;
  }
  return segments;
}

/// The problem's data and weights; "" or why the fit cannot run.
std::string setUpProblem(const Model& model, const Trajectory& trajectory, const ParameterSpace& space,
                         const std::vector<double>& start_genes, const OutputErrorOptions& options,
                         Problem* p, OutputErrorResult* out) {
  p->obs = prepareObservations(model, trajectory);
  if (p->obs.frames < 3) return "fewer than 3 frames";
  p->model = model;
  p->model.frame_rate_hz = p->obs.frame_rate_hz;
  p->refs = freeParameters(model);
  p->space = &space;
  p->base_genes = start_genes;
  for (size_t k = 0; k < space.size(); ++k)
    if (space.gene(k).smooth) p->smooth.push_back(static_cast<int>(k));
  for (size_t i = 0; i < model.particles.size(); ++i)
    if (!model.particles[i].fixed) p->free_particles.push_back(static_cast<int>(i));
  if (p->smooth.empty() || p->free_particles.empty()) return "no smooth free parameter or no free particle";
  p->h = p->obs.frame_period_s;
  out->noise_std_prior_m =
      options.noise_std_m > 0.0 ? options.noise_std_m : std::max(estimateMarkerNoise(trajectory), 1e-9);
  p->w_obs = 1.0 / out->noise_std_prior_m;
  p->w_cont = options.continuity_weight / out->noise_std_prior_m;
  p->exact_jacobian = options.jacobian == OutputErrorJacobian::kExact;
  if (p->exact_jacobian) {
    out->exact_jacobian_unsupported = sensitivityUnsupportedReason(model);
    p->exact_jacobian = out->exact_jacobian_unsupported.empty();
  }
  out->jacobian = p->exact_jacobian ? OutputErrorJacobian::kExact : OutputErrorJacobian::kFiniteDifferences;
  return "";
}

/// The fit's unknowns: the smooth genes (theta) and one start state per segment, and the
/// segments' simulations (which outlive the Ceres problem whose blocks read them).
struct SegmentUnknowns {
  std::vector<std::pair<int, int>> segments;
  std::vector<double> theta;
  std::vector<std::vector<double>> states;
  std::vector<std::unique_ptr<SegmentSimulation>> sims;

  int count() const { return static_cast<int>(segments.size()); }

  /// The observation part of the cost, unweighted [m^2]; infinite when a simulation fails.
  double observationCost(const Problem& p) const {
    double sum = 0.0;
    for (int s = 0; s < count(); ++s) {
      std::vector<double> r(3 * sims[s]->observedSamples());
      if (!sims[s]->rows(theta.data(), states[s].data(), 0, static_cast<int>(r.size()), r.data(),
                         nullptr, nullptr))
        return std::numeric_limits<double>::infinity();
      for (double v : r) sum += v * v;
    }
    return sum / (p.w_obs * p.w_obs);
  }
};

/// Per segment, the start state whose simulation (theta held) best matches the segment's first
/// frames: a dense problem of one state, the same residuals as the observations'. Kept only when
/// it matches the whole segment better: particles unseen in the first frames (occlusion) can make
/// a fit of a few frames wrong for the rest. `elapsed_s`: the fit's time so far.
void fitStartStates(Problem* p, const OutputErrorOptions& options, const std::function<double()>& elapsed_s,
                    SegmentUnknowns* u) {
  ceres::Solver::Options local;
  local.linear_solver_type = ceres::DENSE_QR;
  local.max_num_iterations = 20;
  local.logging_type = ceres::SILENT;
  const int frames = p->obs.frames;
  for (int s = 0; s < u->count() && !(options.cancel && options.cancel->load()); ++s) {
    if (options.max_time_s > 0.0) {
      if (elapsed_s() >= options.max_time_s) break;  // the rest keep the data's states
      local.max_solver_time_in_seconds = options.max_time_s - elapsed_s();
    }
    const int first = u->segments[s].first;
    SegmentSimulation sim(p, first, std::min(first + options.start_state_frames, frames - 1), false, false);
    if (sim.observedSamples() == 0) continue;
    ceres::Problem::Options local_options;
    local_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem fit(local_options);
    fit.AddResidualBlock(new SegmentCost(&sim, p, SegmentCost::Part::kObservations), nullptr,
                         u->theta.data(), u->states[s].data());
    fit.SetParameterBlockConstant(u->theta.data());
    const std::vector<double> from_data = u->states[s];
    ceres::Solver::Summary fit_summary;
    ceres::Solve(local, &fit, &fit_summary);
    SegmentSimulation whole(p, first, u->segments[s].second, false, false);
    const auto segmentCost = [&](const std::vector<double>& state) {
      std::vector<double> r(3 * whole.observedSamples());
      if (!whole.rows(u->theta.data(), state.data(), 0, static_cast<int>(r.size()), r.data(), nullptr, nullptr))
        return std::numeric_limits<double>::infinity();
      double sum = 0.0;
      for (double v : r) sum += v * v;
      return sum;
    };
    if (!fit_summary.IsSolutionUsable() || !(segmentCost(u->states[s]) < segmentCost(from_data)))
      u->states[s] = from_data;
  }
}

/// theta bounded by the genes' bounds, a state block per segment; every observation block first,
/// then every continuity block: Ceres' threads take blocks in this order, so two threads
/// simulate two segments rather than one waiting for the other's. Returns the observations.
int buildProblem(Problem* p, const ParameterSpace& space, SegmentUnknowns* u, ceres::Problem* problem) {
  const int S = u->count();
  for (int s = 0; s < S; ++s)
    u->sims.push_back(std::make_unique<SegmentSimulation>(p, u->segments[s].first, u->segments[s].second, s + 1 < S));
  problem->AddParameterBlock(u->theta.data(), static_cast<int>(u->theta.size()));
  for (size_t j = 0; j < p->smooth.size(); ++j) {
    const Gene& g = space.gene(p->smooth[j]);
    problem->SetParameterLowerBound(u->theta.data(), static_cast<int>(j), g.lower);
    problem->SetParameterUpperBound(u->theta.data(), static_cast<int>(j), g.upper);
  }
  for (int s = 0; s < S; ++s) problem->AddParameterBlock(u->states[s].data(), p->stateSize());
  int observations = 0;
  for (int s = 0; s < S; ++s) {
    observations += 3 * u->sims[s]->observedSamples();
    problem->AddResidualBlock(new SegmentCost(u->sims[s].get(), p, SegmentCost::Part::kObservations),
                              nullptr, u->theta.data(), u->states[s].data());
  }
  for (int s = 0; s + 1 < S; ++s)
    problem->AddResidualBlock(new SegmentCost(u->sims[s].get(), p, SegmentCost::Part::kContinuity), nullptr,
                              u->theta.data(), u->states[s].data(), u->states[s + 1].data());
  return observations;
}

ceres::Solver::Options solverOptions(const OutputErrorOptions& options) {
  ceres::Solver::Options solver;
  switch (options.linear_solver) {
    case OutputErrorLinearSolver::kSparseNormalCholesky:
      solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
      break;
    case OutputErrorLinearSolver::kSparseSchur:
      solver.linear_solver_type = ceres::SPARSE_SCHUR;
      break;
    case OutputErrorLinearSolver::kIterativeSchur:
      solver.linear_solver_type = ceres::ITERATIVE_SCHUR;
      solver.preconditioner_type = ceres::SCHUR_JACOBI;
      break;
  }
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = std::max(1, options.threads);
  solver.function_tolerance = 1e-14;
  solver.gradient_tolerance = 1e-16;
  solver.parameter_tolerance = 1e-12;
  // The projected line search Ceres runs on a bounded problem interpolates with function values
  // only: its default (cubic) asks for the Jacobian at every trial point, here a simulation per
  // column, nearly doubling the cost of an iteration.
  solver.line_search_interpolation_type = ceres::QUADRATIC;
  solver.logging_type = ceres::SILENT;
  return solver;
}

/// Adds a solve's time split to the result's.
void addTimes(const ceres::Solver::Summary& summary, OutputErrorResult* out) {
  out->jacobian_time_s += summary.jacobian_evaluation_time_in_seconds;
  out->linear_solver_time_s += summary.linear_solver_time_in_seconds;
}

/// The solve, with continuation when asked: soft continuity first, then the given weight (the
/// cached residuals carry the weight: recomputed at each change). Returns the iterations.
int solveWithContinuation(Problem* p, const OutputErrorOptions& options, double noise_std_prior_m,
                          const std::function<double()>& elapsed_s, SegmentUnknowns* u,
                          ceres::Problem* problem, ceres::Solver::Summary* summary,
                          OutputErrorResult* out) {
  ceres::Solver::Options solver = solverOptions(options);
  // The start-state fits spent part of the budget.
  if (options.max_time_s > 0.0) solver.max_solver_time_in_seconds = std::max(1e-3, options.max_time_s - elapsed_s());
  CancelCallback cancel(options.cancel);
  if (options.cancel) solver.callbacks.push_back(&cancel);
  ProgressCallback progress(options, elapsed_s);
  if (options.progress) solver.callbacks.push_back(&progress);
  int first_stage_iterations = 0;
  const double hard_w_cont = p->w_cont;
  if (options.first_continuity_weight > 0.0 && options.first_continuity_weight != options.continuity_weight) {
    p->w_cont = options.first_continuity_weight / noise_std_prior_m;
    for (auto& sim : u->sims) sim->invalidate();
    ceres::Solver::Options first_stage = solver;
    first_stage.function_tolerance = options.first_stage_function_tolerance;
    ceres::Solve(first_stage, problem, summary);
    addTimes(*summary, out);
    first_stage_iterations = static_cast<int>(summary->iterations.size()) - 1;
    p->w_cont = hard_w_cont;
    for (auto& sim : u->sims) sim->invalidate();
    if (options.max_time_s > 0.0)
      solver.max_solver_time_in_seconds = std::max(1e-3, options.max_time_s - elapsed_s());
  }
  if (!(options.cancel && options.cancel->load())) {
    ceres::Solve(solver, problem, summary);
    addTimes(*summary, out);
  }
  return first_stage_iterations + static_cast<int>(summary->iterations.size()) - 1;
}

/// The parameters' std from the whole problem's Jacobian at the optimum, the segment states
/// marginalised (covariance.h), scaled by (sigma_hat / sigma_prior)^2: the residuals are weighted
/// by the prior noise, and the residuals at the optimum measure the actual one.
void estimateStd(const Problem& p, const ParameterSpace& space, const OutputErrorOptions& options,
                 SegmentUnknowns* u, ceres::Problem* problem, OutputErrorResult* out) {
  ceres::CRSMatrix crs;
  ceres::Problem::EvaluateOptions eval;
  eval.parameter_blocks.push_back(u->theta.data());
  for (int s = 0; s < u->count(); ++s) eval.parameter_blocks.push_back(u->states[s].data());
  if (!problem->Evaluate(eval, nullptr, nullptr, nullptr, &crs)) {
    out->std_failure = "the Jacobian at the optimum could not be evaluated";
    return;
  }
  const Eigen::SparseMatrix<double> jacobian =
      sparseFromCompressedRows(crs.num_rows, crs.num_cols, crs.rows, crs.cols, crs.values);
  CovarianceOptions covariance_options;
  covariance_options.residual_variance =
      options.std_from_given_noise ? 1.0 : std::pow(out->noise_std_m / out->noise_std_prior_m, 2);
  const ParameterCovariance covariance =
      parameterCovariance(jacobian, static_cast<Eigen::Index>(u->theta.size()), covariance_options);
  const std::vector<size_t> column_genes(p.smooth.begin(), p.smooth.end());
  GeneUncertainty genes = geneUncertainty(covariance, space, out->genes, column_genes);
  out->std_failure = genes.failure;
  out->std_devs = std::move(genes.std_devs);
  out->unidentifiable = std::move(genes.unidentifiable);
}

/// One fit on the whole trajectory (the stages of OutputErrorOptions::grow_segments call it on
/// its first frames).
OutputErrorResult fitOnce(const Model& model, const Trajectory& trajectory,
                          const ParameterSpace& space, const std::vector<double>& start_genes,
                          const OutputErrorOptions& options) {
  const auto began = std::chrono::steady_clock::now();
  const std::function<double()> elapsed_s = [&]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  };
  OutputErrorResult out;
  out.genes = start_genes;
  out.values = space.toPhysical(start_genes);
  out.std_devs.assign(start_genes.size(), std::numeric_limits<double>::quiet_NaN());
  out.unidentifiable.assign(start_genes.size(), 0);
  if (options.segment_frames < 2 || !(options.continuity_weight > 0.0) ||
      !(options.first_continuity_weight >= 0.0) || options.grow_segments < 0 ||
      !(options.first_stage_function_tolerance > 0.0 && options.first_stage_function_tolerance < 1.0)) {
    out.reason = "segment_frames must be >= 2, continuity_weight > 0, first_continuity_weight >= 0, "
                 "grow_segments >= 0 and first_stage_function_tolerance in (0, 1)";
    return out;
  }
  auto p = std::make_unique<Problem>();
  out.reason = setUpProblem(model, trajectory, space, start_genes, options, p.get(), &out);
  if (!out.reason.empty()) return out;
  SegmentUnknowns u;
  u.segments = segmentsOf(p->obs.frames, options.segment_frames);
  const int ns = p->stateSize();
  u.theta.resize(p->smooth.size());
  for (size_t j = 0; j < p->smooth.size(); ++j) u.theta[j] = start_genes[p->smooth[j]];
  u.states.assign(u.count(), std::vector<double>(ns));
  for (int s = 0; s < u.count(); ++s) dataState(*p, u.segments[s].first, u.states[s].data());
  if (options.start_state_frames > 0) fitStartStates(p.get(), options, elapsed_s, &u);

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  out.observations = buildProblem(p.get(), space, &u, &problem);
  out.segments = u.count();
  out.start_cost_m2 = u.observationCost(*p);
  ceres::Solver::Summary summary;
  out.iterations = solveWithContinuation(p.get(), options, out.noise_std_prior_m, elapsed_s, &u, &problem,
                                         &summary, &out);
  out.ran = true;
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  out.stopped_by_time = !out.converged && options.max_time_s > 0.0 && elapsed_s() >= options.max_time_s;
  out.termination = summary.message;
  out.observation_cost_m2 = u.observationCost(*p);
  for (size_t j = 0; j < p->smooth.size(); ++j) out.genes[p->smooth[j]] = u.theta[j];
  out.values = space.toPhysical(out.genes);
  // With nearly hard continuity the segment states are one trajectory's: its start state and
  // the parameters are what the observations determine.
  const int unknowns = static_cast<int>(u.theta.size()) + ns;
  const int dof = std::max(1, out.observations - unknowns);
  out.noise_std_m = std::sqrt(out.observation_cost_m2 / dof);
  if (options.estimate_std && !(options.cancel && options.cancel->load()))
    estimateStd(*p, space, options, &u, &problem, &out);
  out.wall_time_s = elapsed_s();
  return out;
}

}  // namespace

const char* outputErrorJacobianName(OutputErrorJacobian jacobian) {
  switch (jacobian) {
    case OutputErrorJacobian::kExact: return "exact";
    case OutputErrorJacobian::kFiniteDifferences: return "finite differences";
  }
  return "?";
}

OutputErrorResult estimateOutputError(const Model& model, const Trajectory& trajectory,
                                      const ParameterSpace& space,
                                      const std::vector<double>& start_genes,
                                      const OutputErrorOptions& options) {
  const int K = options.segment_frames;
  // Nothing to grow, or options fitOnce refuses (with its reason).
  if (options.grow_segments <= 0 || K < 2 ||
      static_cast<long>(options.grow_segments) * K + 1 >= trajectory.numFrames())
    return fitOnce(model, trajectory, space, start_genes, options);
  // Continuation in the data's length: the first grow_segments segments' frames, then twice as
  // many, ..., then all, each stage from the last one's answer. One noise figure (the whole
  // data's) weights every stage; the last stage alone estimates the std.
  const auto began = std::chrono::steady_clock::now();
  const auto elapsed_s = [&]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  };
  OutputErrorOptions stage = options;
  stage.grow_segments = 0;
  if (!(stage.noise_std_m > 0.0))
    stage.noise_std_m = std::max(estimateMarkerNoise(trajectory), 1e-9);
  std::vector<double> genes = start_genes;
  int iterations = 0, stages = 0;
  double jacobian_time_s = 0.0, linear_solver_time_s = 0.0;
  for (long segments = options.grow_segments;; segments *= 2) {
    const bool last = segments * K + 1 >= trajectory.numFrames();
    stage.estimate_std = last && options.estimate_std;
    if (options.max_time_s > 0.0)
      stage.max_time_s = std::max(1e-3, options.max_time_s - elapsed_s());
    const Trajectory part =
        last ? trajectory : sliceFrames(trajectory, 0, static_cast<int>(segments * K + 1));
    OutputErrorResult r = fitOnce(model, part, space, genes, stage);
    if (!r.ran) {
      r.reason = "on the first " + std::to_string(part.numFrames()) + " frames: " + r.reason;
      return r;
    }
    iterations += r.iterations;
    jacobian_time_s += r.jacobian_time_s;
    linear_solver_time_s += r.linear_solver_time_s;
    ++stages;
    genes = r.genes;
    const bool stopped = (options.cancel && options.cancel->load()) ||
                         (options.max_time_s > 0.0 && elapsed_s() >= options.max_time_s);
    if (last || stopped) {
      // Stopped early: the answer so far, judged on the whole data (its costs are what callers
      // compare, its std what they report), with no iteration.
      if (!last) {
        stage.max_iterations = 0;
        stage.max_time_s = 0.0;
        stage.estimate_std = options.estimate_std;
        r = fitOnce(model, trajectory, space, genes, stage);
      }
      if (!last && !(options.cancel && options.cancel->load())) r.stopped_by_time = true;
      r.iterations = iterations;
      r.jacobian_time_s = jacobian_time_s;
      r.linear_solver_time_s = linear_solver_time_s;
      r.stages = stages;
      r.wall_time_s = elapsed_s();
      return r;
    }
  }
}

std::vector<double> cramerRaoBound(const Model& model, const Trajectory& trajectory,
                                   const ParameterSpace& space, double noise_std_m,
                                   int segment_frames) {
  const std::vector<double> truth = space.toSearch(getValues(model, freeParameters(model)));
  OutputErrorOptions o;
  o.segment_frames = segment_frames;
  o.noise_std_m = noise_std_m;
  o.std_from_given_noise = true;
  o.max_iterations = 20;  // only the segment states move (the data are the truth's own motion)
  const OutputErrorResult r = estimateOutputError(model, trajectory, space, truth, o);
  return r.std_devs;
}

}  // namespace mme

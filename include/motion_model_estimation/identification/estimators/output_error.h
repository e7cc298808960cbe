// The noise-robust estimator: output error by multiple shooting. The one-step prediction cost
// takes accelerations and forces from the same noisy positions, so its minimiser is biased
// (errors in variables) whatever the number of frames. Here the model is simulated over segments
// of K frames from estimated start states (positions and velocities of every free particle, one
// set per segment), and every observed sample is compared with the simulation; continuity
// residuals tie each segment's end to the next one's start, weighted as nearly hard. The unknowns
// are the smooth parameters and the segment states; the thresholds of conditional bonds stay where
// the evolution strategy put them. Solved as a sparse non-linear least-squares problem with Ceres;
// occluded samples simply have no residual.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/search/parameter_space.h"

namespace mme {

/// Marker noise std [m] estimated from the data alone: for white noise the fourth difference
/// x(t-2) - 4x(t-1) + 6x(t) - 4x(t+1) + x(t+2) has variance 70 sigma^2, while smooth motion
/// contributes only h^4 x''''. Robust (median of the squares). 0 when too few samples.
double estimateMarkerNoise(const Trajectory& trajectory);

/// How the output error forms its segments' Jacobians.
enum class OutputErrorJacobian {
  /// Forward sensitivities through the motion law (motion_sensitivity.h): exact, one
  /// simulation per segment. A model they do not cover (sensitivityUnsupportedReason) falls
  /// back to finite differences (OutputErrorResult::exact_jacobian_unsupported says why).
  kExact,
  /// Forward differences: one simulation per column; kept to compare against (bench).
  kFiniteDifferences,
};

/// "exact" or "finite differences" (the command line's and the bench's word).
const char* outputErrorJacobianName(OutputErrorJacobian jacobian);

/// The linear solver of the output error's Gauss-Newton steps (Ceres' names). The Schur ones
/// eliminate an independent set of segment states first (every other one: a continuity block
/// joins two neighbours), Ceres' automatic ordering.
enum class OutputErrorLinearSolver {
  kSparseNormalCholesky,  ///< J^T J of the whole problem, sparse Cholesky
  kSparseSchur,           ///< the eliminated states' Schur complement, sparse Cholesky
  kIterativeSchur,        ///< the same, conjugate gradients (Schur-Jacobi preconditioner)
};

struct OutputErrorOptions {
  int segment_frames = 10;          ///< K: frames per shooting segment
  /// Weight of a continuity residual relative to an observation's: large = nearly hard (the
  /// model's own motion between segments); a soft weight throws information away.
  double continuity_weight = 1000.0;
  /// Continuation: when > 0, the problem is first solved with this continuity weight (segments
  /// nearly free to follow their own data: a start far from the answer does not have to carry
  /// one wrong motion over every segment), then from there with `continuity_weight`. Each stage
  /// gets max_iterations. 0 = one stage.
  double first_continuity_weight = 1.0;
  /// Where the first (soft-continuity) stage stops: a relative change of the cost per iteration
  /// below this (Ceres' function tolerance). Its answer is only the hard stage's start, so it
  /// need not be exact; and with a parameter pressed on a bound (dampers near 0 while every
  /// segment follows its own data) Ceres' projected steps creep there for dozens of iterations
  /// that change nothing the hard stage keeps: 1e-3 saves most of them on damped objects. 1e-14
  /// (the default) runs it to the hard stage's precision.
  double first_stage_function_tolerance = 1e-14;
  double noise_std_m = 0.0;         ///< marker noise; 0 = estimated (estimateMarkerNoise)
  int max_iterations = 100;
  /// Start states from the model: each segment's start state (positions and velocities) is
  /// the one whose simulation with the start's parameters best matches the data over the
  /// segment's first `start_state_frames` frames after its start (a small least-squares fit per
  /// segment, parameters held), instead of the data's positions and frame differences (0). The
  /// frame difference is not the velocity when stiff forces act within a frame, and a joint fit
  /// from it moves the parameters to absorb the error (docs/scenes.md "Identifying the walker").
  int start_state_frames = 2;
  /// Continuation in the data's length: when > 0, the fit runs first on the frames of the first
  /// `grow_segments` segments, then on twice as many segments, and so on, then on all the
  /// frames, each stage from the last one's answer with both continuity stages and
  /// max_iterations (max_time_s bounds them all; a stop by time or `cancel` still judges the
  /// answer on every frame): a way around local minima of one fit on every frame. Measured on
  /// the walker (bench_paper --only walker_oe, 50 frames, 10-frame segments, 1 % off): see
  /// docs/scenes.md "Identifying the walker". The result's iterations and wall time cover every
  /// stage; its start_cost_m2 is the last stage's start (the previous stage's answer on all
  /// frames).
  /// 0: one fit on every frame.
  int grow_segments = 0;
  double max_time_s = 0.0;          ///< 0 = no limit
  int threads = 1;                  ///< Ceres' threads evaluating segments
  OutputErrorJacobian jacobian = OutputErrorJacobian::kExact;
  /// The Gauss-Newton steps' linear solver; the choice of the default is measured by
  /// `bench_paper --only oe_speed` (docs/estimators.md, "The output error's time").
  OutputErrorLinearSolver linear_solver = OutputErrorLinearSolver::kSparseNormalCholesky;
  bool estimate_std = true;         ///< 1-sigma std per parameter from the Jacobian at the optimum
  /// The std from noise_std_m as given (the Cramer-Rao bound) rather than from the residuals.
  bool std_from_given_noise = false;
  /// Raised by another thread: the solve stops after its current iteration (keeping its best).
  const std::atomic<bool>* cancel = nullptr;
  /// Called after every iteration of a stage's solve: the iteration (from 1), the stage's
  /// max_iterations and the wall time since the fit began [s] (a tool's progress line with an
  /// estimate of the time left). Empty: nothing called.
  std::function<void(int iteration, int max_iterations, double elapsed_s)> progress;
};

struct OutputErrorResult {
  bool ran = false;
  std::string reason;               ///< why it did not run
  std::vector<double> genes;        ///< search space, as the start's (thresholds unchanged)
  std::vector<double> values;       ///< physical, freeParameters order
  /// 1-sigma from the Fisher information J^T J / sigma^2 of the whole problem, the segment states
  /// marginalised (their uncertainty propagated; covariance.h); NaN for thresholds and
  /// undetermined parameters.
  std::vector<double> std_devs;
  /// The data do not determine it: it lies (mostly) in the information matrix's null space, or
  /// its std is larger than its value.
  std::vector<uint8_t> unidentifiable;
  /// Why every std is NaN although it was asked for (the covariance could not be computed);
  /// empty otherwise.
  std::string std_failure;
  double noise_std_m = 0.0;         ///< from the residuals at the optimum (RMS per coordinate)
  double noise_std_prior_m = 0.0;   ///< the one the weights used (given or estimated)
  double observation_cost_m2 = 0.0; ///< sum of squared position errors at the optimum [m^2]
  double start_cost_m2 = 0.0;       ///< the same at the start (states from the data)
  int observations = 0;             ///< observed coordinates compared
  int segments = 0;
  int iterations = 0;               ///< of both stages (and of every grow_segments stage)
  int stages = 1;                   ///< fits on growing data run (grow_segments; 1 without)
  bool converged = false;           ///< Ceres reported convergence (not a limit)
  /// The time limit (OutputErrorOptions::max_time_s) ended the fit, or left it no time to start:
  /// the answer is where the solver was, not an optimum.
  bool stopped_by_time = false;
  std::string termination;          ///< Ceres' message
  /// The Jacobian the fit used (finite differences when asked for, or when the model has
  /// something the exact sensitivities do not cover).
  OutputErrorJacobian jacobian = OutputErrorJacobian::kFiniteDifferences;
  /// Exact Jacobians were asked for but not used: why (the model's unsupported part); else empty.
  std::string exact_jacobian_unsupported;
  /// Where the solves' time went (Ceres' summaries, every stage): forming the Jacobians, and the
  /// linear solver (the normal equations or the Schur complement, and their factorisation) [s].
  double jacobian_time_s = 0.0;
  double linear_solver_time_s = 0.0;
  double wall_time_s = 0.0;
};

/// Fits the model's smooth free parameters (starting at `start_genes`, e.g. the evolution
/// strategy's best) and the segment states to `trajectory` (the model's particles as markers).
/// `model.substeps` is the integrator the simulation uses.
OutputErrorResult estimateOutputError(const Model& model, const Trajectory& trajectory,
                                      const ParameterSpace& space,
                                      const std::vector<double>& start_genes,
                                      const OutputErrorOptions& options = {});

/// The Cramer-Rao bound of the output-error model: the 1-sigma std [physical units] of every
/// smooth parameter an efficient estimator would reach from `trajectory` with white marker noise
/// of noise_std_m, the initial positions and velocities unknown too (Fisher information
/// J^T J / sigma^2, J = d(every observed position) / d(parameters, initial state), the states
/// eliminated). `trajectory` is the noiseless motion of `model` whose free values are the truth
/// (its occlusion pattern is the data's). NaN for thresholds and undetermined parameters.
std::vector<double> cramerRaoBound(const Model& model, const Trajectory& trajectory,
                                   const ParameterSpace& space, double noise_std_m,
                                   int segment_frames = 10);

}  // namespace mme

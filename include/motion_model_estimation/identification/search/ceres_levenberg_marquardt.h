// A Levenberg-Marquardt refinement on the cost's residuals, solved by Ceres: the paper's cost is a
// sum of squared prediction errors, so near the answer a Gauss-Newton model of it is nearly exact
// and converges in a few Jacobians where a derivative-free quadratic model (BOBYQA) needs
// thousands of evaluations. Works in the search space (genes), inside the bounds (Ceres' parameter
// bounds: projected steps, no line search). One residual block per residual group of the cost (a
// particle's residuals, over the bond types that can move it: Cost::residualGroups), so Ceres
// forms the damped normal equations from the blocks (sparse LDL^T) instead of a dense Jacobian.
// The blocks' Jacobian is the package's forward difference (residual_jacobian.h: one residual
// evaluation per gene for all blocks, columns in parallel on the caller's pool), so the result
// does not depend on the thread count. Ceres runs the damping
// (Marquardt scaling, Nielsen's update) and the linear algebra; an iteration callback applies the
// package's stopping rules (stall, evaluation budget, deadline, cancel flag), and Ceres' own
// parameter tolerance (or a projected gradient that rounds to zero) is the convergence test.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <vector>

#include "motion_model_estimation/core/cost.h"
#include "motion_model_estimation/core/thread_pool.h"
#include "motion_model_estimation/identification/search/parameter_space.h"
#include "motion_model_estimation/identification/search/refiner.h"

namespace mme {

struct LmSettings {
  uint64_t max_evaluations = 0;  ///< residual evaluations (0 = 50 x (genes + 1))
  /// Stops when `stall_iterations` Jacobians in a row did not divide the cost by this (converged
  /// to a noisy optimum or crawling); 0: stop after `stall_iterations` Jacobians.
  double stall_factor = 1.01;
  int stall_iterations = 3;
  /// Converged when a step moves the genes by no more than this share of their norm (Ceres'
  /// parameter_tolerance); 0: off.
  double step_tolerance = 1e-10;
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
  const std::atomic<bool>* cancel = nullptr;  ///< raised: stop at the next iteration
  /// Most entries of the Jacobian Ceres may hold (the blocks': each group's residuals x its
  /// movable genes; residuals x movable genes for a cost without groups; it keeps a few copies
  /// of 8 bytes per entry); beyond it the refinement does not start
  /// (RefineStatus::kJacobianTooLarge: the caller may fall back to a derivative-free search).
  uint64_t max_jacobian_entries = 40000000;
  /// Genes the search may move (empty = all); the others keep their start value and cost no
  /// Jacobian column.
  std::vector<uint8_t> movable;
};

struct LmResult {
  std::vector<double> genes;  ///< best point (inside the bounds)
  double cost = 0.0;          ///< its global cost [m^2]
  uint64_t evaluations = 0;   ///< residual evaluations (each = one full-cost evaluation)
  int jacobians = 0;
  /// kConverged (Ceres' parameter or gradient tolerance, met by the step the last Jacobian
  /// predicts, or an exact fit), kStalled (stall rule),
  /// kNoProgress (no damping lowers the cost, or the model blew up), kEvaluationLimit,
  /// kDeadline (passed, or the next iteration would pass it), kCancelled, kJacobianTooLarge
  /// (not started: the Jacobian would exceed max_jacobian_entries).
  RefineStatus status = RefineStatus::kNotRun;
};

/// Minimises cost(space.toPhysical(genes)) from `start` (inside the bounds). `pool` may be null
/// (one thread).
LmResult levenbergMarquardt(const Cost& cost, const ParameterSpace& space,
                            const std::vector<double>& start, const LmSettings& settings,
                            ThreadPool* pool);

}  // namespace mme

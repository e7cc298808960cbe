// A Levenberg-Marquardt refinement on the cost's residuals, solved by Ceres: the paper's cost is a
// sum of squared prediction errors, so near the answer a Gauss-Newton model of it is nearly exact
// and converges in a few Jacobians where a derivative-free quadratic model (BOBYQA) needs
// thousands of evaluations. Works in the search space (genes), inside the bounds (Ceres' parameter
// bounds: a step leaving the box is clamped onto it, no line search). The Jacobian is the
// package's forward difference (residual_jacobian.h: one residual evaluation per gene, columns in
// parallel on the caller's pool), so the result does not depend on the thread count. A gene moves
// only the terms near its bond type's sites, so the residuals are grouped into Ceres residual
// blocks by the genes that move them (the start's Jacobian's non-zeros) and Ceres solves the
// damped normal equations by sparse Cholesky; one dense block when a quarter of the Jacobian is
// there or the genes are few (32 at most). A later Jacobian with a non-zero outside those blocks (the structure changed with the
// point: a contact, a switching bond) restarts the solve from its point on blocks that hold it.
// Ceres runs the damping (Marquardt's diagonal scaling, Nielsen's update, starting at 1e-3) and
// the linear algebra; the package's stopping rules (step tolerance, stall, evaluation budget,
// deadline, cancel flag) are checked before each Jacobian, so none is paid for that would not be
// used, and an iteration callback applies them before each trial step.
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
  /// Converged when, after a step the linear model predicted well, the next step it predicts
  /// (with the same Jacobian) moves no gene by more than this share of its range; 0: off.
  double step_tolerance = 1e-10;
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
  const std::atomic<bool>* cancel = nullptr;  ///< raised: stop before the next Jacobian or step
  /// Most Jacobian entries kept (the non-zeros, or residuals x genes for one dense block; a few
  /// copies of 8-12 bytes each); beyond it the refinement stops with its best point
  /// (RefineStatus::kJacobianTooLarge: the caller may fall back to a derivative-free search).
  uint64_t max_jacobian_entries = 50000000;
  /// Genes the search may move (empty = all); the others keep their start value and cost no
  /// Jacobian column.
  std::vector<uint8_t> movable;
};

struct LmResult {
  std::vector<double> genes;  ///< best point (inside the bounds)
  double cost = 0.0;          ///< its global cost [m^2]
  uint64_t evaluations = 0;   ///< residual evaluations (each = one full-cost evaluation)
  int jacobians = 0;
  int solves = 0;       ///< Ceres solves (more than one when the structure grew)
  bool sparse = false;  ///< the last solve ran on several residual blocks (sparse Cholesky)
  /// kConverged (step tolerance, an exact fit, or a projected gradient of exactly zero),
  /// kStalled (stall rule), kNoProgress (no damping lowers the cost: the step vanished or 49
  /// trial steps in a row failed), kEvaluationLimit, kDeadline (passed, or the next Jacobian
  /// would pass it), kCancelled, kJacobianTooLarge, kNotRun (the model blows up at
  /// the start, or nothing to move).
  RefineStatus status = RefineStatus::kNotRun;
};

/// Minimises cost(space.toPhysical(genes)) from `start` (inside the bounds). `pool` may be null
/// (one thread).
LmResult levenbergMarquardt(const Cost& cost, const ParameterSpace& space,
                            const std::vector<double>& start, const LmSettings& settings,
                            ThreadPool* pool);

}  // namespace mme

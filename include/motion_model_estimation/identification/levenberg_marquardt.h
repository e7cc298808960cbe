// A Levenberg-Marquardt refinement on the cost's residuals: the paper's cost is a sum of squared
// prediction errors, so near the answer a Gauss-Newton model of it is nearly exact and converges
// in a few Jacobians where a derivative-free quadratic model (BOBYQA) needs thousands of
// evaluations. Works in the search space (genes), inside the bounds (projected steps); the
// Jacobian is by forward differences, one residual evaluation per gene, its columns computed in
// parallel (each column is independent: the result does not depend on the thread count).
#pragma once

#include <chrono>
#include <cstdint>
#include <vector>

#include "motion_model_estimation/core/cost.h"
#include "motion_model_estimation/core/thread_pool.h"
#include "motion_model_estimation/identification/parameter_space.h"

namespace mme {

struct LmSettings {
  uint64_t max_evaluations = 0;  ///< residual evaluations (0 = 50 x (genes + 1))
  /// Stops when `stall_iterations` Jacobians in a row did not divide the cost by this (converged
  /// to a noisy optimum or crawling); 0: stop after `stall_iterations` Jacobians.
  double stall_factor = 1.01;
  int stall_iterations = 3;
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
  /// Most non-zero Jacobian entries kept (12 bytes each: 10^8 = 1.2 GB); beyond it the
  /// refinement stops rather than exhaust memory (LmResult::jacobian_too_large).
  uint64_t max_jacobian_entries = 100000000;
};

struct LmResult {
  std::vector<double> genes;  ///< best point (inside the bounds)
  double cost = 0.0;          ///< its global cost [m^2]
  uint64_t evaluations = 0;   ///< residual evaluations (each = one full-cost evaluation)
  int jacobians = 0;
  /// The Jacobian's non-zero entries exceeded max_jacobian_entries: stopped there, keeping the
  /// best point so far (the caller may fall back to a derivative-free search).
  bool jacobian_too_large = false;
};

/// Minimises cost(space.toPhysical(genes)) from `start` (inside the bounds). `pool` may be null
/// (one thread).
LmResult levenbergMarquardt(const CostFunction& cost, const ParameterSpace& space,
                            const std::vector<double>& start, const LmSettings& settings,
                            ThreadPool* pool);

}  // namespace mme

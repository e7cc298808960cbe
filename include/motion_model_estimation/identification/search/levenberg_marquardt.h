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

#include <Eigen/Core>

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
  /// Most non-zero Jacobian entries kept (12 bytes each: 10^8 = 1.2 GB); beyond it the
  /// refinement stops rather than exhaust memory (LmResult::jacobian_too_large).
  uint64_t max_jacobian_entries = 100000000;
  /// Genes the search may move (empty = all); the others keep their start value and cost no
  /// Jacobian column.
  std::vector<uint8_t> movable;
};

struct LmResult {
  std::vector<double> genes;  ///< best point (inside the bounds)
  double cost = 0.0;          ///< its global cost [m^2]
  uint64_t evaluations = 0;   ///< residual evaluations (each = one full-cost evaluation)
  int jacobians = 0;
  /// kConverged (step tolerance), kStalled (stall rule), kNoProgress (no damping lowers the
  /// cost), kEvaluationLimit, kDeadline (passed, or the next Jacobian would pass it), kCancelled,
  /// kJacobianTooLarge (the non-zero entries exceeded max_jacobian_entries: stopped there with
  /// the best point so far; the caller may fall back to a derivative-free search).
  RefineStatus status = RefineStatus::kNotRun;
};

namespace detail {

/// A Jacobian (m rows x n genes) by sparse columns: the row indices of each column ascending and
/// its non-zero values. The forward differences of a gene are exactly zero on the terms it does
/// not move, so a large model's Jacobian is mostly absent.
struct JacobianColumns {
  size_t rows_count = 0;                      ///< m
  std::vector<std::vector<uint32_t>> rows;    ///< per gene
  std::vector<std::vector<double>> values;    ///< per gene, same length as rows[k]
  size_t nonZeros() const;
  /// J^T r.
  Eigen::VectorXd gradient(const Eigen::VectorXd& residual) const;
};

enum class NormalEquationsPath { kAuto, kDense, kSparse };

/// J^T J (dense n x n, symmetric) and J^T r. kAuto: a dense m x n matrix and Eigen's blocked
/// product when at least a quarter of J is stored (and m x n fits in 64 MB), else the outer
/// products of J's rows (cost: the sum over rows of their non-zeros squared).
void normalEquations(const JacobianColumns& jac, const Eigen::VectorXd& residual,
                     Eigen::MatrixXd* jtj, Eigen::VectorXd* g,
                     NormalEquationsPath path = NormalEquationsPath::kAuto);

/// Forward-difference Jacobian of cost.residuals() (in search space) at genes x, whose residuals
/// are `residual`, over the genes `active` (column j = gene active[j]); one residual evaluation
/// per column, columns in parallel on `pool` (may be null). False when the stored entries
/// exceeded max_entries (the columns are then incomplete).
bool forwardJacobian(const Cost& cost, const ParameterSpace& space, const std::vector<double>& x,
                     const Eigen::VectorXd& residual, const std::vector<size_t>& active,
                     uint64_t max_entries, ThreadPool* pool, JacobianColumns* jac);

}  // namespace detail

/// Minimises cost(space.toPhysical(genes)) from `start` (inside the bounds). `pool` may be null
/// (one thread).
LmResult levenbergMarquardt(const Cost& cost, const ParameterSpace& space,
                            const std::vector<double>& start, const LmSettings& settings,
                            ThreadPool* pool);

}  // namespace mme

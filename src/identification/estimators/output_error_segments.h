// The output error's shooting segments (output_error.cpp's private part): what every segment
// shares, one segment's simulation with its residuals and Jacobian, and the Ceres cost blocks
// that read it. Only output_error.cpp and output_error_segments.cpp include it.
#pragma once

#include <ceres/ceres.h>

#include <mutex>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/observations.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/search/parameter_space.h"

namespace mme {
namespace output_error_detail {

/// What every segment shares (read-only during the solve).
struct Problem {
  Model model;                      // values of fixed parameters; free ones set per evaluation
  std::vector<ParamRef> refs;
  const ParameterSpace* space = nullptr;
  std::vector<double> base_genes;   // the start: thresholds keep these
  std::vector<int> smooth;          // gene indices Ceres moves (theta order)
  std::vector<int> free_particles;  // particle indices in the state
  Observations obs;
  double h = 0.0;                   // frame period [s]
  double w_obs = 1.0;               // 1 / sigma
  double w_cont = 1.0;              // continuity_weight / sigma
  bool exact_jacobian = true;       // forward sensitivities (else forward differences)

  int stateSize() const { return 6 * static_cast<int>(free_particles.size()); }
};

/// A shooting segment's simulation (frames [first, last]), shared by its two residual blocks:
/// both need the same residuals and the same forward-difference Jacobian (one short simulation
/// per column), which it computes once per (theta, state) and hands to each. The rows are the
/// observed samples (at first..last-1, and at last for the final segment) and then, when a next
/// segment exists, the end state x continuity weight (the next state is subtracted by the
/// continuity block, whose derivative along it is -I exactly). Thread-safe: Ceres may evaluate
/// both blocks at once.
class SegmentSimulation {
 public:
  /// `theta_columns` false: the Jacobian along theta is left zero (a fit with theta held).
  SegmentSimulation(const Problem* p, int first, int last, bool has_next, bool theta_columns = true)
      : p_(p), first_(first), last_(last), has_next_(has_next), theta_columns_(theta_columns),
        model_(p->model), sim_(p->model) {
    const int end = has_next ? last : last + 1;
    for (int t = first; t < end; ++t)
      for (int i : p->free_particles) observed_ += p->obs.isOccluded(t, i) ? 0 : 1;
    rows_ = 3 * observed_ + (has_next ? p->stateSize() : 0);
  }

  int observedSamples() const { return observed_; }

  /// Forgets what it computed (the weights changed).
  void invalidate() {
    std::lock_guard<std::mutex> lock(mutex_);
    key_valid_ = false;
    jacobian_valid_ = false;
  }

  /// Copies rows [row0, row0 + count) of the residuals (and of the Jacobians along theta and
  /// the state when the pointers are given, row-major) for (theta, state). False when the
  /// simulation is not finite.
  bool rows(const double* theta, const double* state, int row0, int count, double* residuals,
            double* jac_theta, double* jac_state);

 private:
  void computeJacobian(const double* theta, const double* state);

  /// The rows' derivatives from one simulation carrying the sensitivities; model_ holds theta's
  /// values (simulate() ran for the residuals).
  void exactJacobian(const double* theta, const double* state);

  /// Forward differences around residuals_ (which hold (theta, state)'s).
  void forwardDifferences(const double* theta, const double* state);

  /// The segment's rows for theta (smooth genes) and its start state.
  bool simulate(const double* theta, const double* state, double* out);

  /// The simulation's start: the free particles from `state`, the fixed ones where the data
  /// see them at the first frame, with the model's velocity.
  State startState(const double* state) const;

  const Problem* p_;
  int first_, last_;
  bool has_next_;
  bool theta_columns_;
  int observed_ = 0;
  int rows_ = 0;
  Model model_;
  Simulator sim_;
  std::vector<double> theta_set_;  // theta the simulator holds (empty: none yet)
  std::mutex mutex_;
  bool key_valid_ = false;
  std::vector<double> key_theta_, key_state_;  // what residuals_ (and the Jacobian) are for
  std::vector<double> residuals_;
  bool ok_ = false;
  bool jacobian_valid_ = false;
  int jacobian_takers_ = 0;
  std::vector<double> jac_theta_, jac_state_;  // rows_ x np, rows_ x ns, row-major
};

/// One residual block of a segment: its observations (parameter blocks theta and the segment's
/// state) or its continuity with the next segment's state (theta, the state and the next
/// state). The two are separate blocks so that the dense Jacobian blocks stay small: the next
/// state touches only the continuity rows; both read the segment's one simulation.
class SegmentCost final : public ceres::CostFunction {
 public:
  enum class Part { kObservations, kContinuity };

  SegmentCost(SegmentSimulation* sim, const Problem* p, Part part) : sim_(sim), p_(p), part_(part) {
    const bool continuity = part == Part::kContinuity;
    set_num_residuals(continuity ? p->stateSize() : 3 * sim->observedSamples());
    mutable_parameter_block_sizes()->push_back(static_cast<int32_t>(p->smooth.size()));
    mutable_parameter_block_sizes()->push_back(p->stateSize());
    if (continuity) mutable_parameter_block_sizes()->push_back(p->stateSize());
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int m = num_residuals(), ns = p_->stateSize();
    const int row0 = part_ == Part::kObservations ? 0 : 3 * sim_->observedSamples();
    if (!sim_->rows(parameters[0], parameters[1], row0, m, residuals,
                    jacobians ? jacobians[0] : nullptr, jacobians ? jacobians[1] : nullptr))
      return false;
    if (part_ == Part::kObservations) return true;
    const double* next = parameters[2];
    for (int k = 0; k < m; ++k) residuals[k] -= p_->w_cont * next[k];
    if (jacobians && jacobians[2]) {
      std::fill(jacobians[2], jacobians[2] + static_cast<size_t>(m) * ns, 0.0);
      for (int j = 0; j < ns; ++j) jacobians[2][j * ns + j] = -p_->w_cont;
    }
    return true;
  }

 private:
  SegmentSimulation* sim_;
  const Problem* p_;
  Part part_;
};

/// Start state of frame t from the data: the position, and the velocity x h from a central
/// difference (one-sided at the ends, 0 where a neighbour is occluded).
void dataState(const Problem& p, int t, double* state);

}  // namespace output_error_detail
}  // namespace mme

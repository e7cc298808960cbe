// Exact derivatives of a simulated motion: forward sensitivities through the motion law of SPEC
// section 3 (semi-implicit Euler), for the output error's Jacobians. Alongside the state it
// carries dx/dq and dv/dq for every column q (the chosen physical parameters, then the initial
// positions and velocities of the free particles), propagated with each bond's force Jacobian
// with respect to its particles' positions, velocities and its type's own parameters.
#pragma once

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/simulator.h"

namespace mme {

/// "" when MotionSensitivity covers the model's motion law; otherwise why not, in words (the
/// caller then differentiates by finite differences). Not covered: muscles (a muscle's force
/// reads a network over other bonds), interactions (bonds appear and vanish with distance) and
/// Provot's clamp (a projection after the step, a kink the sensitivities would have to follow).
/// Every other kind of the catalogue is covered, with every parameter its law reads.
std::string sensitivityUnsupportedReason(const Model& model);

/// Integrates one model from a given state and the derivatives of the state along the columns
/// [params (physical units), x0 of every free particle (3 each, m), v0 of every free particle
/// (3 each, m/s)]. The derivative along a threshold (min/max_distance) is 0: the force is flat
/// in it between switching events. Throws InputError for a model it does not cover.
class MotionSensitivity {
 public:
  /// Row-major 3n x columns matrix: rows 3i..3i+2 are particle i's x, y, z.
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

  /// `params`: the parameters to differentiate along (e.g. freeParameters(model) or a subset).
  MotionSensitivity(const Model& model, std::vector<ParamRef> params);
  ~MotionSensitivity();
  MotionSensitivity(MotionSensitivity&&) noexcept;
  MotionSensitivity& operator=(MotionSensitivity&&) noexcept;

  /// Replaces the parameter values (same structure as the constructor's model).
  void setParameters(const Model& model);
  /// Whether the columns of the parameters are carried (false: the initial state's only, for a
  /// fit with the parameters held; columns() then excludes them).
  void setParameterColumns(bool on);
  /// Starts at s (fixed particles keep their x and v); the derivatives are the identity along
  /// the free particles' initial state and zero along the parameters.
  void start(const State& s);
  /// Advances one frame of model.substeps substeps of frame_period_s / substeps [s].
  void stepFrame(double frame_period_s);

  const State& state() const;
  /// d x / d columns and d v / d columns at the current state.
  const Matrix& dx() const;
  const Matrix& dv() const;
  /// Column count: parameters (when carried) + 6 x free particles.
  int columns() const;
  /// Index of the first initial-state column (the parameter count, or 0 when not carried).
  int stateColumn0() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mme

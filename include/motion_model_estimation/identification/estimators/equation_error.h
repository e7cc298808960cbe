// A start for identification that needs no search: the forces of springs, dampers, flexion,
// viscosity and gravity are linear in (k, k L, c, k theta0, c_v, g; with L known, k_nl and c_nl),
// so Newton's law written on every observed frame, m a = F(x, v), is a linear least-squares
// problem in them (the equation error). Accelerations come from finite differences of the positions, raw or smoothed by a local
// quadratic fit (Savitzky-Golay) when the markers are noisy. Exact on noiseless data with one
// step per frame; a good start elsewhere, wherever the search bounds are.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

struct EquationErrorOptions {
  /// 0 (or 1): raw differences of the frame step, a = (x+ - 2x + x-)/h^2 and v = (x - x-)/h (exactly the
  /// one-step prediction of semi-implicit Euler). w >= 2: a quadratic fitted to the 2w+1 frames
  /// around each frame gives x, v and a (noise averaged out, motion slightly smoothed).
  int smoothing_half_width = 0;
  /// A spring type whose stiffness, rest length and cubic stiffness_nl are all free: its rest
  /// length enters non-linearly; with this, it is linearised about the model's values (k0, L0,
  /// k_nl0 must be set), so a solve is one Gauss-Newton step and repeated solves (values set
  /// from the last) converge. Without it such a type makes the equation error not applicable.
  bool linearize_rest_length = false;
};

struct EquationErrorResult {
  bool applicable = false;
  std::string reason;               ///< why not applicable (a free parameter it cannot solve for)
  /// Physical values in freeParameters(model) order; NaN where the data do not determine one
  /// (no observed row involves it, or it came out non-physical, e.g. a negative stiffness).
  std::vector<double> values;
  size_t rows = 0;                  ///< equations used (3 per particle and frame)
  /// RMS of the rows' residuals, (m a - F) h^2 / m [m]: with raw differences, the one-step
  /// prediction error of the solution.
  double residual_rms_m = 0.0;
};

/// The equation error's normal equations, before the solve: one column per linear unknown.
struct EquationErrorSystem {
  std::string reason;               ///< "" when built; else why the model does not fit the form
  /// Per column: the free parameter (index into freeParameters(model)) it determines, and for a
  /// product column (k L, k theta0) the stiffness column it is divided by (-1 otherwise).
  std::vector<int> column_param, column_partner;
  /// Per column: added to the coefficient to give the parameter (a linearised rest length's L0;
  /// 0 otherwise).
  std::vector<double> column_offset;
  Eigen::MatrixXd ata;              ///< A^T A of the weighted rows
  Eigen::VectorXd atb;              ///< A^T b
  double btb = 0.0;                 ///< b^T b
  size_t rows = 0;
};

/// Builds the normal equations of the equation error (the same rows as solveEquationError).
EquationErrorSystem buildEquationErrorSystem(const Model& model, const Trajectory& trajectory,
                                             const EquationErrorOptions& options = {});

/// Solves the equation error for the model's free parameters. Applicable when every free
/// parameter is a spring's stiffness, rest_length, damping, damping_nl or (its rest_length
/// known) stiffness_nl, a flexion's stiffness, rest_angle or damping, a viscosity or a gravity
/// component, and no free parameter enters non-linearly (a free rest_length with a non-zero or
/// free stiffness_nl, free conditions, free Provot clamps and free interaction parameters are
/// not). `trajectory` has the model's particles as markers.
EquationErrorResult solveEquationError(const Model& model, const Trajectory& trajectory,
                                       const EquationErrorOptions& options = {});

/// Whether a bond type's parameter is physical only when positive (the catalogue's
/// ParamInfo::physically_positive, bond_kind.h; false for a muscle's network parameters).
bool physicalOnlyPositive(ParamId id);

}  // namespace mme

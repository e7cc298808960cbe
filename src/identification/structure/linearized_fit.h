// The non-linear level's equation error. Cubic stiffness and quadratic damping are linear in
// their own coefficients, but beside them a rest length no longer separates as k L; it enters
// linearised about its current value, so the equation error becomes a Gauss-Newton iteration
// rather than one solve. This unit builds that level's candidate model and iterates it.
#pragma once

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"

namespace mme {
namespace structure {

/// The non-linear level's candidate model: `linear` (the best linear level's kept bonds, one type
/// each) with the values of its least-squares equation-error fit, and a free cubic stiffness on
/// every candidate spring (a quadratic damping too where it has a damper), at 0.
Model nonlinearCandidates(Model linear, const Trajectory& fit, const EquationErrorOptions& ee,
                          int first_candidate_type);

/// The least-squares solution of every column of `model`'s linearised equation error (rest
/// lengths beside cubic terms, equation_error.h), iterated from the model's values while the
/// linearised residual falls (Gauss-Newton; a step that raises it is undone); the values are
/// written into the model.
void convergeLinearized(Model* model, const Trajectory& fit, const EquationErrorOptions& ee);

}  // namespace structure
}  // namespace mme

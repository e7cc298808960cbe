// Bond typing for structure selection: after a level's elimination every kept bond has a type
// of its own, but a physical object has few materials. Bonds whose solved values agree within
// their uncertainty share a type, and the criterion decides whether the shared typing is kept;
// a type that comes out non-physical in the typed model's joint fit is held rather than
// throwing the typing away.
#pragma once

#include <string>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"
#include "elimination.h"
#include "selection_context.h"
#include "solved_bonds.h"

namespace mme {
namespace structure {

/// Bonds of one kind whose values (k, L, c; k, theta0, c; c_v) agree within `sigmas` standard
/// deviations share a type (greedy, in order of stiffness). Returns the typed model (candidate
/// types renamed s00, s01, ... for springs, f00, ... for flexion, v00, ... for viscosity) and
/// its number of candidate types in `types_out`.
Model typeBonds(const Solved& solved, int first_candidate_type, double sigmas, int* types_out);

/// A level's model with its typing decided, and the fit figures that go with it.
struct TypingChoice {
  Model model;
  double rss_m2 = 0.0;   ///< equation-error residual sum of squares
  int parameters = 0;    ///< free parameters
  double bic = 0.0;
};

/// One type per bond (`solved`, its fit `sel` over `rows` equations) or shared types
/// (typeBonds, fitted jointly with `level_ee`; `nonlinear`: rest lengths iterated), whichever
/// the criterion prefers (floor `floor2`); shared types only when `try_typing` (not when the
/// time limit cut the level). Says what it weighed; a preferred typing that cannot be used
/// becomes a note.
TypingChoice chooseTyping(const SelectionContext& ctx, const std::string& name, const Solved& solved,
                          const Selection& sel, size_t rows, double floor2, bool try_typing,
                          bool nonlinear, const EquationErrorOptions& level_ee);

}  // namespace structure
}  // namespace mme

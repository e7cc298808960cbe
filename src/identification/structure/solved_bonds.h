// Reading an elimination's solve back into a model. The elimination works on columns of the
// normal equations; the rest of the selection works on bonds: their physical values (a rest
// length is k L / k), their standard deviations for typing, which optional terms they kept, and
// which came out non-physical. This unit is that translation, and the pruning that goes with it.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"
#include "elimination.h"

namespace mme {
namespace structure {

/// A kept bond's values: spring (k, L, c, k_nl, c_nl); flexion (k, theta0, c, 0, 0); viscosity
/// (c_v, 0, 0, 0, 0).
using BondValues = Eigen::Matrix<double, 5, 1>;
/// Which optional terms a kept bond has (bits): damping, cubic stiffness, quadratic damping.
enum TermBits : uint8_t { kHasDamping = 1, kHasStiffnessNl = 2, kHasDampingNl = 4 };

/// The model a selection describes: the base model's own bonds, then one type per kept bond
/// with its solved values; gravity off when its unit was removed.
struct Solved {
  Model model;
  std::vector<int> kept_types;      ///< the candidate types kept (indices into the candidate model)
  std::vector<BondValues> value, sigma;  ///< per kept type: its values and their 1-sigma
  std::vector<uint8_t> terms;       ///< per kept type: its optional terms (TermBits)
  std::vector<int> bad_bonds;       ///< kept types with k <= 0, L <= 0, theta0 outside (0, pi] or c_v <= 0
  /// Optional terms that came out non-physical (a damping <= 0): (type, ParamId).
  std::vector<std::pair<int, int>> bad_terms;
};

/// The model `sel` (the elimination's result on `sys`, built from `candidate`) describes, with
/// each kept bond's values and 1-sigma (from the final solve's inverse and the noise level
/// `sigma2`); candidate types start at `first_candidate_type`. Dampers are read only when
/// `dampers` (the level has them).
Solved describe(const Model& candidate, const EquationErrorSystem& sys, const Selection& sel,
                double sigma2, int first_candidate_type, bool dampers);

/// Drops the kept bonds whose values came out non-physical and the non-physical optional terms
/// from `solved`, without solving again: the last pass, or one cut by the time limit, must not
/// hand on a negative stiffness. Returns whether anything was dropped.
bool dropNonPhysical(Solved* solved, int first_candidate_type);

/// What a level kept, before typing: per candidate bond its kind, particles and which of its
/// parameters are present (equal strings: the same structure).
std::string structureSignature(const Model& model, int first_candidate_type);

}  // namespace structure
}  // namespace mme

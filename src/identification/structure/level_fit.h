// One level of structure selection, fitted by the equation error. A level is a set of candidate
// components (springs; + dampers; + flexion; + viscosity; or the non-linear or conditional
// terms on an earlier level's bonds); fitting it means thinning those candidates by the
// elimination, in passes: pairs the residual asks for join the candidates, bonds that come out
// non-physical are dropped, and the kept bonds are typed. Judging it against the other levels
// is level_judging.h's; the order of levels is level_sequence.h's.
#pragma once

#include <array>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "residual_screening.h"
#include "selection_context.h"

namespace mme {
namespace structure {

/// A level: which candidate components it holds.
struct Level {
  std::string name;
  bool dampers, flexion, viscosity;
  int nonlinear_on = -1;  ///< >= 0: the non-linear terms on that level's kept bonds
  int conditional_on = -1;  ///< >= 0: conditions on that level's kept springs
};

/// What a level starts from besides the given model: the earlier levels' kept bonds (the base
/// of the non-linear and conditional levels), the conditional level's thresholds, the flexion
/// candidates, and the candidate pairs so far (screening adds to them).
struct LevelInputs {
  const std::vector<Model>& untyped;  ///< per earlier level: its kept bonds, one type each
  const std::vector<ConditionalChoice>& conditional_choices;
  const std::vector<std::array<int, 3>>& triples;
  std::set<std::pair<int, int>>* all_candidates;
};

/// A fitted level: its candidate (typed model and equation-error figures, not yet refitted or
/// judged), its kept bonds before typing, and the noise level and equations it was priced with.
struct LevelFit {
  StructureCandidate candidate;
  Model kept_untyped;
  double sigma2 = 0.0;
  size_t rows = 0;
  std::string signature;  ///< structureSignature of the kept bonds
  bool given_up = false;  ///< the time limit ran out during this level (never the first)
};

/// Fits `level` by the equation error on the fitted frames. The first level (`first_level`)
/// is never given up: cut by the time limit, it ends on its elimination so far. Throws
/// InputError when the equation error does not apply or is not finite.
LevelFit fitLevel(const SelectionContext& ctx, const Level& level, const LevelInputs& in, bool first_level);

}  // namespace structure
}  // namespace mme

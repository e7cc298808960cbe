// The non-linear level's equation error (linearized_fit.h): its candidate model and the
// Gauss-Newton iteration of its linearised rest lengths.
#include "linearized_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "motion_model_estimation/core/model_builder.h"
#include "motion_model_estimation/identification/estimators/normal_equations.h"
#include "candidate_structure.h"

namespace mme {
namespace structure {

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

/// One solve of every column `sys` determines (a column some row touches), in `all`; the
/// solution untrusted when the system is not finite.
NormalEquationsSolution solveDetermined(const EquationErrorSystem& sys, std::vector<int>* all) {
  const bool finite = sys.reason.empty() && sys.ata.allFinite() && sys.atb.allFinite() &&
                      std::isfinite(sys.btb);
  for (size_t j = 0; finite && j < sys.column_param.size(); ++j)
    if (sys.ata(j, j) > 0.0) all->push_back(static_cast<int>(j));
  NormalEquationsSolution solved;
  if (finite) solved = solveNormalEquations(sys.ata, sys.atb, sys.btb, *all);
  return solved;
}

/// Writes the solution `theta` of the columns `all` into `model`; a linearised rest length
/// moves by at most 20 % of its value per step: a bond with next to no stiffness (a candidate
/// the data do not want) has next to no say on its length.
void applyStep(Model* model, const std::vector<ParamRef>& refs, const EquationErrorSystem& sys,
               const std::vector<int>& all, const Eigen::VectorXd& theta) {
  for (int j : all) {
    const int partner = sys.column_partner[j];
    double value = partner >= 0 ? theta[j] / theta[partner] : theta[j] + sys.column_offset[j];
    if (!std::isfinite(value)) continue;
    const ParamRef& r_ref = refs[sys.column_param[j]];
    if (r_ref.bond_type >= 0 && r_ref.param == kRestLength && sys.column_offset[j] != 0.0) {
      const double before = sys.column_offset[j];
      value = std::min(std::max(value, 0.8 * before), 1.2 * before);
    }
    setParam(*model, r_ref, value);
  }
}

}  // namespace

Model nonlinearCandidates(Model linear, const Trajectory& fit, const EquationErrorOptions& ee,
                          int first_candidate_type) {
  const EquationErrorResult start = solveEquationError(linear, fit, ee);
  const std::vector<ParamRef> refs = freeParameters(linear);
  if (start.applicable)
    for (size_t k = 0; k < refs.size(); ++k)
      if (std::isfinite(start.values[k])) setParam(linear, refs[k], start.values[k]);
  for (size_t t = first_candidate_type; t < linear.bond_types.size(); ++t) {
    BondType& type = linear.bond_types[t];
    if (type.kind != BondKind::kSpring || !type.param(kStiffness).free) continue;
    type.param(kStiffnessNl) = valueParam(0.0, true);
    if (type.param(kDamping).free) type.param(kDampingNl) = valueParam(0.0, true);
  }
  return linear;
}

void convergeLinearized(Model* model, const Trajectory& fit, const EquationErrorOptions& ee) {
  const std::vector<ParamRef> refs = freeParameters(*model);
  double best_rss = std::numeric_limits<double>::infinity();
  Model before_step = *model;
  for (int iteration = 0; iteration < 30; ++iteration) {
    const EquationErrorSystem sys = buildEquationErrorSystem(*model, fit, ee);
    std::vector<int> all;
    const NormalEquationsSolution solved = solveDetermined(sys, &all);
    const double r = solved.trusted ? solved.rss : kNan;
    if (!solved.trusted || !(r < best_rss * (1.0 - 1e-6))) {
      // No progress from this point: back to the one it was reached from (iteration 0: the start).
      if (iteration > 0) *model = before_step;
      return;
    }
    best_rss = r;
    before_step = *model;
    applyStep(model, refs, sys, all, solved.theta);
    if (r <= 1e-30 * std::max(sys.btb, 1e-300)) return;  // exact
  }
}

}  // namespace structure
}  // namespace mme

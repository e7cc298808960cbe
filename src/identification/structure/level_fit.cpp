// One level of structure selection fitted by the equation error (level_fit.h): its candidate
// model, its passes of elimination with screening and non-physical drops, and its typing.
#include "level_fit.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"
#include "bond_typing.h"
#include "candidate_structure.h"
#include "elimination.h"
#include "linearized_fit.h"
#include "solved_bonds.h"

namespace mme {
namespace structure {

namespace {

constexpr double kRoundOffFloorM = 1e-10;  ///< an equation-error residual below this is exact

/// The noise level of a level's full candidate model's residual, floored at round-off.
struct NoiseLevel {
  double rhs_rms_m = 0.0;     ///< RMS of the right-hand side
  double floor2_m2 = 0.0;     ///< round-off floor of the residual's mean square
  double sigma2_m2 = 0.0;     ///< the criterion's sigma^2
};

/// Round-off of the equation error (conditioning included) on exact data: 1e-6 of the rows'
/// RMS, 1e-10 m at least: no capture resolves a tenth of a nanometre, and a small motion's rhs
/// (micrometres) would otherwise put the floor below the solves' own round-off.
NoiseLevel noiseLevel(const EquationErrorSystem& sys, const Eigen::VectorXd& theta_all, size_t unknowns) {
  NoiseLevel noise;
  noise.rhs_rms_m = std::sqrt(sys.btb / std::max<size_t>(sys.rows, 1));
  noise.floor2_m2 = std::pow(std::max(1e-6 * noise.rhs_rms_m, kRoundOffFloorM), 2);
  const double dof = std::max(1.0, static_cast<double>(sys.rows) - static_cast<double>(unknowns));
  noise.sigma2_m2 = std::max(rss(sys, theta_all) / dof, noise.floor2_m2);
  return noise;
}

/// The level's candidate model before any pass: the non-linear level starts from its base
/// level's kept bonds (values set); the conditional level from its base level's kept bonds with
/// the chosen springs' thresholds held at the scan's values (the masks are then known: linear
/// unknowns again); a cumulative level from the given model with every candidate of its
/// components (pairs the screening of an earlier level found included).
Model levelStartModel(const SelectionContext& ctx, const Level& level, const LevelInputs& in) {
  if (level.nonlinear_on >= 0) return in.untyped[level.nonlinear_on];
  if (level.conditional_on >= 0) {
    Model full = in.untyped[level.conditional_on];
    for (const ConditionalChoice& choice : in.conditional_choices) {
      Param threshold;
      threshold.value = choice.threshold_m;
      threshold.present = threshold.has_value = true;
      full.bond_types[choice.type].param(choice.lower ? kMinDistance : kMaxDistance) = threshold;
    }
    return full;
  }
  Model full = ctx.model;
  addCandidateBonds(&full, std::vector<std::pair<int, int>>(in.all_candidates->begin(), in.all_candidates->end()),
                    ctx.fit, level.dampers);
  if (level.flexion) addCandidateFlexions(&full, in.triples, ctx.fit, level.dampers);
  if (level.viscosity) addCandidateViscosities(&full);
  return full;
}

/// The level's equation error; throws InputError (naming the level) when it does not apply or
/// is not finite.
EquationErrorSystem levelSystem(const Model& full, const Trajectory& fit, const EquationErrorOptions& ee,
                                const std::string& name) {
  EquationErrorSystem sys = buildEquationErrorSystem(full, fit, ee);
  if (!sys.reason.empty())
    throw InputError("structure selection: the equation error does not apply: " + sys.reason);
  if (!sys.ata.allFinite() || !sys.atb.allFinite() || !std::isfinite(sys.btb))
    throw InputError("structure selection: " + name + ": the equation error is not finite "
                     "(positions or values too large?)");
  return sys;
}

/// Fits one level in passes (LevelFit); each pass builds the equation error of the candidate
/// model as it stands, eliminates, and either changes the candidates (screened pairs added,
/// non-physical bonds dropped) for another pass or types what it kept.
class LevelFitter {
 public:
  LevelFitter(const SelectionContext& ctx, const Level& level, const LevelInputs& in, bool first_level)
      : ctx_(ctx), level_(level), in_(in), first_level_(first_level),
        nonlinear_(level.nonlinear_on >= 0), conditional_(level.conditional_on >= 0) {}

  LevelFit run() {
    out_.candidate.name = level_.name;
    full_ = levelStartModel(ctx_, level_, in_);
    // The non-linear level: rest lengths beside cubic terms enter linearised about the values.
    level_ee_ = ctx_.ee;
    level_ee_.linearize_rest_length = nonlinear_;
    if (nonlinear_) full_ = nonlinearCandidates(full_, ctx_.fit, ctx_.ee, ctx_.first_candidate_type);
    for (int pass = 0; pass < kMaxPasses; ++pass)
      if (runPass(pass) != PassEnd::kAgain) break;
    return out_;
  }

 private:
  enum class PassEnd { kGivenUp, kAgain, kDone };

  /// The time limit ran out during this level (never the first level).
  bool giveUp() { return out_.given_up = !first_level_ && ctx_.deadline.passed(); }

  PassEnd runPass(int pass) {
    if (giveUp()) return PassEnd::kGivenUp;
    if (nonlinear_) convergeLinearized(&full_, ctx_.fit, level_ee_);
    const EquationErrorSystem sys = levelSystem(full_, ctx_.fit, level_ee_, level_.name);
    std::vector<int> always;
    const std::vector<Group> groups = groupColumns(sys, freeParameters(full_), ctx_.first_candidate_type, &always);
    const std::vector<int> all = activeColumns(groups, always);
    // With its inverse: the elimination starts from this solve.
    NormalEquationsSolution solved_all = solveActive(sys, all, true, level_.name);
    if (giveUp()) return PassEnd::kGivenUp;
    const NoiseLevel noise = noiseLevel(sys, solved_all.theta, all.size());
    sayEliminating(sys, all.size(), solved_all.theta, noise);
    Selection sel = eliminate(sys, groups, always, noise.sigma2_m2, level_.name, ctx_.deadline,
                              first_level_, ctx_.options.progress, &solved_all);
    if (giveUp()) return PassEnd::kGivenUp;
    Solved solved = describe(full_, sys, sel, noise.sigma2_m2, ctx_.first_candidate_type, level_.dampers);
    const bool out_of_time = ctx_.deadline.passed();  // the first level ends on what it has
    const bool may_repeat = pass + 1 < kMaxPasses && !out_of_time;
    // Bonds the neighbourhoods missed (long ones): pairs the residual asks for become
    // candidates too, and the selection runs again (at most 4 rounds of 20). Before the
    // non-physical drops: a missing bond makes true ones come out wrong.
    if (!nonlinear_ && !conditional_ && screening_rounds_ < 4 && may_repeat) {
      ++screening_rounds_;
      if (addScreenedPairs(solved.model, noise.floor2_m2)) return PassEnd::kAgain;
    }
    const bool non_physical = !solved.bad_bonds.empty() || !solved.bad_terms.empty();
    if (non_physical && may_repeat) {
      dropForNextPass(solved);
      return PassEnd::kAgain;
    }
    if (non_physical) dropWithoutSolving(out_of_time, &solved, &sel);
    finish(solved, sel, sys.rows, noise, out_of_time);
    return PassEnd::kDone;
  }

  void sayEliminating(const EquationErrorSystem& sys, size_t unknowns, const Eigen::VectorXd& theta_all,
                      const NoiseLevel& noise) const {
    char line[200];
    std::snprintf(line, sizeof(line), "structure: %s: %zu unknowns over %zu equations (residual "
                  "RMS %.3g m, rhs RMS %.3g m); eliminating", level_.name.c_str(), unknowns,
                  sys.rows, std::sqrt(rss(sys, theta_all) / std::max<size_t>(sys.rows, 1)), noise.rhs_rms_m);
    ctx_.say(line);
  }

  /// Adds the pairs outside the candidates that the residual of `solved_model` asks for (at
  /// most 20); returns whether there were any.
  bool addScreenedPairs(const Model& solved_model, double floor2_m2) {
    std::set<std::pair<int, int>> have;
    for (const Bond& b : full_.bonds)
      if (kindArity(full_.bond_types[b.type].kind) == 2) have.insert(std::minmax(b.particles[0], b.particles[1]));
    const std::vector<std::pair<int, int>> more =
        missingPairs(solved_model, ctx_.fit, have, 10.0 * std::sqrt(floor2_m2), 20);
    if (more.empty()) return false;
    addCandidateBonds(&full_, more, ctx_.fit, level_.dampers);
    in_.all_candidates->insert(more.begin(), more.end());
    ctx_.result->candidate_bonds = static_cast<int>(in_.all_candidates->size());
    ctx_.say("structure: " + level_.name + ": " + std::to_string(more.size()) +
             " pair(s) outside the neighbourhoods explain the residual: candidates too");
    return true;
  }

  /// Kept bonds that came out non-physical lose their spring (the bond goes) or their damper;
  /// then the system is solved again. A type without a bond keeps no free value.
  void dropForNextPass(const Solved& solved) {
    const std::set<int> bad(solved.bad_bonds.begin(), solved.bad_bonds.end());
    std::vector<Bond> bonds;
    for (const Bond& b : full_.bonds)
      if (!bad.count(b.type)) bonds.push_back(b);
    full_.bonds = bonds;
    for (int t : solved.bad_bonds) {
      BondType& type = full_.bond_types[t];
      for (ParamId id : paramsOfKind(type.kind)) type.param(id) = Param();
    }
    for (const auto& bad_term : solved.bad_terms)
      full_.bond_types[bad_term.first].param(static_cast<ParamId>(bad_term.second)) = Param();
    ctx_.say("structure: " + level_.name + ": " + std::to_string(solved.bad_bonds.size()) +
             " non-physical bond(s) and " + std::to_string(solved.bad_terms.size()) +
             " damping term(s) dropped; solving again");
  }

  /// The last pass, or one cut by the time limit: the non-physical bonds and terms go without
  /// solving again (the criterion's figures stay as solved), and a note says so.
  void dropWithoutSolving(bool out_of_time, Solved* solved, Selection* sel) {
    const std::string why = out_of_time ? "the time limit cut this level" :
                                          "they remained after " + std::to_string(kMaxPasses) + " passes";
    const std::string line = level_.name + ": " + std::to_string(solved->bad_bonds.size()) +
                             " non-physical bond(s) and " + std::to_string(solved->bad_terms.size()) +
                             " damping term(s) dropped without solving again (" + why + ")";
    ctx_.say("structure: " + line);
    ctx_.result->notes.push_back(line);
    dropNonPhysical(solved, ctx_.first_candidate_type);
    sel->parameters = static_cast<int>(freeParameters(solved->model).size());  // rss: as solved
  }

  /// Types the kept bonds (one type per bond, or shared where the values agree; the criterion
  /// decides) and records the level's figures.
  void finish(const Solved& solved, const Selection& sel, size_t rows, const NoiseLevel& noise,
              bool out_of_time) {
    const TypingChoice typing = chooseTyping(ctx_, level_.name, solved, sel, rows, noise.floor2_m2,
                                             !out_of_time, nonlinear_, level_ee_);
    StructureCandidate& cand = out_.candidate;
    cand.model = typing.model;
    cand.bonds = static_cast<int>(typing.model.bonds.size());
    cand.bond_types = static_cast<int>(typing.model.bond_types.size());
    cand.parameters = typing.parameters;
    cand.fit_rms_m = std::sqrt(typing.rss_m2 / std::max<size_t>(rows, 1));
    cand.bic = typing.bic;
    out_.signature = structureSignature(solved.model, ctx_.first_candidate_type);
    out_.kept_untyped = solved.model;
    out_.sigma2 = noise.sigma2_m2;
    out_.rows = rows;
  }

  const SelectionContext& ctx_;
  const Level& level_;
  const LevelInputs& in_;
  const bool first_level_, nonlinear_, conditional_;
  Model full_;                 ///< the candidate model as the passes change it
  EquationErrorOptions level_ee_;
  int screening_rounds_ = 0;
  LevelFit out_;
};

}  // namespace

LevelFit fitLevel(const SelectionContext& ctx, const Level& level, const LevelInputs& in, bool first_level) {
  return LevelFitter(ctx, level, in, first_level).run();
}

}  // namespace structure
}  // namespace mme

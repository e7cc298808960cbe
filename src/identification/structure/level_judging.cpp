// Judging levels by held-out prediction (level_judging.h): the refit of a level's model, its
// open-loop prediction error on the held-out frames, the model-free guesses, and the choice
// among the levels.
#include "level_judging.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"
#include "motion_model_estimation/identification/identifier.h"

namespace mme {
namespace structure {

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr int kHorizons[3] = {1, 5, 10};

/// The open-loop prediction error of `model` on the held-out frames of `held` (from
/// `held_start`, 1, 5 and 10 frames ahead) into `c`; NaN when no start can be judged.
void heldOutErrors(const Model& model, const Trajectory& held, int held_start,
                   StructureCandidate* c) {
  try {
    const PredictionReport r = evaluatePredictions(model, held, {1, 5, 10}, 10.0, held_start);
    for (const PredictionError& row : r.rows)
      if (row.predictor == Predictor::kModel)
        for (int k = 0; k < 3; ++k)
          if (row.horizon == kHorizons[k]) c->held_out_rms_m[k] = row.rms_m;
    c->rollout_bounded = r.rollout_bounded;
  } catch (const InputError&) {
    for (double& e : c->held_out_rms_m) e = kNan;
  }
}

/// Frees what the refit searches beyond the equation error's unknowns: the non-linear level's
/// rest lengths, and the conditional level's thresholds (refined by the threshold search).
void freeForRefit(Model* model, int first_type, bool nonlinear, bool conditional) {
  for (size_t t = first_type; t < model->bond_types.size(); ++t) {
    BondType& type = model->bond_types[t];
    if (type.kind != BondKind::kSpring || !type.param(kStiffness).free) continue;
    if (nonlinear) type.param(kRestLength).free = true;
    for (ParamId id : {kMinDistance, kMaxDistance})
      if (conditional && type.param(id).present) type.param(id).free = true;
  }
}

/// The refit's settings: the short-term cost (ranking only: the final fit is the caller's),
/// the level's generation budget, and what is left of the selection's time limit.
IdentifyOptions refitOptions(const SelectionContext& ctx) {
  IdentifyOptions io = ctx.options.identify;
  io.cost = CostChoice::kShortTerm;
  io.generations = std::min(io.generations, ctx.options.refit_generations);
  io.estimate_std = false;
  if (ctx.deadline.limited())
    io.max_wall_time_s = io.max_wall_time_s > 0.0 ? std::min(io.max_wall_time_s, ctx.deadline.remainingS())
                                                  : std::max(ctx.deadline.remainingS(), 1e-3);
  return io;
}

/// Refits `cand->model` by the full identification on the fitted frames (when there is
/// something to refit and time to do it).
void refit(const SelectionContext& ctx, StructureCandidate* cand) {
  if (!ctx.options.refit) return;
  if (freeParameters(cand->model).empty()) {
    ctx.say("structure: " + cand->name + ": no bond and no gravity kept: nothing to refit");
    return;
  }
  if (ctx.deadline.passed()) {
    ctx.say("structure: " + cand->name + ": not refitted (the time limit is spent); judged with the "
            "equation error's values");
    return;
  }
  const IdentifyResult r = identifyModel(cand->model, ctx.fit, refitOptions(ctx));
  cand->model = r.model;
  cand->refit_cost_m2 = r.global_cost;
  char line[160];
  std::snprintf(line, sizeof(line), "structure: %s: refit %d generations (%s), %.1f s",
                cand->name.c_str(), r.generations, identifyStopName(r.stop), r.wall_time_s);
  ctx.say(line);
}

}  // namespace

void judgeModelFreeGuesses(const Model& model, const HeldOutSplit& split, StructureResult* result) {
  for (auto& row : result->guess_rms_m)
    for (double& e : row) e = kNan;
  try {
    const PredictionReport r = evaluatePredictions(model, split.held, {1, 5, 10}, 0.0, split.held_start);
    for (const PredictionError& row : r.rows)
      for (int k = 0; k < 3; ++k)
        if (row.horizon == kHorizons[k] && row.predictor != Predictor::kModel)
          result->guess_rms_m[static_cast<int>(row.predictor) - 1][k] = row.rms_m;
  } catch (const InputError& e) {
    result->notes.push_back(std::string("no held-out prediction: ") + e.what());
  }
}

void refitAndJudge(const SelectionContext& ctx, StructureCandidate* cand, bool nonlinear, bool conditional) {
  freeForRefit(&cand->model, ctx.first_candidate_type, nonlinear, conditional);
  refit(ctx, cand);
  cand->parameters = static_cast<int>(freeParameters(cand->model).size());
  heldOutErrors(cand->model, ctx.split.held, ctx.split.held_start, cand);
  char line[256];
  std::snprintf(line, sizeof(line),
                "structure: %s: %d bonds, %d types, %d parameters; held-out RMS 1/5/10 frames "
                "ahead %.3g / %.3g / %.3g mm",
                cand->name.c_str(), cand->bonds, cand->bond_types, cand->parameters,
                1e3 * cand->held_out_rms_m[0], 1e3 * cand->held_out_rms_m[1],
                1e3 * cand->held_out_rms_m[2]);
  ctx.say(line);
}

int bestCandidate(const std::vector<StructureCandidate>& candidates) {
  double best_err = std::numeric_limits<double>::infinity();
  for (const StructureCandidate& c : candidates)
    if (std::isfinite(c.held_out_rms_m[2])) best_err = std::min(best_err, c.held_out_rms_m[2]);
  int chosen = -1;
  for (size_t i = 0; i < candidates.size(); ++i) {
    const StructureCandidate& c = candidates[i];
    const bool near = !std::isfinite(best_err) || (std::isfinite(c.held_out_rms_m[2]) &&
                                                   c.held_out_rms_m[2] <= 1.02 * best_err);
    if (!near) continue;
    if (chosen < 0 || c.parameters < candidates[chosen].parameters ||
        (c.parameters == candidates[chosen].parameters && c.bic < candidates[chosen].bic))
      chosen = static_cast<int>(i);
  }
  return chosen;
}

}  // namespace structure
}  // namespace mme

// Step 3 of a layout's fit (sensor_muscle_fit.h): the chosen candidate on every frame. Its
// equations are completed with the validation frames' and its rounds of rollout equations run
// again on every frame. The refit is then checked by its own rollouts, from the validation start
// and from frames spread over the data, each bounded by the validation frames' box as a
// held-out test is by its own frames' (the whole data's box can be larger: a body that walks in
// lets a rollout drift farther): when one leaves the data (a refit can, where the validation fit
// did not), the next candidate of the same window (bounded in validation, by validation error)
// is refitted instead; when none stays bounded, the first is kept and reported not better than
// the passive model.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "sensor_muscle_fit.h"

namespace mme::sensor_muscles {

namespace {

constexpr int kMaxFinalFits = 4;        ///< candidates refitted on every frame at most
constexpr int kFinalRolloutStarts = 8;  ///< starts over the data of the refit's check

/// The refit's check rollouts are 10x the frames a held-out test of the same share judges when
/// these data are its fitted part (validation / (1 - share): 10x the validation frames alone
/// lets a model that leaves slowly pass the shorter check and fail the test), plus the 2 frames
/// of a start's history.
int finalRolloutFrames(const FitRun& run) {
  return static_cast<int>(
      std::ceil(10.0 * ((run.frames - run.validation_start) / (1.0 - run.o.validation_fraction) + 2.0)));
}

/// The candidates to refit, in order: the best, then the other bounded ones of its window by
/// validation error, kMaxFinalFits at most.
std::vector<int> refitOrder(const FitRun& run) {
  const std::vector<SensorMuscleCandidate>& candidates = run.result.candidates;
  const int window = candidates[run.best].window_frames;
  std::vector<int> order = {run.best};
  for (int k = 0; k < static_cast<int>(candidates.size()); ++k) {
    const SensorMuscleCandidate& c = candidates[k];
    if (k != run.best && c.window_frames == window && c.bounded && std::isfinite(c.validation_rms_m))
      order.push_back(k);
  }
  std::stable_sort(order.begin() + 1, order.end(), [&](int a, int b) {
    return candidates[a].validation_rms_m < candidates[b].validation_rms_m;
  });
  if (static_cast<int>(order.size()) > kMaxFinalFits) order.resize(kMaxFinalFits);
  return order;
}

/// One candidate refitted on every frame (`sys`): its ridge, its rounds run again on every frame.
/// False when a solve fails.
bool refit(FitRun& run, const System& sys, const SensorMuscleCandidate& c, Eigen::VectorXd* theta) {
  if (!run.solve(sys, c.ridge, theta)) return false;
  if (c.rollout_rounds == 0) return true;
  say(run.o, "sensor muscles: ridge " + formatRidge(c.ridge) + ", " + std::to_string(c.rollout_rounds) +
      " rollout round(s) on every frame");
  return runRounds(run, sys, c.ridge, *theta, run.frames, run.frames, c.rollout_rounds, false,
                   [&](int, const Eigen::VectorXd& r, const RolloutCount&) { *theta = r; });
}

/// The refit's model stays bounded on the validation frames and over the check's rollouts.
bool refitStaysBounded(const FitRun& run, const Eigen::VectorXd& theta, const Activation& activation,
                       int rollout_frames) {
  double rms = 0.0;
  bool bounded = false;
  try {
    const Model model = run.build(theta, run.frames, activation.time_s);
    run.judge.judge(model, &rms, nullptr, &bounded);
    bounded = bounded && run.rollouts.boundedFromEverywhere(model, kFinalRolloutStarts, rollout_frames,
                                                            run.validation_start);
  } catch (const InputError&) {
  }
  return bounded;
}

/// The fit that is written: the first refit that stays bounded, else the first that solved.
struct FinalFit {
  Eigen::VectorXd theta;
  Activation activation;
  int accepted = -1;     ///< its candidate (the best one when no refit stayed bounded)
  bool bounded = false;  ///< a refit stayed bounded
  size_t tried = 0;      ///< candidates in the refit order
};

FinalFit chooseFinalFit(FitRun& run, const System& sys) {
  const int rollout_frames = finalRolloutFrames(run);
  const std::vector<int> order = refitOrder(run);
  FinalFit first, chosen;
  chosen.accepted = run.best;
  for (int index : order) {
    const SensorMuscleCandidate& c = run.result.candidates[index];
    Eigen::VectorXd theta;
    if (!refit(run, sys, c, &theta)) continue;
    const Activation activation = chooseActivation(run, index);
    if (first.theta.size() == 0) first = {theta, activation};
    if (refitStaysBounded(run, theta, activation, rollout_frames)) {
      chosen = {theta, activation, index, true};
      break;
    }
    say(run.o, "sensor muscles: ridge " + formatRidge(c.ridge) + ", " + std::to_string(c.rollout_rounds) +
        " rollout round(s), refitted on every frame: a rollout of it " + std::to_string(rollout_frames) +
        " frames long (from the validation start or from one of 8 frames over the data) leaves the "
        "validation frames' box; the next candidate");
  }
  if (first.theta.size() == 0) throw InputError("sensor muscles: the final solve failed");
  if (!chosen.bounded) {
    chosen.theta = first.theta;
    chosen.activation = first.activation;
  }
  chosen.tried = order.size();
  return chosen;
}

}  // namespace

void refitOnEveryFrame(FitRun& run) {
  const SensorMuscleCandidate& best = run.result.candidates[run.best];
  System& sys = run.best_sys;
  run.equations.accumulate(best.window_frames, run.validation_start - best.window_frames, run.frames, &sys,
                           run.pool.get());
  const FinalFit fit = chooseFinalFit(run, sys);
  SensorMuscleResult& result = run.result;
  const SensorMuscleCandidate chosen = result.candidates[fit.accepted];
  result.chosen = fit.accepted;
  result.window_frames = chosen.window_frames;
  result.ridge = chosen.ridge;
  result.activation_time_s = fit.activation.time_s;
  result.validation_rms_m = fit.activation.validation_rms_m;
  decideKept(chosen.bounded, fit.bounded, fit.tried, &result);
  result.rows = sys.rows;
  // A row sums window^2 frames' a h^2 (the triangle's weights): per frame, divided by that.
  const double per_frame = 1.0 / (run.passive.frame_rate_hz * run.passive.frame_rate_hz *
                                  chosen.window_frames * chosen.window_frames);
  result.residual_rms_m = residualRms(sys, fit.theta) * per_frame;
  result.model = run.build(fit.theta, run.frames, fit.activation.time_s);
}

}  // namespace mme::sensor_muscles

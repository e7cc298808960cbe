#include "output_error_step.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "motion_model_estimation/core/stiffness.h"
#include "motion_model_estimation/identification/estimators/answer_judge.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"

namespace mme {

namespace {

/// An output-error residual this many times the data's noise estimate is a misfit worth a word.
constexpr double kMisfitFactor = 2.0;
/// ... this many times: the model cannot explain the motion (bonds or kinds missing, a body
/// driven by muscles), whatever the noise: the starts meant against the noise's bias are not
/// tried, and the later stages run only when the first one gains on the judge.
constexpr double kHopelessFactor = 10.0;
/// The share by which the first stage of a model that cannot explain the motion must predict
/// better than the one-step answer for the later stages (minutes on 40 markers) to be worth
/// their time.
constexpr double kWorthwhileGain = 0.05;
/// A fit whose cost ends this many times above its start's has diverged (a least-squares solver
/// that works never ends above its start; this far above means it blew up on the way).
constexpr double kDivergedFactor = 10.0;
/// Output-error iterations a start gets before the best start is fitted to convergence.
constexpr int kScoutIterations = 15;
/// Most substeps per frame the stiff-scene rule asks for.
constexpr int kMaxSubsteps = 64;

std::string formatValue(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", v);
  return text;
}

}  // namespace

OutputErrorStep::OutputErrorStep(const Model& model, const Trajectory& trajectory,
                                 const ParameterSpace& space, const IdentifyOptions& options,
                                 const std::vector<Eigen::Vector3d>& reference_m,
                                 std::function<double()> elapsed,
                                 std::function<void(const std::string&)> note)
    : trajectory_(trajectory), space_(space), options_(options), reference_m_(reference_m),
      elapsed_(std::move(elapsed)), note_(std::move(note)), model_(model) {}

OutputErrorOutcome OutputErrorStep::run(const std::vector<double>& one_step_genes, double noise_estimate_m) {
  noise_estimate_m_ = noise_estimate_m;
  out_ = OutputErrorOutcome();
  out_.substeps = model_.substeps;
  out_.one_step_judged_rms_m = judge(model_, one_step_genes);
  out_.judged_rms_m = out_.one_step_judged_rms_m;
  const int coarse_substeps = model_.substeps;
  std::string failed;
  OutputErrorResult best = scoutStarts(one_step_genes, &failed);
  if (!best.ran) {
    if (options_.max_wall_time_s > 0.0 && elapsed_() >= options_.max_wall_time_s) out_.time_cut = true;
    if (!failed.empty())
      note_("warning: the output-error fit " + failed + ": not adopted, the one-step answer is kept");
    return out_;
  }
  double best_rms_m = judge(model_, best.genes);
  const auto hopeless = [&] {
    return misfit(best) && !(best_rms_m < (1.0 - kWorthwhileGain) * out_.one_step_judged_rms_m);
  };
  // Too few substeps for the model's stiffness also leave residuals far above the noise (a
  // stiff scene's noiseless data look like a model that cannot explain them): the trial comes
  // before the judgement.
  trySubsteps(&best, &best_rms_m);
  const std::string horizon = std::to_string(kJudgeHorizonFrames) + " frames ahead";
  const bool stopped_early = hopeless();
  if (stopped_early) {
    note_("the output error's first stage leaves residuals of " + formatValue(best.noise_std_m) + " m RMS, " +
          formatValue(best.noise_std_m / std::max(noise_estimate_m_, 1e-9)) +
          "x the markers' noise (the model does not explain the motion), and predicts " + horizon + " " +
          formatJudged(best_rms_m) + " against " + formatJudged(out_.one_step_judged_rms_m) +
          " for the one-step answer: the final fit is not run");
    if (options_.estimate_std)
      out_.std_missing_reason = "the output error stopped after its first stage, whose uncertainty is not computed";
  } else {
    finalFit(&best, &best_rms_m);
  }
  noteFit(best, stopped_early);
  std::string figures = "judged " + horizon + " on the fitted frames, the output error's answer predicts " +
                        formatJudged(best_rms_m) + " and the one-step answer " +
                        formatJudged(out_.one_step_judged_rms_m);
  if (model_.substeps != coarse_substeps)
    figures += " (another integrator: compared by the output-error cost, " + formatValue(best.observation_cost_m2) +
               " against " + formatValue(one_step_oe_cost_m2_) + " m^2)";
  // Another integrator than the one-step answer's: compared by the output-error cost as the trial
  // did (the first scout's start is the one-step answer's), a blow-up never adopted.
  const bool adopt = model_.substeps == coarse_substeps
                         ? outputErrorReplacesOneStep(best_rms_m, out_.one_step_judged_rms_m,
                                                      best.noise_std_m, noise_estimate_m_)
                         : !std::isinf(best_rms_m) && best.observation_cost_m2 <= one_step_oe_cost_m2_;
  if (!adopt) {
    note_("warning: " + figures + ": the output error's answer is worse and not adopted, the one-step answer is kept");
    model_.substeps = coarse_substeps;
    out_.std_missing_reason.clear();
    return out_;
  }
  if (!replacesStanding(best_rms_m, out_.one_step_judged_rms_m) && model_.substeps == coarse_substeps)
    figures += ", but its residuals (" + formatValue(best.noise_std_m) + " m) are at the markers' noise (" +
               formatValue(noise_estimate_m_) + " m), where predictions from noisy starts cannot tell the two apart";
  note_(figures + ": the output error's answer is adopted");
  out_.adopted = true;
  out_.fit = best;
  out_.substeps = model_.substeps;
  out_.judged_rms_m = best_rms_m;
  return out_;
}

/// The search's answer and the smoothed equation-error solutions (the one-step optimum is biased
/// by noise, badly so at a millimetre).
std::vector<std::vector<double>> OutputErrorStep::starts(const std::vector<double>& one_step_genes) const {
  std::vector<std::vector<double>> out{one_step_genes};
  for (int half_width : {3, 8}) {
    EquationErrorOptions o;
    o.smoothing_half_width = half_width;
    const EquationErrorResult ee = solveEquationError(model_, trajectory_, o);
    if (!ee.applicable) break;
    std::vector<double> g = one_step_genes;
    for (size_t k = 0; k < space_.size(); ++k) {
      const Gene& gene = space_.gene(k);
      const double v = ee.values[k];
      if (!gene.smooth || gene.clamp_length || !std::isfinite(v) || (gene.log_scale && !(v > 0.0)))
        continue;
      g[k] = space_.reflect(k, gene.log_scale ? std::log(v) : v);
    }
    out.push_back(g);
  }
  return out;
}

/// An output-error fit of `m` from `from`, within what is left of the time limit.
OutputErrorResult OutputErrorStep::fit(const Model& m, const std::vector<double>& from, int max_iterations,
                                       bool estimate_std) const {
  OutputErrorOptions o = options_.output_error;
  o.max_iterations = std::min(o.max_iterations, max_iterations);
  o.threads = std::max(o.threads, options_.es.threads);
  if (options_.max_wall_time_s > 0.0) {
    const double left = options_.max_wall_time_s - elapsed_();
    if (left <= 0.0) {
      OutputErrorResult none;
      none.reason = "no time left";
      none.stopped_by_time = true;
      return none;
    }
    o.max_time_s = o.max_time_s > 0.0 ? std::min(o.max_time_s, left) : left;
  }
  o.estimate_std = estimate_std;
  if (options_.cancel) o.cancel = options_.cancel;
  return estimateOutputError(m, trajectory_, space_, from, o);
}

/// Why a fit is no answer ("" when it is one): it did not run, ended non-finite (Ceres could not
/// evaluate the residuals, e.g. a rollout that blew up), or diverged (far above its start).
std::string OutputErrorStep::unusableBecause(const OutputErrorResult& oe) const {
  if (!oe.ran) return "did not run (" + oe.reason + ")";
  if (!std::isfinite(oe.observation_cost_m2)) return "failed (" + oe.termination + ")";
  if (oe.start_cost_m2 > 0.0 && oe.observation_cost_m2 > kDivergedFactor * oe.start_cost_m2)
    return "diverged (cost " + formatValue(oe.observation_cost_m2) + " m^2 from " +
           formatValue(oe.start_cost_m2) + " m^2 at its start)";
  return "";
}

/// Each start scouted with a few iterations; the lowest output-error cost wins. *failed: why a
/// fit that ran was no answer.
OutputErrorResult OutputErrorStep::scoutStarts(const std::vector<double>& one_step_genes, std::string* failed) {
  OutputErrorResult best;
  const std::vector<std::vector<double>> from = starts(one_step_genes);
  for (size_t s = 0; s < from.size(); ++s) {
    OutputErrorResult oe = fit(model_, from[s], kScoutIterations, false);
    if (s == 0 && oe.ran) one_step_oe_cost_m2_ = oe.start_cost_m2;
    const std::string why = unusableBecause(oe);
    if (oe.ran && !why.empty()) *failed = why;
    if (!why.empty()) oe.ran = false;
    if (oe.ran && (!best.ran || oe.observation_cost_m2 < best.observation_cost_m2)) best = oe;
    // A fit as good as the noise allows needs no other start; one far above the noise is not
    // the noise's bias, which the other starts are for.
    if (best.ran && best.noise_std_m <= 1.2 * best.noise_std_prior_m) break;
    if (best.ran && misfit(best)) {
      if (s + 1 < from.size())
        note_("the output error from the one-step answer leaves residuals " +
              formatValue(best.noise_std_m / std::max(noise_estimate_m_, 1e-9)) +
              "x the markers' noise: the starts against the noise's bias are not tried");
      break;
    }
  }
  return best;
}

/// The model cannot explain the motion: its residuals are kHopelessFactor times the noise.
bool OutputErrorStep::misfit(const OutputErrorResult& oe) const {
  return oe.noise_std_m > kHopelessFactor * std::max(noise_estimate_m_, 1e-9);
}

double OutputErrorStep::judge(const Model& m, const std::vector<double>& genes) const {
  Model judged = m;
  setValues(judged, space_.refs(), space_.toPhysical(genes));
  return judgedPredictionRms_m(judged, trajectory_);
}

/// The stiffest mode's angular frequency times the frame period, at `values`.
double OutputErrorStep::omegaH(const std::vector<double>& values) const {
  Model m = model_;
  setValues(m, space_.refs(), values);
  return stiffestModeRadPerS(m, reference_m_) * (1.0 / model_.frame_rate_hz);
}

/// Stiff scenes: semi-implicit Euler drifts as (omega h)^2; a finer integrator is kept when the
/// simulated motion fits the frames clearly better and predicts no worse (data made by a coarse
/// integrator, e.g. a simulation with one step per frame, keep theirs).
void OutputErrorStep::trySubsteps(OutputErrorResult* best, double* best_rms_m) {
  const double omega_h = omegaH(best->values);
  if (!(options_.max_omega_h_per_substep > 0.0) || !(omega_h / model_.substeps > options_.max_omega_h_per_substep))
    return;
  const int needed = std::min(kMaxSubsteps, static_cast<int>(std::ceil(omega_h / options_.max_omega_h_per_substep)));
  if (needed <= model_.substeps) return;
  Model finer = model_;
  finer.substeps = needed;
  const OutputErrorResult oe = fit(finer, best->genes, kScoutIterations, false);
  out_.time_cut = out_.time_cut || oe.stopped_by_time;
  const std::string head = "the stiffest mode has omega*h = " + formatValue(omega_h) + " per frame: " +
                           std::to_string(needed) + " substeps per frame ";
  const std::string why = unusableBecause(oe);
  if (!why.empty()) {  // no cost to compare: say why instead of a cost of 0
    note_(head + "could not be tried (the fit " + why + "): kept " + std::to_string(model_.substeps));
    return;
  }
  // Integrators compared by the output-error cost (each fits its own start states): the judge
  // starts from frame differences, the velocity a one-step integrator wants, and so favours it.
  const double finer_rms_m = judge(finer, oe.genes);
  const bool better = oe.observation_cost_m2 < 0.5 * best->observation_cost_m2 && !std::isinf(finer_rms_m);
  note_(head + "fit the frames " + (better ? "better" : "no better") + " than " + std::to_string(model_.substeps) +
        " (output-error cost " + formatValue(oe.observation_cost_m2) + " against " +
        formatValue(best->observation_cost_m2) + " m^2, " + std::to_string(kJudgeHorizonFrames) +
        " frames ahead " + formatJudged(finer_rms_m) + " against " + formatJudged(*best_rms_m) + "): " +
        (better ? "the model now uses " + std::to_string(needed) : "kept " + std::to_string(model_.substeps)));
  if (better) {
    model_ = finer;
    *best = oe;
    *best_rms_m = finer_rms_m;
  }
}

/// The output error from the best start, to convergence; its answer replaces the scouts' when
/// its cost is no higher and it predicts no worse.
void OutputErrorStep::finalFit(OutputErrorResult* best, double* best_rms_m) {
  const OutputErrorResult oe = fit(model_, best->genes, options_.output_error.max_iterations, options_.estimate_std);
  out_.time_cut = out_.time_cut || oe.stopped_by_time || best->stopped_by_time;
  const std::string why = unusableBecause(oe);
  if (!why.empty() && oe.ran) note_("warning: the final output-error fit " + why + ": not adopted");
  const double final_rms_m = why.empty() ? judge(model_, oe.genes) : *best_rms_m;
  if (why.empty() && oe.observation_cost_m2 <= best->observation_cost_m2 * (1.0 + 1e-9) &&
      replacesStanding(final_rms_m, *best_rms_m)) {
    *best = oe;
    *best_rms_m = final_rms_m;
    return;
  }
  if (options_.estimate_std)  // the scouts' answer stands, and they estimate no std
    out_.std_missing_reason =
        oe.stopped_by_time ? "the time limit cut the output-error fit before its uncertainty was computed"
        : why.empty()      ? "the final output-error fit ended no better than its start, whose uncertainty is not computed"
                           : "the final output-error fit " + why;
}

void OutputErrorStep::noteFit(const OutputErrorResult& oe, bool first_stage_only) const {
  note_("output error: " + std::to_string(oe.segments) + " segments, " + std::to_string(oe.iterations) +
        (first_stage_only ? " iterations of its first stage (" : " iterations of the final fit (") +
        (oe.stages > 1 ? "over " + std::to_string(oe.stages) + " stages growing the data, " : std::string()) +
        (oe.converged ? "converged" : oe.termination) + "), marker noise from its residuals " +
        formatValue(oe.noise_std_m) + " m (from the data " + formatValue(noise_estimate_m_) + " m)");
  if (oe.noise_std_m > kMisfitFactor * std::max(noise_estimate_m_, 1e-9))
    note_("warning: the output-error residual (" + formatValue(oe.noise_std_m) + " m RMS) is " +
          formatValue(oe.noise_std_m / std::max(noise_estimate_m_, 1e-9)) +
          "x the markers' noise: the model does not explain the motion (missing bonds or "
          "kinds, a wrong structure, or too few substeps for its stiffness)");
}

}  // namespace mme

// The offline pipeline as a user gets it: the default engine identifies what the paper's
// settings did not (a soft hanging object without bounds), stops once converged, widens a default
// bound it ended on, reports a user's bound instead of crossing it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/core/stiffness.h"
#include "motion_model_estimation/identification/estimators/answer_judge.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/muscles/muscle_placement.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "motion_model_estimation/scenes/scenes.h"
#include "test_helpers.h"

namespace {

using mme::test::maxRelativeError;

struct Hanging {
  mme::Model truth = mme::makeHangingObject({});
  mme::Model blank = mme::test::withoutBounds(mme::test::withoutValues(truth));
  mme::Trajectory data = mme::simulateTrajectory(truth, 240, truth.frame_rate_hz);
  std::vector<double> true_values = mme::getValues(truth, mme::freeParameters(truth));
};

bool anyNote(const mme::IdentifyResult& r, const std::string& text) {
  for (const std::string& note : r.notes)
    if (note.find(text) != std::string::npos) return true;
  return false;
}

/// The output error ran: its judge's figures or a fit that was no answer.
bool outputErrorRan(const mme::IdentifyResult& r) {
  return anyNote(r, "judged 10 frames ahead on the fitted frames") || anyNote(r, "the output-error fit");
}

std::string allNotes(const mme::IdentifyResult& r) {
  std::string text;
  for (const std::string& note : r.notes) text += note + "\n";
  return text;
}

using mme::test::StiffAtOneSubstep;

// With the model's integrator kept (no substep trial) the output error's answer predicts 10
// frames ahead far worse than the one-step answer it would replace: the identification ends with
// the one-step answer (bit for bit the one-step cost's), says why in a warning, and does not run
// the final fit.
TEST(Identifier, AnOutputErrorThatBlowsUpLeavesTheBetterAnswerWithAWarning) {
  StiffAtOneSubstep s;
  mme::IdentifyOptions options = mme::identifyOptionsFor(mme::Preset::kDefault);
  options.estimate_std = false;
  options.es.threads = 1;
  options.max_omega_h_per_substep = 0.0;
  const mme::IdentifyResult r = mme::identifyModel(s.search, s.data, options);
  EXPECT_EQ(r.estimator, mme::Estimator::kShortTerm);
  EXPECT_EQ(r.substeps, 1);
  EXPECT_TRUE(anyNote(r, "warning: judged 10 frames ahead")) << "no warning";
  EXPECT_TRUE(anyNote(r, "the output error's answer is worse and not adopted"));
  EXPECT_TRUE(anyNote(r, " not run"));  // the final fit
  options.cost = mme::CostChoice::kShortTerm;
  const mme::IdentifyResult one_step = mme::identifyModel(s.search, s.data, options);
  EXPECT_EQ(r.values, one_step.values);
  EXPECT_EQ(r.global_cost, one_step.global_cost);
  EXPECT_TRUE(std::isfinite(mme::judgedPredictionRms_m(r.model, s.data)));
}

// At a millimetre of noise on the paper's object the one-step answer is biased by the noise (its
// stiffnesses several times the truth) yet, from noisy starts, predicts the fitted frames about as
// well as the output error's: the output error's answer, whose residuals are at the noise, is
// the one adopted, and it lands near the truth.
TEST(Identifier, AtAMillimetreTheOutputErrorAtTheNoiseIsAdopted) {
  const mme::Scene scene = mme::makeScene("paper_object");
  mme::Trajectory data = mme::simulateTrajectory(scene.model, 100, scene.model.frame_rate_hz);
  mme::addGaussianNoise(&data, 1e-3, 501);
  const std::vector<double> truth = mme::getValues(scene.model, mme::freeParameters(scene.model));
  mme::IdentifyOptions options = mme::identifyOptionsFor(mme::Preset::kDefault);
  options.estimate_std = false;
  options.es.threads = 1;
  const mme::IdentifyResult r = mme::identifyModel(scene.model, data, options);
  EXPECT_EQ(r.estimator, mme::Estimator::kOutputError);
  EXPECT_TRUE(anyNote(r, "the output error's answer is adopted"));
  std::vector<double> errors;
  for (size_t k = 0; k < truth.size(); ++k) errors.push_back(std::abs(r.values[k] / truth[k] - 1.0));
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.05) << "median relative error";
}

// The one-step cost's std (covariance.h on its forward-difference Jacobian): a spring type whose
// only bond joins two fixed particles moves no residual, so its parameters are flagged with no
// std, and the others keep the std of the same model without that type (only the degrees of
// freedom in s^2 = cost / (residuals - genes) differ).
TEST(Identifier, OneStepStdFlagsWhatTheDataCannotDetermine) {
  mme::Model plain = mme::test::smallObject();
  mme::test::addParticle(&plain, Eigen::Vector3d(1, 1, 1), 1.0, true);
  mme::test::addParticle(&plain, Eigen::Vector3d(1.2, 1, 1), 1.0, true);
  mme::Model idle = plain;
  const int type = mme::test::addType(&idle, "idle", mme::BondKind::kSpring,
                                      {{mme::kStiffness, 5.0}, {mme::kRestLength, 0.15}});
  const int last = static_cast<int>(idle.particles.size()) - 1;
  mme::test::addBond(&idle, type, last - 1, last);
  mme::Trajectory data = mme::simulateTrajectory(idle, 60, 100.0);
  mme::addGaussianNoise(&data, 1e-4, 4);
  const auto uncertainty = [&](const mme::Model& model, size_t* residuals) {
    const mme::Model search = mme::test::withoutValues(model);
    const mme::ShortTermCost cost(search, data);
    const mme::ParameterSpace space(search, data);
    *residuals = cost.residualCount();
    return mme::estimateStdDevs(cost, space, space.toSearch(mme::getValues(model, mme::freeParameters(model))));
  };
  size_t m = 0;
  const mme::GeneUncertainty without = uncertainty(plain, &m);
  const mme::GeneUncertainty with = uncertainty(idle, &m);
  ASSERT_TRUE(with.failure.empty()) << with.failure;
  const size_t n = without.std_devs.size();
  ASSERT_EQ(with.std_devs.size(), n + 2);
  EXPECT_TRUE(with.unidentifiable[n]);      // idle/stiffness
  EXPECT_TRUE(with.unidentifiable[n + 1]);  // idle/rest_length
  EXPECT_TRUE(std::isnan(with.std_devs[n]) && std::isnan(with.std_devs[n + 1]));
  const double dof_ratio = std::sqrt(static_cast<double>(m - n) / static_cast<double>(m - n - 2));
  for (size_t k = 0; k < n; ++k) {
    EXPECT_FALSE(with.unidentifiable[k]) << k;
    ASSERT_TRUE(std::isfinite(without.std_devs[k]) && without.std_devs[k] > 0.0) << k;
    EXPECT_NEAR(with.std_devs[k], without.std_devs[k] * dof_ratio, 1e-9 * without.std_devs[k]) << k;
  }
}

/// A controller the passive springs lack: test_helpers' muscleObject with its muscle made a
/// plain spring for the passive model, every spring's stiffness free, 1 um of marker noise. The
/// search's one-step residuals are the controller's forces, far above what the noise gives.
struct MissedController {
  mme::Model truth = mme::test::muscleObject();
  mme::Trajectory data = mme::simulateTrajectory(truth, 200, truth.frame_rate_hz);
  mme::Model passive = mme::removeMuscles(truth);
  MissedController() {
    mme::addGaussianNoise(&data, 1e-6, 7);
    for (mme::BondType& type : passive.bond_types) type.param(mme::kStiffness).free = true;
  }
};

mme::IdentifyOptions quickDefaults() {
  mme::IdentifyOptions o = mme::identifyOptionsFor(mme::Preset::kDefault);
  o.es.threads = 1;
  o.estimate_std = false;
  o.generations = 80;
  return o;
}

// Asked to defer it, the identification leaves the output error to its caller where the
// one-step residuals are far above the markers' noise (the passive model misses a controller):
// the answer is the search's, bit for bit, and a note says why. Not asked, the output error runs.
TEST(Identifier, TheOutputErrorOnAModelThatMissesTheMotionIsDeferredWhenAsked) {
  const MissedController c;
  mme::IdentifyOptions o = quickDefaults();
  const mme::IdentifyResult inline_oe = mme::identifyModel(c.passive, c.data, o);
  EXPECT_FALSE(inline_oe.output_error_deferred);
  EXPECT_TRUE(outputErrorRan(inline_oe)) << allNotes(inline_oe);
  o.defer_output_error_on_misfit = true;
  const mme::IdentifyResult deferred = mme::identifyModel(c.passive, c.data, o);
  EXPECT_TRUE(deferred.output_error_deferred);
  EXPECT_EQ(deferred.estimator, mme::Estimator::kShortTerm);
  EXPECT_TRUE(anyNote(deferred, "the output error is deferred"));
  EXPECT_FALSE(outputErrorRan(deferred)) << allNotes(deferred);
  EXPECT_GT(deferred.one_step_rms_m, 2.0 * std::sqrt(6.0) * deferred.noise_estimate_m);
  o.cost = mme::CostChoice::kShortTerm;
  const mme::IdentifyResult one_step = mme::identifyModel(c.passive, c.data, o);
  EXPECT_EQ(deferred.values, one_step.values);
  // Run later, the output error is judged as inline: its answer only where it predicts no worse.
  o.cost = mme::CostChoice::kAuto;
  const mme::IdentifyResult later = mme::runDeferredOutputError(deferred, c.data, o);
  EXPECT_FALSE(later.output_error_deferred);
  EXPECT_TRUE(outputErrorRan(later)) << allNotes(later);
  EXPECT_EQ(later.generations, deferred.generations);  // the search it started from
  if (later.estimator == mme::Estimator::kShortTerm) EXPECT_EQ(later.values, deferred.values);
  else EXPECT_LE(mme::judgedPredictionRms_m(later.model, c.data), mme::judgedPredictionRms_m(deferred.model, c.data));
}

// Where the passive model explains the motion (its residuals at the markers' noise) nothing is
// deferred: the output error runs and the answer is the one without the option, bit for bit.
TEST(Identifier, TheOutputErrorAtTheNoiseIsNeverDeferred) {
  const mme::Model truth = mme::test::smallObject();
  mme::Trajectory data = mme::simulateTrajectory(truth, 100, truth.frame_rate_hz);
  mme::addGaussianNoise(&data, 1e-4, 11);
  mme::IdentifyOptions o = quickDefaults();
  const mme::IdentifyResult plain = mme::identifyModel(mme::test::withoutValues(truth), data, o);
  o.defer_output_error_on_misfit = true;
  const mme::IdentifyResult asked = mme::identifyModel(mme::test::withoutValues(truth), data, o);
  EXPECT_FALSE(asked.output_error_deferred);
  EXPECT_FALSE(anyNote(asked, "deferred"));
  EXPECT_TRUE(anyNote(asked, "judged 10 frames ahead on the fitted frames"));
  EXPECT_LT(asked.one_step_rms_m, 1.5 * std::sqrt(6.0) * asked.noise_estimate_m);
  EXPECT_EQ(asked.estimator, plain.estimator);
  EXPECT_EQ(asked.values, plain.values);
}

TEST(Identifier, DefaultEngineIdentifiesAHangingObjectWithoutBoundsAndStopsOnceConverged) {
  Hanging h;
  mme::IdentifyOptions options = mme::identifyOptionsFor(mme::Preset::kDefault);
  options.estimate_std = false;
  const mme::IdentifyResult r = mme::identifyModel(h.blank, h.data, options);
  EXPECT_LT(maxRelativeError(r.values, h.true_values), 1e-3) << r.global_cost;
  EXPECT_EQ(r.stop, mme::IdentifyStop::kConverged);
  EXPECT_LT(r.generations, 100);
  for (mme::ParameterFlag flag : r.flags) EXPECT_EQ(flag, mme::ParameterFlag::kNone);
}

// A complete guess in the model (every free value given, e.g. an earlier fit) is an individual of
// the first population as it is: with no equation-error start, no refinement and one generation,
// the search ends no worse than the guess; without the values start it ends far worse.
TEST(Identifier, ACompleteGuessIsNeverLost) {
  Hanging h;
  mme::Trajectory noisy = h.data;
  mme::addGaussianNoise(&noisy, 1e-4, 3);
  mme::Model guess = h.truth;  // the truth's values: the best the noisy data allow, nearly
  const mme::ShortTermCost cost(guess, noisy);
  const double guess_cost = cost.evaluate(h.true_values, nullptr);
  mme::IdentifyOptions options = mme::identifyOptionsFor(mme::Preset::kDefault);
  options.estimate_std = false;
  options.equation_error_start = false;
  options.es.refine_start_generation = 1000;
  options.generations = 1;
  options.cost = mme::CostChoice::kShortTerm;
  options.max_bound_widenings = 0;
  const mme::IdentifyResult kept = mme::identifyModel(guess, noisy, options);
  EXPECT_LE(kept.global_cost, guess_cost);
  options.values_start = false;
  const mme::IdentifyResult drawn = mme::identifyModel(guess, noisy, options);
  EXPECT_GT(drawn.global_cost, 2.0 * guess_cost);
}

// Without the equation-error start the rest lengths (2.4-20x shorter than observed) lie below
// the default bounds [observed/3, 3 observed]: the refined best presses on them, they are
// widened and the search resumes from it.
TEST(Identifier, WidensADefaultBoundTheAnswerEndedOnAndSaysSo) {
  Hanging h;
  mme::IdentifyOptions options = mme::identifyOptionsFor(mme::Preset::kDefault);
  options.estimate_std = false;
  options.equation_error_start = false;
  options.generations = 400;
  std::vector<std::string> messages;
  const mme::IdentifyResult r = mme::identifyModel(
      h.blank, h.data, options, [&](const mme::Progress& p) { if (!p.message.empty()) messages.push_back(p.message); });
  EXPECT_GE(r.bound_widenings, 1);
  ASSERT_FALSE(messages.empty());
  EXPECT_NE(messages[0].find("rest_length' ended at its default lower search bound"), std::string::npos)
      << messages[0];
  EXPECT_EQ(r.notes.size(), messages.size());
  // Each widening is tenfold (here twice for some types): every rest length ends inside and
  // every parameter is found.
  EXPECT_LT(maxRelativeError(r.values, h.true_values), 1e-3);
  for (mme::ParameterFlag flag : r.flags) EXPECT_EQ(flag, mme::ParameterFlag::kNone);
}

// A bound from the model file is the user's: reached, it is flagged, never crossed.
TEST(Identifier, FlagsAUserBoundInsteadOfCrossingIt) {
  mme::Model truth = mme::test::smallObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 60, 100.0);
  mme::Model search = mme::test::withoutValues(truth);
  search.bond_types[1].param(mme::kStiffness).max = 30.0;  // true 45 N/m
  mme::IdentifyOptions options = mme::identifyOptionsFor(mme::Preset::kDefault);
  options.estimate_std = false;
  const mme::IdentifyResult r = mme::identifyModel(search, data, options);
  EXPECT_EQ(r.bound_widenings, 0);
  ASSERT_EQ(r.parameters[2].name, "s1/stiffness");
  EXPECT_NEAR(r.values[2], 30.0, 0.3);
  EXPECT_EQ(r.flags[2], mme::ParameterFlag::kAtUpperBound);
  EXPECT_STREQ(mme::parameterFlagName(r.flags[2]), "at_upper_bound");
}

// The paper's preset runs its whole generation budget (no convergence stop) with BOBYQA from 400.
// A time limit that cuts the output-error fit after the search converged is reported as the
// time limit, never as convergence (the output error's own limit, grown in stages so that the
// cut is certain: the first stage always outlasts 1 ns). Without the limit the same run
// converges.
TEST(Identifier, ATimeLimitThatCutTheFitIsNeverConvergence) {
  const mme::Model truth = mme::makeHangingObject({});
  const mme::Model blank = mme::test::withoutBounds(mme::test::withoutValues(truth));
  mme::Trajectory noisy = mme::simulateTrajectory(truth, 60, truth.frame_rate_hz);
  mme::addGaussianNoise(&noisy, 1e-4, 3);
  mme::IdentifyOptions options = mme::identifyOptionsFor(mme::Preset::kDefault);
  options.estimate_std = false;
  options.cost = mme::CostChoice::kOutputError;
  options.output_error.grow_segments = 2;
  const mme::IdentifyResult whole = mme::identifyModel(blank, noisy, options);
  ASSERT_EQ(whole.estimator, mme::Estimator::kOutputError);
  EXPECT_EQ(whole.stop, mme::IdentifyStop::kConverged);
  options.output_error.max_time_s = 1e-9;
  const mme::IdentifyResult cut = mme::identifyModel(blank, noisy, options);
  EXPECT_EQ(cut.stop, mme::IdentifyStop::kWallTime);
  EXPECT_STREQ(mme::identifyStopName(cut.stop), "wall-time limit");
}

TEST(Identifier, PaperPresetKeepsThePapersSchedule) {
  const mme::IdentifyOptions paper = mme::identifyOptionsFor(mme::Preset::kPaper);
  EXPECT_EQ(paper.patience_generations, 0);
  EXPECT_EQ(paper.es.refine_algorithm, mme::RefineAlgorithm::kBobyqa);
  EXPECT_EQ(paper.es.refine_start_generation, 400);
  EXPECT_EQ(paper.es.refine_period, 100);
  EXPECT_FALSE(paper.equation_error_start);
  EXPECT_EQ(paper.max_bound_widenings, 0);
  EXPECT_EQ(paper.cost, mme::CostChoice::kShortTerm);
  const mme::IdentifyOptions best = mme::identifyOptionsFor(mme::Preset::kDefault);
  EXPECT_EQ(best.es.refine_algorithm, mme::RefineAlgorithm::kLevenbergMarquardt);
  mme::Preset preset = mme::Preset::kDefault;
  EXPECT_TRUE(mme::parsePreset("paper", &preset));
  EXPECT_EQ(preset, mme::Preset::kPaper);
  EXPECT_FALSE(mme::parsePreset("Paper", &preset));

  mme::Model truth = mme::test::smallObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 40, 100.0);
  mme::IdentifyOptions short_paper = paper;
  short_paper.generations = 30;
  short_paper.estimate_std = false;
  EXPECT_EQ(mme::identifyModel(mme::test::withoutValues(truth), data, short_paper).generations, 30);
}

}  // namespace

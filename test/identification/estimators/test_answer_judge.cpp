// The yardstick every estimator's answer is judged by before it replaces another: the truth
// predicts better than a wrong model, a model that blows up scores infinity (never a huge finite
// figure), nothing judgeable gives NaN, and the adoption rule reads those figures as it says.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/answer_judge.h"
#include "motion_model_estimation/scenes/scenes.h"
#include "test_helpers.h"

namespace {

struct Scene {
  mme::Model truth = mme::makeScene("paper_object").model;
  mme::Trajectory data = mme::simulateTrajectory(truth, 60, truth.frame_rate_hz);
  /// The truth with every free value scaled by `factor`.
  mme::Model scaled(double factor) const {
    mme::Model m = truth;
    const std::vector<mme::ParamRef> refs = mme::freeParameters(m);
    std::vector<double> values = mme::getValues(m, refs);
    for (double& v : values) v *= factor;
    mme::setValues(m, refs, values);
    return m;
  }
};

TEST(AnswerJudge, TheTruthPredictsBetterThanAWrongModel) {
  Scene s;
  const double truth_m = mme::judgedPredictionRms_m(s.truth, s.data);
  const double wrong_m = mme::judgedPredictionRms_m(s.scaled(1.3), s.data);
  EXPECT_LT(truth_m, 1e-6);  // its own noiseless motion, from frame differences as start velocities
  EXPECT_GT(wrong_m, 10.0 * truth_m);
  EXPECT_TRUE(std::isfinite(wrong_m));
}

// Stiffness 1e4 times the truth's with one step per frame: semi-implicit Euler leaves its stable
// range (omega h > 2) and the predictions grow without bound.
TEST(AnswerJudge, AModelThatBlowsUpScoresInfinity) {
  Scene s;
  mme::Model stiff = s.truth;
  for (mme::BondType& type : stiff.bond_types)
    if (type.param(mme::kStiffness).present) type.param(mme::kStiffness).value *= 1e4;
  stiff.substeps = 1;
  const double rms_m = mme::judgedPredictionRms_m(stiff, s.data, 40);
  EXPECT_TRUE(std::isinf(rms_m)) << rms_m;
  EXPECT_EQ(mme::formatJudged(rms_m), "blew up");
}

TEST(AnswerJudge, NothingToJudgeIsNaN) {
  Scene s;
  EXPECT_TRUE(std::isnan(mme::judgedPredictionRms_m(s.truth, mme::sliceFrames(s.data, 0, 3))));
  EXPECT_TRUE(std::isnan(mme::judgedPredictionRms_m(s.truth, s.data, 0)));
}

TEST(AnswerJudge, AdoptionRule) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(mme::replacesStanding(1.0, 2.0));
  EXPECT_TRUE(mme::replacesStanding(2.0, 2.0));
  EXPECT_TRUE(mme::replacesStanding(2.0 * (1.0 + 0.5 * mme::kJudgeTolerance), 2.0));  // within the noise
  EXPECT_FALSE(mme::replacesStanding(2.0 * (1.0 + 2.0 * mme::kJudgeTolerance), 2.0));
  EXPECT_FALSE(mme::replacesStanding(inf, 2.0));
  EXPECT_FALSE(mme::replacesStanding(inf, inf));  // a candidate that blew up never replaces
  EXPECT_TRUE(mme::replacesStanding(1.0, inf));
  EXPECT_TRUE(mme::replacesStanding(1.0, nan));
  EXPECT_FALSE(mme::replacesStanding(nan, 1.0));
  EXPECT_TRUE(mme::replacesStanding(nan, nan));  // nothing says it is worse
}

// An output-error answer judged worse still replaces the one-step answer when its residuals are
// at the markers' noise, unless its prediction blew up; above the noise the judge decides.
TEST(AnswerJudge, AnOutputErrorAtTheNoiseReplacesTheOneStepAnswer) {
  const double inf = std::numeric_limits<double>::infinity();
  const double noise_m = 1e-3;
  EXPECT_TRUE(mme::outputErrorReplacesOneStep(14e-3, 13e-3, 1.0 * noise_m, noise_m));
  EXPECT_TRUE(mme::outputErrorReplacesOneStep(14e-3, 13e-3, mme::kAtNoiseFactor * noise_m, noise_m));
  EXPECT_FALSE(mme::outputErrorReplacesOneStep(14e-3, 13e-3, 2.0 * mme::kAtNoiseFactor * noise_m, noise_m));
  EXPECT_FALSE(mme::outputErrorReplacesOneStep(inf, 13e-3, noise_m, noise_m));
  EXPECT_FALSE(mme::outputErrorReplacesOneStep(14e-3, 13e-3, noise_m, 0.0));  // noise unknown
  EXPECT_TRUE(mme::outputErrorReplacesOneStep(12e-3, 13e-3, 100.0 * noise_m, noise_m));  // judged better
}

}  // namespace

// The live node's prediction figures: evaluated when due (the first time, then once per period),
// the true model beats the model-free guesses on its own window and a wrong model does not, a
// window too short to predict from keeps no report and says why, bad settings are refused.
#include <gtest/gtest.h>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/live/prediction_monitor.h"
#include "test_helpers.h"

namespace {

using mme::test::predictionRms;

TEST(PredictionMonitor, EvaluatesWhenDueAndJudgesTheModel) {
  const mme::Model truth = mme::test::smallObject();
  const mme::Trajectory window = mme::simulateTrajectory(truth, 60, 100.0);
  mme::PredictionMonitor monitor({1, 10}, 5.0);
  EXPECT_TRUE(monitor.due(100.0));
  EXPECT_FALSE(monitor.report().has_value());
  ASSERT_TRUE(monitor.evaluate(100.0, truth, window));
  EXPECT_FALSE(monitor.due(104.9));
  EXPECT_TRUE(monitor.due(105.0));
  std::optional<mme::PredictionReport> r = monitor.report();
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->rows.size(), 8u);
  EXPECT_LT(predictionRms(*r, 10, mme::Predictor::kModel), 1e-12);
  EXPECT_GT(predictionRms(*r, 10, mme::Predictor::kConstantVelocity), 1e-5);
  EXPECT_TRUE(r->rollout_bounded);
  EXPECT_EQ(monitor.lastError(), "");

  // A model twice as stiff predicts worse than before, 10 frames ahead by more than 1 ahead.
  mme::Model wrong = truth;
  for (mme::BondType& t : wrong.bond_types) t.param(mme::kStiffness).value *= 2.0;
  ASSERT_TRUE(monitor.evaluate(105.0, wrong, window));
  r = monitor.report();
  EXPECT_GT(predictionRms(*r, 10, mme::Predictor::kModel), 1e-6);
  EXPECT_GT(predictionRms(*r, 10, mme::Predictor::kModel), predictionRms(*r, 1, mme::Predictor::kModel));
}

TEST(PredictionMonitor, TheCaptionSetsTheModelAgainstTheGuesses) {
  mme::PredictionReport r;
  r.rows.push_back({10, mme::Predictor::kModel, 7.14e-3, 300});
  r.rows.push_back({10, mme::Predictor::kConstantVelocity, 12.26e-3, 300});
  r.rows.push_back({10, mme::Predictor::kConstantAcceleration, 9.81e-3, 300});
  EXPECT_EQ(mme::predictionCaption(r, 10, 41),
            "10 frames ahead: model 7.1 mm (41 muscles), constant velocity 12.3, constant "
            "acceleration 9.8 mm");
  EXPECT_NE(mme::predictionCaption(r, 10, 0).find("(passive)"), std::string::npos);
  EXPECT_EQ(mme::predictionCaption(r, 5, 41), "");  // no sample at that horizon
}

TEST(PredictionMonitor, AWindowTooShortKeepsNoReportAndSaysWhy) {
  const mme::Model truth = mme::test::smallObject();
  const mme::Trajectory window = mme::simulateTrajectory(truth, 30, 100.0);
  mme::PredictionMonitor monitor;
  ASSERT_TRUE(monitor.evaluate(1.0, truth, window));
  EXPECT_FALSE(monitor.evaluate(7.0, truth, mme::sliceFrames(window, 0, 2)));
  EXPECT_FALSE(monitor.report().has_value());  // the old report is not shown as current
  EXPECT_NE(monitor.lastError(), "");
  EXPECT_FALSE(monitor.due(8.0));  // a failed try waits its period too
  EXPECT_TRUE(monitor.due(12.0));
}

TEST(PredictionMonitor, BadSettingsAreRefused) {
  EXPECT_THROW(mme::PredictionMonitor({}, 1.0), mme::InputError);
  EXPECT_THROW(mme::PredictionMonitor({0, 5}, 1.0), mme::InputError);
  EXPECT_THROW(mme::PredictionMonitor({1}, 0.0), mme::InputError);
}

}  // namespace

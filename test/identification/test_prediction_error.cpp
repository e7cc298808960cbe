// The prediction judge: the true model predicts its own motion exactly at every horizon and the
// model-free guesses do not; each guess is exact on the motion it assumes; occluded targets do
// not count and a start tolerates short gaps; a model that blows up is caught by the rollout;
// bad horizons are refused.
#include <gtest/gtest.h>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/prediction_error.h"
#include "test_helpers.h"

namespace {

using mme::Predictor;

using mme::test::predictionRms;

TEST(PredictionError, TheTrueModelPredictsItsOwnMotionAndTheGuessesDoNot) {
  const mme::Model truth = mme::test::smallObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 80, 100.0);
  const mme::PredictionReport r = mme::evaluatePredictions(truth, data, {1, 5, 10});
  ASSERT_EQ(r.rows.size(), 12u);
  EXPECT_EQ(r.starts, 77);  // frames 2..78
  for (int k : {1, 5, 10}) {
    EXPECT_LT(predictionRms(r, k, Predictor::kModel), 1e-12) << k;
    EXPECT_GT(predictionRms(r, k, Predictor::kConstantVelocity), 1e-5) << k;
    EXPECT_GT(predictionRms(r, k, Predictor::kConstantAcceleration), 1e-7) << k;
  }
  EXPECT_LT(predictionRms(r, 1, Predictor::kConstantVelocity), predictionRms(r, 10, Predictor::kConstantVelocity));
  EXPECT_TRUE(r.rollout_bounded);
  EXPECT_EQ(r.rollout_frames, 800);
  // A model 50 % stiffer predicts worse, the more so the further ahead.
  mme::Model stiff = truth;
  for (mme::BondType& t : stiff.bond_types) t.param(mme::kStiffness).value *= 1.5;
  const mme::PredictionReport w = mme::evaluatePredictions(stiff, data, {1, 10});
  EXPECT_GT(predictionRms(w, 1, Predictor::kModel), 1e-9);
  EXPECT_GT(predictionRms(w, 10, Predictor::kModel), 10.0 * predictionRms(w, 1, Predictor::kModel));
}

// Free fall: no bond, gravity only. Semi-implicit Euler under constant gravity is exactly the
// gravity-only guess and a constant second difference, so all three but constant velocity are
// exact; occluded targets are not counted.
TEST(PredictionError, EachGuessIsExactOnTheMotionItAssumes) {
  mme::Model fall;
  fall.frame_rate_hz = 50;
  for (int c = 0; c < 3; ++c) fall.gravity_mps2[c] = mme::test::valueParam(c == 2 ? -9.81 : 0.0);
  mme::test::addParticle(&fall, Eigen::Vector3d(0, 0, 1), 1.0, false, "", Eigen::Vector3d(0.3, 0, 2));
  mme::test::addParticle(&fall, Eigen::Vector3d(1, 0, 1), 2.0, false, "", Eigen::Vector3d(0, -0.2, 0));
  mme::Trajectory data = mme::simulateTrajectory(fall, 40, 50.0);
  const mme::PredictionReport r = mme::evaluatePredictions(fall, data, {3});
  EXPECT_LT(predictionRms(r, 3, Predictor::kModel), 1e-12);
  EXPECT_LT(predictionRms(r, 3, Predictor::kGravityOnly), 1e-12);
  EXPECT_LT(predictionRms(r, 3, Predictor::kConstantAcceleration), 1e-10);
  EXPECT_GT(predictionRms(r, 3, Predictor::kConstantVelocity), 1e-3);
  const long all = r.rows[0].samples;
  // Particle 1 unseen at frame 20: no start there (its position is unknown), the next two start
  // with its velocity from frame 19, and it is scored neither at frame 20 nor from those starts.
  data.occluded[20 * 2 + 1] = 1;
  const mme::PredictionReport o = mme::evaluatePredictions(fall, data, {3});
  EXPECT_EQ(o.starts, r.starts - 1);
  // Lost: both particles at start 20, particle 1 at starts 21 and 22, its target 20 (start 17).
  EXPECT_EQ(o.rows[0].samples, all - 3 * (2 + 2 + 1));
  // Particle 1 unseen every third frame: there are still starts (velocity from two frames
  // back), and what is scored stays exact.
  for (int t = 5; t < 40; t += 3) data.occluded[t * 2 + 1] = 1;
  const mme::PredictionReport gaps = mme::evaluatePredictions(fall, data, {3});
  EXPECT_GT(gaps.starts, 10);
  EXPECT_GT(gaps.rows[0].samples, 0);
  EXPECT_LT(predictionRms(gaps, 3, Predictor::kModel), 1e-12);
}

TEST(PredictionError, ARolloutThatBlowsUpIsCaughtAndBadInputIsRefused) {
  const mme::Model truth = mme::test::smallObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 30, 100.0);
  mme::Model explosive = truth;
  for (mme::BondType& t : explosive.bond_types) t.param(mme::kStiffness).value *= 1e5;  // omega h >> 2
  EXPECT_FALSE(mme::evaluatePredictions(explosive, data, {1}).rollout_bounded);
  EXPECT_THROW(mme::evaluatePredictions(truth, data, {}), mme::InputError);
  EXPECT_THROW(mme::evaluatePredictions(truth, data, {0}), mme::InputError);
  mme::Trajectory two = mme::sliceFrames(data, 0, 2);
  EXPECT_THROW(mme::evaluatePredictions(truth, two, {1}), mme::InputError);
}

}  // namespace

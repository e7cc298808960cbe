// The live node's sensor muscles: the refit of their linear part recovers a linear controller
// from its data alone, the job adds muscles to a passive model on a window (its passive
// parameters left free), lays them on the estimator's latest passive values, refits them on a
// later window once its period has passed (kept only where the refit predicts the window no
// worse), forgets them on request, and turns an unusable window into a state and a reason,
// never a crash.
#include <gtest/gtest.h>

#include <cmath>

#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"
#include "motion_model_estimation/identification/muscles/muscle_placement.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/live/muscle_job.h"
#include "motion_model_estimation/live/muscle_refit.h"
#include "test_helpers.h"

namespace {

using mme::Model;

/// muscleObject with its controller in tanh's near-linear range (gain x `scale`, network /
/// `scale`; test_sensor_muscles uses 100): at 1000 a law the linear refit represents to 1e-5.
Model linearMuscleObject(double scale = 100.0) {
  Model m = mme::test::muscleObject();
  mme::BondType& type = m.bond_types[m.bondTypeIndex("m")];
  type.param(mme::kGain).value *= scale;
  for (mme::Param& p : type.network) p.value /= scale;
  return m;
}

/// The model's 10-frame open-loop error on `window` [m].
double predict10M(const Model& model, const mme::Trajectory& window) {
  std::vector<std::string> names;
  for (const mme::Particle& p : model.particles) names.push_back(p.name);
  const mme::PredictionReport report =
      mme::evaluatePredictions(model, mme::remapMarkers(window, names, nullptr), {10}, 1.0);
  return mme::test::predictionRms(report, 10, mme::Predictor::kModel);
}

/// gain x network value k of the muscle type `name`: what the linear refit solves for.
double linearWeight(const Model& m, const std::string& name, int k) {
  const mme::BondType& type = m.bond_types[m.bondTypeIndex(name)];
  return type.value(mme::kGain) * type.network[k].value;
}

TEST(MuscleRefit, RecoversALinearControllerFromItsData) {
  const Model truth = linearMuscleObject(1000.0);
  const mme::Trajectory data = mme::simulateTrajectory(truth, 200, truth.frame_rate_hz);
  Model silent = truth;
  for (mme::Param& p : silent.bond_types[silent.bondTypeIndex("m")].network) p.value = 0.0;
  ASSERT_EQ(mme::refittableMuscleTypes(silent), 1);
  const mme::MuscleRefitResult r = mme::refitMuscleActivations(silent, data, 1e-12);
  ASSERT_TRUE(r.ok) << r.why;
  EXPECT_EQ(r.muscle_types, 1);
  EXPECT_EQ(r.unknowns, 5);              // 2 inputs x (elongation, speed) + bias
  EXPECT_EQ(r.rows, 3 * 3 * (200 - 2));  // 3 free particles, every inner frame
  EXPECT_LT(r.residual_rms_m, 1e-7);  // what tanh bends away from linear
  for (int k = 0; k < 5; ++k)
    EXPECT_NEAR(linearWeight(r.model, "m", k), linearWeight(truth, "m", k),
                2e-3 * std::abs(linearWeight(truth, "m", k)) + 1e-9)
        << "network value " << k;
  // The gain is the margin x the largest linear activation: tanh stays near linear.
  EXPECT_GT(r.model.bond_types[r.model.bondTypeIndex("m")].value(mme::kGain), 0.0);
  EXPECT_LT(predict10M(r.model, data), 1e-2 * predict10M(silent, data));
}

TEST(MuscleRefit, TheIterativeSolveFromTheCurrentValuesFindsTheSameFit) {
  // What a large body gets (above the direct solve's size): conjugate gradients started at the
  // model's values; on 5 unknowns they reach the direct solve's answer.
  const Model truth = linearMuscleObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 200, truth.frame_rate_hz);
  Model start = truth;
  for (mme::Param& p : start.bond_types[start.bondTypeIndex("m")].network) p.value *= 0.5;
  const mme::MuscleRefitResult direct = mme::refitMuscleActivations(start, data, 1e-3);
  const mme::MuscleRefitResult iterative = mme::refitMuscleActivations(start, data, 1e-3, 10.0, 0);
  ASSERT_TRUE(direct.ok && iterative.ok);
  for (int k = 0; k < 5; ++k)
    EXPECT_NEAR(linearWeight(iterative.model, "m", k), linearWeight(direct.model, "m", k),
                1e-6 * std::abs(linearWeight(direct.model, "m", k)) + 1e-12)
        << "network value " << k;
}

TEST(MuscleRefit, SaysWhyWhenThereIsNothingToRefit) {
  const Model truth = linearMuscleObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 50, truth.frame_rate_hz);
  const Model passive = mme::removeMuscles(truth);
  mme::MuscleRefitResult r = mme::refitMuscleActivations(passive, data, 1.0);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.why.find("no muscle"), std::string::npos) << r.why;
  mme::Trajectory hidden = data;
  for (auto& o : hidden.occluded) o = 1;
  r = mme::refitMuscleActivations(truth, hidden, 1.0);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.why.find("no frame"), std::string::npos) << r.why;
  r = mme::refitMuscleActivations(truth, mme::sliceFrames(data, 0, 2), 1.0);
  EXPECT_FALSE(r.ok);
}

mme::MuscleJobOptions jobOptions() {
  mme::MuscleJobOptions o;
  o.fit = mme::liveSensorMuscleOptions(6, 0.0);
  o.fit.neighbours = 3;
  o.min_frames = 150;
  o.refit_period_s = 1.0;
  return o;
}

TEST(MuscleJob, AddsMusclesThenRefitsTheirLinearPartOnALaterWindow) {
  const Model truth = linearMuscleObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 300, truth.frame_rate_hz);
  Model passive = mme::removeMuscles(truth);
  passive.bond_types[passive.bondTypeIndex("s")].param(mme::kStiffness).free = true;  // estimated live
  mme::MuscleJob job(jobOptions());
  EXPECT_EQ(job.status(), "waiting");
  // Too short a window: nothing runs.
  EXPECT_FALSE(job.fitIfDue(passive, mme::sliceFrames(data, 0, 100), 0.0).has_value());
  EXPECT_EQ(job.status(), "waiting");
  const std::optional<Model> fitted = job.fitIfDue(passive, mme::sliceFrames(data, 0, 150), 0.0);
  ASSERT_TRUE(fitted.has_value()) << job.status() << ": " << job.lastMessage();
  EXPECT_EQ(job.status(), "fitted");
  EXPECT_GT(job.muscles(), 4);
  EXPECT_EQ(job.fits(), 1u);
  EXPECT_EQ(mme::refittableMuscleTypes(*fitted), job.muscles());
  // The passive parameters stay free (the estimator goes on with them), the muscles are fixed.
  std::vector<std::string> before, after;
  for (const mme::ParamRef& ref : mme::freeParameters(passive)) before.push_back(ref.name);
  for (const mme::ParamRef& ref : mme::freeParameters(*fitted)) after.push_back(ref.name);
  EXPECT_EQ(after, before);
  // Fitted: no second fit.
  EXPECT_FALSE(job.fitIfDue(passive, data, 100.0).has_value());

  // The kept muscles laid on the estimator's passive model: its free values become theirs.
  Model estimated = passive;
  estimated.bond_types[estimated.bondTypeIndex("s")].param(mme::kStiffness).value = 61.0;
  const std::optional<Model> laid = job.withMuscles(estimated);
  ASSERT_TRUE(laid.has_value());
  EXPECT_EQ(laid->bond_types[laid->bondTypeIndex("s")].value(mme::kStiffness), 61.0);
  EXPECT_EQ(laid->bonds.size(), fitted->bonds.size());
  EXPECT_FALSE(job.withMuscles(mme::test::smallObject()).has_value());  // another structure

  // A later window (the estimator's: no anchor markers): before the period nothing runs, after
  // it the linear part is refitted there and kept, predicting that window no worse.
  const mme::Trajectory later = mme::sliceFrames(data, 150, 150);
  EXPECT_FALSE(job.refitIfDue(passive, later, job.lastFitS() + 0.5).has_value());
  EXPECT_EQ(job.refits(), 0u);
  const std::optional<Model> refitted = job.refitIfDue(passive, later, job.lastFitS() + 1.5);
  ASSERT_TRUE(refitted.has_value());
  EXPECT_EQ(job.refits(), 1u);
  EXPECT_EQ(job.refitsAdopted(), 1u);
  EXPECT_GT(job.lastRefitMs(), 0.0);
  EXPECT_NE(mme::modelToYaml(*refitted), mme::modelToYaml(*fitted));
  EXPECT_LE(predict10M(*refitted, later), predict10M(*fitted, later));
  EXPECT_EQ(mme::modelToYaml(*job.withMuscles(passive)), mme::modelToYaml(*refitted));  // kept
  // Its free parameters are still the passive ones.
  after.clear();
  for (const mme::ParamRef& ref : mme::freeParameters(*refitted)) after.push_back(ref.name);
  EXPECT_EQ(after, before);
  // The next refit waits for the period from this one's end.
  EXPECT_FALSE(job.refitIfDue(passive, later, job.lastFitS() + 2.0).has_value());
  // The same input gives the same refit.
  mme::MuscleJob again(jobOptions());
  ASSERT_TRUE(again.fitIfDue(passive, mme::sliceFrames(data, 0, 150), 0.0).has_value());
  const std::optional<Model> same = again.refitIfDue(passive, later, again.lastFitS() + 1.5);
  ASSERT_TRUE(same.has_value());
  EXPECT_EQ(mme::modelToYaml(*same), mme::modelToYaml(*refitted));

  // forget(): waiting again; no refit without muscles.
  job.forget();
  EXPECT_EQ(job.status(), "waiting");
  EXPECT_EQ(job.muscles(), 0);
  EXPECT_FALSE(job.refitIfDue(passive, later, 1e6).has_value());
  EXPECT_FALSE(job.withMuscles(passive).has_value());
}

TEST(MuscleJob, AnUnusableWindowFailsWithTheReasonAndRetriesLater) {
  const Model truth = linearMuscleObject();
  mme::Trajectory data = mme::simulateTrajectory(truth, 150, truth.frame_rate_hz);
  for (auto& o : data.occluded) o = 1;
  mme::MuscleJob job(jobOptions());
  EXPECT_FALSE(job.fitIfDue(mme::removeMuscles(truth), data, 0.0).has_value());
  EXPECT_EQ(job.status(), "failed");
  EXPECT_FALSE(job.lastMessage().empty());
  // Not again before the retry period.
  const uint32_t fits = job.fits();
  EXPECT_FALSE(job.fitIfDue(mme::removeMuscles(truth), data, 1.0).has_value());
  EXPECT_EQ(job.status(), "failed");
  EXPECT_EQ(job.fits(), fits);
  // Cancelled: nothing runs any more.
  job.cancel();
  EXPECT_FALSE(job.fitIfDue(mme::removeMuscles(truth), data, 1e6).has_value());
}

TEST(MuscleJob, BadOptionsNameTheParameter) {
  mme::MuscleJobOptions o = jobOptions();
  EXPECT_EQ(mme::validateOptions(o), "");
  o.fit.sensors = 0;
  EXPECT_NE(mme::validateOptions(o).find("muscle_sensors"), std::string::npos);
  o = jobOptions();
  o.refit_period_s = -1.0;
  EXPECT_NE(mme::validateOptions(o).find("muscle_refit_period_sec"), std::string::npos);
  o = jobOptions();
  o.fit.max_time_s = std::nan("");
  EXPECT_NE(mme::validateOptions(o).find("muscles_max_time_sec"), std::string::npos);
}

}  // namespace

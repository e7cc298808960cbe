// The offline pipeline (pipeline/identify_pipeline.h) and the metadata of its result
// (pipeline/result_metadata.h): the steps run in order and hand on what the next needs, a
// step the data cannot feed leaves the answer before it with a warning, and the file's
// `identification:` block says what the result holds.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/model_builder.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/core/stiffness.h"
#include "motion_model_estimation/identification/estimators/answer_judge.h"
#include "motion_model_estimation/identification/muscles/muscle_placement.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/pipeline/identify_pipeline.h"
#include "motion_model_estimation/pipeline/result_metadata.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "motion_model_estimation/scenes/scenes.h"
#include "test_helpers.h"

namespace {

mme::Model smallRandomObject() {
  mme::RandomObjectSpec spec;
  spec.particles = 8;
  spec.bond_types = 2;
  spec.bonds = 12;
  return mme::makeRandomObject(spec);
}

mme::PipelineOptions quickOptions() {
  mme::PipelineOptions o;
  o.identify.es.threads = 1;
  o.identify.generations = 60;
  return o;
}

// From the particles alone: the structure step chooses bonds, its hook runs before the
// identification starts, and the identification fits the chosen model's parameters.
TEST(IdentifyPipeline, StructureThenIdentificationInOrder) {
  const mme::Model truth = smallRandomObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 100, truth.frame_rate_hz);
  mme::PipelineOptions o = quickOptions();
  o.select_structure = true;
  std::vector<std::string> events;
  o.structure_chosen = [&](const mme::StructureResult& r) {
    events.push_back("structure " + std::to_string(r.model.bonds.size()));
  };
  o.identification_starts = [&](const mme::Model& m, const mme::Trajectory& t) {
    events.push_back("identify " + std::to_string(m.bonds.size()));
    EXPECT_EQ(t.numFrames(), data.numFrames());
  };
  const mme::PipelineResult r = mme::runPipeline(mme::test::particlesOnly(truth), data, o);
  ASSERT_TRUE(r.structure.has_value());
  ASSERT_EQ(events.size(), 2u);
  const std::string bonds = std::to_string(r.structure->model.bonds.size());
  EXPECT_EQ(events[0], "structure " + bonds);
  EXPECT_EQ(events[1], "identify " + bonds);
  EXPECT_FALSE(r.structure->model.bonds.empty());
  EXPECT_EQ(r.model.bonds.size(), r.structure->model.bonds.size());
  EXPECT_EQ(r.identified.parameters.size(), mme::freeParameters(r.structure->model).size());
  EXPECT_FALSE(r.sensor_muscles.has_value());
  EXPECT_TRUE(r.sensor_muscle_summary.empty());
  // The file gets the identified values.
  for (size_t k = 0; k < r.identified.parameters.size(); ++k)
    EXPECT_EQ(mme::paramOf(r.model, r.identified.parameters[k]).value, r.identified.values[k]);
}

// Sensor muscles on data too short for them: the passive model is the answer, the reason is
// warned about and noted in the file.
TEST(IdentifyPipeline, SensorMusclesTheDataCannotFeedLeaveThePassiveModel) {
  const mme::Model truth = mme::test::smallObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 40, truth.frame_rate_hz);
  mme::PipelineOptions o = quickOptions();
  o.sensor_muscles = mme::SensorMuscleOptions();
  std::vector<std::string> warnings;
  o.warn = [&](const std::string& line) { warnings.push_back(line); };
  const mme::PipelineResult r = mme::runPipeline(mme::test::withoutValues(truth), data, o);
  EXPECT_FALSE(r.sensor_muscles.has_value());
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("no sensor muscles ("), std::string::npos) << warnings[0];
  ASSERT_FALSE(r.notes.empty());
  EXPECT_EQ(r.notes.back().rfind("sensor muscles: none (", 0), 0u) << r.notes.back();
  EXPECT_EQ(r.model.bonds.size(), truth.bonds.size());
  EXPECT_EQ(mme::muscleTypeCount(r.model), 0);
}

// The model written starts where the data do: the first frame's positions, and the velocity
// that lands one simulated frame on the second frame, so that simulating it replays the data
// from their first frame.
TEST(IdentifyPipeline, TheModelStartsAtTheFirstFrame) {
  const mme::Model truth = mme::test::smallObject();
  const mme::Trajectory whole = mme::simulateTrajectory(truth, 60, truth.frame_rate_hz);
  const mme::Trajectory data = mme::sliceFrames(whole, 7, 40);
  const mme::PipelineResult r = mme::runPipeline(mme::test::withoutValues(truth), data, quickOptions());
  ASSERT_EQ(r.model.particles.size(), truth.particles.size());
  const mme::Trajectory replay = mme::simulateTrajectory(r.model, 2, truth.frame_rate_hz);
  double off_difference = 0.0;
  for (int i = 0; i < data.numMarkers(); ++i) {
    EXPECT_TRUE(r.model.particles[i].position_m.isApprox(data.position(0, i), 1e-12)) << i;
    EXPECT_LT((replay.position(1, i) - data.position(1, i)).norm(), 1e-12) << i;
    const Eigen::Vector3d difference = (data.position(1, i) - data.position(0, i)) * truth.frame_rate_hz;
    off_difference = std::max(off_difference, (r.model.particles[i].velocity_mps - difference).norm());
  }
  EXPECT_GT(off_difference, 0.0);  // not the plain frame difference, which misses by h^2 a
  mme::Model fixed_first = truth;
  fixed_first.particles[0].fixed = true;
  mme::startAtFrame(data, 3, &fixed_first);
  EXPECT_EQ(fixed_first.particles[0].position_m, truth.particles[0].position_m);  // held where it is
  EXPECT_TRUE(fixed_first.particles[1].position_m.isApprox(data.position(3, 1), 1e-12));
  EXPECT_THROW(mme::startAtFrame(data, data.numFrames(), &fixed_first), mme::InputError);
}

// A stiff scene at one substep per frame (paper_object at omega h = 2.5, the data from 20
// substeps with 0.1 mm noise) with the model's integrator kept: the output error's answer blows
// up over its segments. The file written holds the one-step answer, which predicts better, and
// its notes carry the warning; the output error's answer is nowhere in it.
TEST(IdentifyPipeline, TheFileHoldsTheBetterAnswerWhenTheOutputErrorBlowsUp) {
  const mme::test::StiffAtOneSubstep stiff;
  const mme::Trajectory& data = stiff.data;
  const mme::Model& search = stiff.search;
  mme::PipelineOptions o;
  o.identify.es.threads = 1;
  o.identify.estimate_std = false;
  o.identify.max_omega_h_per_substep = 0.0;
  const mme::PipelineResult r = mme::runPipeline(search, data, o);
  ASSERT_EQ(r.identified.estimator, mme::Estimator::kShortTerm);
  const std::string path = ::testing::TempDir() + "adoption_blow_up.yaml";
  const mme::IdentificationInfo info = mme::identificationInfo(r.identified, r.notes);
  mme::writeModelFile(path, r.model, &info);
  const mme::Model written = mme::loadModelFile(path);
  EXPECT_EQ(mme::getValues(written, r.identified.parameters), r.identified.values);
  EXPECT_EQ(written.substeps, 1);
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("the output error's answer is worse and not adopted"), std::string::npos);
  EXPECT_NE(text.str().find("method: es\n"), std::string::npos) << text.str().substr(0, 400);
  std::remove(path.c_str());
  EXPECT_TRUE(std::isfinite(mme::judgedPredictionRms_m(written, data)));  // it does not blow up
}

/// A controller the passive springs lack (test_helpers' muscleObject, its network in the
/// near-linear range sensor muscles represent: gain 100x, weights and bias / 100), every spring's
/// stiffness free in the passive model, 1 um of noise: the one-step residuals are far above the
/// noise, and sensor muscles learn the controller.
struct MissedController {
  mme::Model truth = mme::test::muscleObject();
  mme::Trajectory data;
  mme::Model passive;
  MissedController() {
    mme::BondType& type = truth.bond_types[truth.bondTypeIndex("m")];
    type.param(mme::kGain).value *= 100.0;
    for (mme::Param& p : type.network) p.value /= 100.0;
    data = mme::simulateTrajectory(truth, 240, truth.frame_rate_hz);
    mme::addGaussianNoise(&data, 1e-6, 7);
    passive = mme::removeMuscles(truth);
    for (mme::BondType& t : passive.bond_types) t.param(mme::kStiffness).free = true;
  }
};

mme::PipelineOptions withSensorMuscles() {
  mme::PipelineOptions o = quickOptions();
  o.identify.estimate_std = false;
  mme::SensorMuscleOptions sm;
  sm.sensors = 6;  // every pair of the 4 particles
  sm.neighbours = 3;
  sm.anchors_by_validation = false;
  o.sensor_muscles = sm;
  o.output_error_after_muscles = true;
  return o;
}

bool anyNote(const std::vector<std::string>& notes, const std::string& text) {
  for (const std::string& note : notes)
    if (note.find(text) != std::string::npos) return true;
  return false;
}

/// The output error ran: its judge's figures or a fit that was no answer.
bool outputErrorRan(const std::vector<std::string>& notes) {
  return anyNote(notes, "judged 10 frames ahead on the fitted frames") || anyNote(notes, "the output-error fit");
}

// With sensor muscles and a passive model that misses the motion, the output error waits for
// the muscles: kept, it never runs (the file's passive part is the search's answer); not kept
// (here: a layout too large to fit), it runs after them and is judged as it would have been.
TEST(IdentifyPipeline, TheOutputErrorRunsAfterTheMusclesOnlyWhenTheyAreNotKept) {
  const MissedController c;
  const mme::PipelineResult kept = mme::runPipeline(c.passive, c.data, withSensorMuscles());
  ASSERT_TRUE(kept.sensor_muscles.has_value());
  EXPECT_TRUE(kept.sensor_muscles->better_than_passive) << kept.sensor_muscles->not_kept_because;
  EXPECT_TRUE(kept.identified.output_error_deferred);
  EXPECT_EQ(kept.identified.estimator, mme::Estimator::kShortTerm);
  EXPECT_TRUE(anyNote(kept.notes, "the output error is deferred"));
  EXPECT_FALSE(outputErrorRan(kept.notes));
  EXPECT_GT(mme::muscleTypeCount(kept.model), 0);

  mme::PipelineOptions too_large = withSensorMuscles();
  too_large.sensor_muscles->max_unknowns = 1;
  std::vector<std::string> said;
  too_large.say = [&](const std::string& line) { said.push_back(line); };
  const mme::PipelineResult not_kept = mme::runPipeline(c.passive, c.data, too_large);
  EXPECT_FALSE(not_kept.sensor_muscles.has_value());
  EXPECT_FALSE(not_kept.identified.output_error_deferred);
  EXPECT_TRUE(anyNote(not_kept.notes, "the output error is deferred"));
  EXPECT_TRUE(outputErrorRan(not_kept.notes));
  EXPECT_TRUE(anyNote(said, "the deferred output error runs"));
  EXPECT_EQ(mme::muscleTypeCount(not_kept.model), 0);
  EXPECT_EQ(mme::getValues(not_kept.model, not_kept.identified.parameters), not_kept.identified.values);

  // Not deferred: the output error runs before the muscles, which are still fitted.
  mme::PipelineOptions before = withSensorMuscles();
  before.output_error_after_muscles = false;
  const mme::PipelineResult first = mme::runPipeline(c.passive, c.data, before);
  EXPECT_FALSE(first.identified.output_error_deferred);
  EXPECT_FALSE(anyNote(first.notes, "the output error is deferred"));
  EXPECT_TRUE(outputErrorRan(first.notes));
  EXPECT_TRUE(first.sensor_muscles.has_value());
}

// A passive scene at the markers' noise with sensor muscles asked for: nothing is deferred, the
// output error gives the answer as without muscles, and the muscles' gate skips them.
TEST(IdentifyPipeline, APassiveSceneAtTheNoiseStillGetsTheOutputErrorFirst) {
  const mme::Model truth = mme::test::smallObject();
  mme::Trajectory data = mme::simulateTrajectory(truth, 100, truth.frame_rate_hz);
  mme::addGaussianNoise(&data, 1e-4, 11);
  mme::PipelineOptions o = quickOptions();
  o.identify.estimate_std = false;
  const mme::PipelineResult plain = mme::runPipeline(mme::test::withoutValues(truth), data, o);
  o.sensor_muscles = mme::SensorMuscleOptions();
  o.output_error_after_muscles = true;
  const mme::PipelineResult with = mme::runPipeline(mme::test::withoutValues(truth), data, o);
  EXPECT_FALSE(with.identified.output_error_deferred);
  EXPECT_FALSE(anyNote(with.notes, "deferred"));
  EXPECT_EQ(with.identified.estimator, plain.identified.estimator);
  EXPECT_EQ(with.identified.values, plain.identified.values);
  ASSERT_TRUE(with.sensor_muscles.has_value());
  EXPECT_FALSE(with.sensor_muscles->better_than_passive);
}

// A raised cancel flag (Ctrl-C): the structure and the search end at once with their best so
// far, the passive model is handed on (to be written), and the sensor muscles do not start.
TEST(IdentifyPipeline, CancelEndsWithAPassiveModelAndNoMuscles) {
  const mme::Model truth = smallRandomObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 100, truth.frame_rate_hz);
  mme::PipelineOptions o = quickOptions();
  o.identify.generations = 100000;
  o.identify.patience_generations = 0;
  o.select_structure = true;
  o.sensor_muscles = mme::SensorMuscleOptions();
  std::atomic<bool> cancel{true};
  o.cancel = &cancel;
  int passive_calls = 0;
  o.passive_identified = [&](const mme::PipelineResult& r) {
    ++passive_calls;
    EXPECT_TRUE(r.cancelled);
    EXPECT_FALSE(r.model.bonds.empty());
  };
  const mme::PipelineResult r = mme::runPipeline(mme::test::particlesOnly(truth), data, o);
  EXPECT_TRUE(r.cancelled);
  EXPECT_EQ(passive_calls, 1);
  EXPECT_EQ(r.identified.stop, mme::IdentifyStop::kCancelled);
  EXPECT_STREQ(mme::identifyStopName(r.identified.stop), "interrupted");
  EXPECT_LE(r.identified.generations, 1);
  EXPECT_FALSE(r.sensor_muscles.has_value());
  for (double v : r.identified.values) EXPECT_TRUE(std::isfinite(v));
}

// The judge step matches the data's markers to the model's particles by name: markers in another
// order, a marker the model has not and a fixed particle without a marker (as the sensor
// muscles' anchors) give the figures of the same model on its own markers. The truth predicts
// its own noiseless motion where the guesses cannot; a judged frame past the data is refused.
TEST(IdentifyPipeline, TheJudgeMatchesMarkersByNameAndJudgesAfterTheHistory) {
  const mme::Model truth = mme::test::smallObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 90, truth.frame_rate_hz);
  const int judged_from = 60;
  const mme::PredictionReport plain = mme::evaluatePredictions(truth, data, {10}, 10.0, judged_from);
  std::vector<std::string> shuffled;
  for (const mme::Particle& p : truth.particles) shuffled.insert(shuffled.begin(), p.name);
  shuffled.push_back("stray");  // seen by nobody: occluded throughout
  const mme::Trajectory capture = mme::remapMarkers(data, shuffled, nullptr);
  mme::Model anchored = truth;
  mme::ParticleOptions anchor;
  anchor.name = "anchor_0";
  anchor.fixed = true;
  mme::addParticle(&anchored, Eigen::Vector3d(5, 5, 5), anchor);
  const mme::PredictionReport judged = mme::judgePredictions(anchored, capture, judged_from);
  ASSERT_EQ(judged.rows.size(), plain.rows.size());
  EXPECT_EQ(judged.starts, plain.starts);
  for (size_t k = 0; k < plain.rows.size(); ++k) {
    EXPECT_EQ(judged.rows[k].horizon, 10);
    EXPECT_EQ(judged.rows[k].predictor, plain.rows[k].predictor);
    EXPECT_EQ(judged.rows[k].samples, plain.rows[k].samples) << k;
    EXPECT_NEAR(judged.rows[k].rms_m, plain.rows[k].rms_m, 1e-12 + 1e-9 * plain.rows[k].rms_m) << k;
  }
  EXPECT_EQ(judged.rollout_bounded, plain.rollout_bounded);
  double model_m = NAN, constant_velocity_m = NAN;
  for (const mme::PredictionError& e : judged.rows) {
    if (e.predictor == mme::Predictor::kModel) model_m = e.rms_m;
    if (e.predictor == mme::Predictor::kConstantVelocity) constant_velocity_m = e.rms_m;
  }
  EXPECT_LT(model_m, 1e-3 * constant_velocity_m);
  EXPECT_THROW(mme::judgePredictions(truth, data, data.numFrames()), mme::InputError);
}

TEST(IdentifyPipeline, MusclesNeedASpringType) {
  mme::Model model;
  mme::test::addParticle(&model, Eigen::Vector3d(0, 0, 0));
  mme::test::addParticle(&model, Eigen::Vector3d(1, 0, 0));
  const mme::Trajectory data = mme::simulateTrajectory(model, 20, 100.0);
  EXPECT_THROW(mme::placeMuscles(model, data, mme::MusclePlacement{}), mme::InputError);
}

TEST(IdentifyPipeline, BadOptionsAreNamed) {
  mme::PipelineOptions o = quickOptions();
  EXPECT_EQ(mme::validateOptions(o), "");
  o.sensor_muscles = mme::SensorMuscleOptions();
  o.sensor_muscles->sensors = 0;
  EXPECT_NE(mme::validateOptions(o).find("sensor muscles"), std::string::npos);
  o.sensor_muscles.reset();
  o.muscles = mme::MusclePlacement{};
  o.muscles->hidden = -1;
  EXPECT_NE(mme::validateOptions(o).find("hidden"), std::string::npos);
  const mme::Model truth = mme::test::smallObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 40, truth.frame_rate_hz);
  EXPECT_THROW(mme::runPipeline(truth, data, o), mme::InputError);
}

// One block for offline and live results: method names, a std where finite, a flag where set.
TEST(ResultMetadata, OfflineAndLiveResultsSayTheSameThings) {
  mme::IdentifyResult r;
  r.parameters = {mme::ParamRef{}, mme::ParamRef{}};
  r.parameters[0].name = "s/stiffness";
  r.parameters[1].name = "s/damping";
  r.values = {10.0, 0.1};
  r.std_devs = {0.5, std::nan("")};
  r.flags = {mme::ParameterFlag::kNone, mme::ParameterFlag::kAtLowerBound};
  r.estimator = mme::Estimator::kOutputError;
  r.global_cost = 2e-6;
  r.frames = 90;
  r.generations = 12;
  const mme::IdentificationInfo offline = mme::identificationInfo(r, {"a note"});
  EXPECT_EQ(offline.method, "es+output_error");
  EXPECT_EQ(offline.std_names, std::vector<std::string>{"s/stiffness"});
  EXPECT_EQ(offline.std_values, std::vector<double>{0.5});
  ASSERT_EQ(offline.flags.size(), 1u);
  EXPECT_EQ(offline.flags[0].first, "s/damping");
  EXPECT_EQ(offline.flags[0].second, "at_lower_bound");
  EXPECT_EQ(offline.notes, std::vector<std::string>{"a note"});
  EXPECT_EQ(offline.frames, 90);

  mme::Estimate e;
  e.parameter_names = {"s/stiffness", "s/damping"};
  e.values = r.values;
  e.std_devs = r.std_devs;
  e.parameter_flags = r.flags;
  e.estimator = mme::Estimator::kShortTerm;
  e.window_frames = 90;
  e.generation = 12;
  const mme::IdentificationInfo live = mme::identificationInfo(e);
  EXPECT_EQ(live.method, "es-online");
  EXPECT_EQ(live.std_names, offline.std_names);
  EXPECT_EQ(live.flags, offline.flags);
  EXPECT_EQ(live.frames, 90);
  EXPECT_EQ(mme::methodName(mme::Estimator::kOutputError, true), "es-online+output_error");
}

}  // namespace

// Sensor muscles (real gait): muscles reading the pairs whose distance varies most,
// fitted by ridge least squares and judged on held-out frames. That they learn a controller the
// passive model lacks (the held-out open-loop error falls several-fold), that they stay silent
// where no controller acted, that gaps only drop equations, that the model they write survives
// its file, and that bad options get clear errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/structure/marker_model.h"
#include "motion_model_estimation/identification/muscles/muscle_placement.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "test_helpers.h"

namespace {

using mme::Model;

constexpr int kFrames = 300, kFitted = 240, kHorizon = 10;

/// A predictor's error kHorizon frames ahead on the frames from `first_start` (kFitted by
/// default), the data remapped to the model's particles (the sensor muscles' anchors are fixed
/// particles without markers).
double heldOutRms(const Model& model, const mme::Trajectory& data, bool* bounded = nullptr,
                  int first_start = kFitted, mme::Predictor predictor = mme::Predictor::kModel) {
  std::vector<std::string> names;
  for (const mme::Particle& p : model.particles) names.push_back(p.name);
  const mme::PredictionReport report = mme::evaluatePredictions(
      model, mme::remapMarkers(data, names, nullptr), {kHorizon}, 10.0, first_start);
  if (bounded) *bounded = report.rollout_bounded;
  return mme::test::predictionRms(report, kHorizon, predictor);
}

/// muscleObject with its controller in the near-linear range: gain 100x, network weights and
/// bias / 100, so |y| stays below ~0.02 and gain tanh(y) is gain y within 0.02 %: the same
/// linear part as muscleObject's controller, a law sensor muscles can represent.
Model linearMuscleObject() {
  Model m = mme::test::muscleObject();
  mme::BondType& type = m.bond_types[m.bondTypeIndex("m")];
  type.param(mme::kGain).value *= 100.0;
  for (mme::Param& p : type.network) p.value /= 100.0;
  return m;
}

/// Data of linearMuscleObject and its passive model (the muscle made a plain spring).
struct LinearControllerCase {
  Model truth = linearMuscleObject();
  mme::Trajectory data = mme::simulateTrajectory(truth, kFrames, truth.frame_rate_hz);
  Model passive = mme::removeMuscles(truth);
};

mme::SensorMuscleOptions smallOptions() {
  mme::SensorMuscleOptions o;
  o.sensors = 6;  // every pair of this 4-particle object
  o.neighbours = 3;
  // One layout per fit (anchors on): AnchorsAreKeptWhereTheyPredictTheValidationBetter tests
  // the choice between the two.
  o.anchors_by_validation = false;
  return o;
}

TEST(SensorMuscles, LearnTheControllerThePassiveModelLacks) {
  // The muscle is driven by the elongations and speeds of two other bonds; the passive model
  // (the muscle made a plain spring with the same spring part) moves otherwise.
  const LinearControllerCase setup;
  const Model& passive = setup.passive;
  const mme::Trajectory& data = setup.data;
  mme::SensorMuscleOptions shown = smallOptions();
  shown.progress = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
  const mme::SensorMuscleResult r =
      mme::addSensorMuscles(passive, mme::sliceFrames(data, 0, kFitted), shown);
  EXPECT_EQ(r.sensors, 6);
  EXPECT_GT(r.muscles, 4);
  EXPECT_EQ(r.unknowns, static_cast<size_t>(r.muscles * (2 * 6 + 3)));
  EXPECT_TRUE(r.better_than_passive);
  EXPECT_EQ(r.not_kept_because, "");
  const mme::SensorMuscleOptions o = smallOptions();
  // The one-step candidates, then the rounds from one to 2 + rollout_lower_ridges of them
  // (RolloutEquationsUndoTheNoiseBias checks which).
  const size_t plain = o.windows_frames.size() * o.ridges.size();
  ASSERT_GE(r.candidates.size(), plain + o.rollout_rounds);
  ASSERT_LE(r.candidates.size(), plain + (2 + o.rollout_lower_ridges) * o.rollout_rounds);
  ASSERT_EQ((r.candidates.size() - plain) % o.rollout_rounds, 0u);
  ASSERT_GE(r.chosen, 0);
  ASSERT_LT(r.chosen, static_cast<int>(r.candidates.size()));
  const mme::SensorMuscleCandidate& chosen = r.candidates[r.chosen];
  // The chosen fit's error, lower when an activation time constant helped it.
  if (r.activation_time_s > 0.0) {
    EXPECT_LT(r.validation_rms_m, chosen.validation_rms_m);
  } else {
    EXPECT_EQ(r.validation_rms_m, chosen.validation_rms_m);
  }
  EXPECT_EQ(r.ridge, chosen.ridge);
  EXPECT_EQ(r.window_frames, chosen.window_frames);
  EXPECT_TRUE(chosen.bounded);
  for (const mme::SensorMuscleCandidate& c : r.candidates) {  // none bounded and better
    if (c.bounded) {
      EXPECT_GE(c.validation_rms_m, chosen.validation_rms_m);
    }
  }
  EXPECT_LT(r.validation_rms_m, r.passive_rms_m);
  bool bounded = false;
  const double muscles_rms = heldOutRms(r.model, data, &bounded);
  const double passive_rms = heldOutRms(passive, data);
  std::printf("held out, %d frames ahead: passive %.3g m, sensor muscles %.3g m (ridge %g, %d "
              "muscles)\n", kHorizon, passive_rms, muscles_rms, r.ridge, r.muscles);
  EXPECT_TRUE(bounded);
  EXPECT_LT(muscles_rms, 0.2 * passive_rms);
  // Every added parameter is fixed: identified here, not left to the search.
  EXPECT_EQ(mme::freeParameters(r.model).size(), mme::freeParameters(passive).size());
  EXPECT_EQ(mme::muscleTypeCount(r.model), r.selected_muscles);
  // The same input gives the same model.
  const mme::SensorMuscleResult again =
      mme::addSensorMuscles(passive, mme::sliceFrames(data, 0, kFitted), smallOptions());
  EXPECT_EQ(mme::modelToYaml(again.model), mme::modelToYaml(r.model));
}

/// The particle pairs of `model`'s bonds whose type's name starts with `prefix`.
std::vector<std::pair<int, int>> pairsOf(const Model& model, const std::string& prefix) {
  std::vector<std::pair<int, int>> pairs;
  for (const mme::Bond& bond : model.bonds)
    if (model.bond_types[bond.type].name.rfind(prefix, 0) == 0)
      pairs.emplace_back(std::min(bond.particles[0], bond.particles[1]), std::max(bond.particles[0], bond.particles[1]));
  return pairs;
}

TEST(SensorMuscles, GroupedSelectionKeepsTheMuscleThatActsAndDropsMostOthers) {
  // One controller acts: the muscle between the fixed particle 0 and particle 3, reading the
  // bonds 0-1 and 1-2. The layout puts 15 muscles (every pair, and 9 to the anchors) reading 6
  // sensors; the selection keeps the muscle on 0-3 and drops most of the others.
  // With 0.1 mm of marker noise: noiseless data support every group that lowers the residual.
  LinearControllerCase setup;
  mme::addGaussianNoise(&setup.data, 1e-4, 5);
  const mme::Trajectory fitted = mme::sliceFrames(setup.data, 0, kFitted);
  mme::SensorMuscleOptions o = smallOptions();
  o.select_groups = true;
  o.progress = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
  const mme::SensorMuscleResult r = mme::addSensorMuscles(setup.passive, fitted, o);
  mme::SensorMuscleOptions off = smallOptions();  // the default: no selection
  const mme::SensorMuscleResult r0 = mme::addSensorMuscles(setup.passive, fitted, off);
  EXPECT_EQ(r0.selected_muscles, r0.muscles);
  EXPECT_EQ(r0.selected_sensors, r0.sensors);
  EXPECT_EQ(mme::muscleTypeCount(r0.model), r0.muscles);
  ASSERT_TRUE(r.better_than_passive) << r.not_kept_because;
  const std::vector<std::pair<int, int>> kept = pairsOf(r.model, "muscle_");
  EXPECT_EQ(static_cast<int>(kept.size()), r.selected_muscles);
  EXPECT_EQ(static_cast<int>(pairsOf(r.model, "sensor_").size()), r.selected_sensors);
  EXPECT_NE(std::find(kept.begin(), kept.end(), std::make_pair(0, 3)), kept.end());
  EXPECT_LE(static_cast<int>(kept.size()) - 1, (r.muscles - 1) / 2);  // most of the other 14 dropped
  EXPECT_LT(r.selected_parameters, r.unknowns);
  const double selected_rms = heldOutRms(r.model, setup.data), full_rms = heldOutRms(r0.model, setup.data);
  std::printf("held out, %d frames ahead: %d of %d muscles, %d of %d sensors, %zu of %zu parameters on %zu "
              "samples: %.3g m; without the selection %.3g m\n", kHorizon, r.selected_muscles, r.muscles,
              r.selected_sensors, r.sensors, r.selected_parameters, r.unknowns, r.rows, selected_rms, full_rms);
  EXPECT_LT(selected_rms, 1.1 * full_rms);
}

TEST(SensorMuscles, StaySilentWhereNoControllerActed) {
  // Data of the passive model itself: the muscles have nothing to explain, and predict as it
  // (the search forced: the gain gate would not start it).
  const Model passive = mme::removeMuscles(mme::test::muscleObject());
  const mme::Trajectory data = mme::simulateTrajectory(passive, kFrames, passive.frame_rate_hz);
  mme::SensorMuscleOptions forced = smallOptions();
  forced.skip_without_gain = false;
  const mme::SensorMuscleResult r = mme::addSensorMuscles(passive, mme::sliceFrames(data, 0, kFitted), forced);
  EXPECT_LT(r.residual_rms_m, 1e-9);
  // Nothing to gain: not kept, and the reason says so.
  EXPECT_FALSE(r.better_than_passive);
  EXPECT_NE(r.not_kept_because.find("is not below the passive model's"), std::string::npos)
      << r.not_kept_because;
  EXPECT_LT(heldOutRms(r.model, data), 1e-6);
  EXPECT_LT(heldOutRms(passive, data), 1e-9);
}

TEST(SensorMuscles, TheSearchDoesNotRunWhereThePassiveModelPredictsAtTheNoise) {
  // The passive model's own data, noiseless: it predicts the validation frames at round-off, so
  // the search is not started and the result says why; with the same data and marker noise its
  // one-step residual is the noise, and again nothing is fitted.
  const Model passive = mme::removeMuscles(mme::test::muscleObject());
  const mme::Trajectory data = mme::sliceFrames(mme::simulateTrajectory(passive, kFrames, passive.frame_rate_hz),
                                                0, kFitted);
  const mme::SensorMuscleResult r = mme::addSensorMuscles(passive, data, smallOptions());
  EXPECT_TRUE(r.skipped);
  EXPECT_FALSE(r.better_than_passive);
  EXPECT_TRUE(r.candidates.empty());
  EXPECT_EQ(r.unknowns, 0u);
  EXPECT_EQ(mme::modelToYaml(r.model), mme::modelToYaml(passive));
  EXPECT_NE(r.not_kept_because.find("within the"), std::string::npos) << r.not_kept_because;
  EXPECT_LT(r.passive_rms_m, 1e-9);

  mme::Trajectory noisy = data;
  mme::addGaussianNoise(&noisy, 2e-4, 7);
  const mme::SensorMuscleResult n = mme::addSensorMuscles(passive, noisy, smallOptions());
  EXPECT_TRUE(n.skipped);
  EXPECT_TRUE(n.candidates.empty());
  EXPECT_GT(n.noise_m, 1e-4);
  EXPECT_LT(n.noise_m, 4e-4);
  EXPECT_NE(n.not_kept_because.find("noise"), std::string::npos) << n.not_kept_because;
}

TEST(SensorMuscles, TheGateLetsASceneWithAControllerThrough) {
  // Where a controller acted, its forces are far above the noise: the search runs and keeps
  // the muscles, the gate's noise estimate reported beside them.
  const LinearControllerCase c;
  mme::Trajectory noisy = mme::sliceFrames(c.data, 0, kFitted);
  mme::addGaussianNoise(&noisy, 1e-5, 3);
  const mme::SensorMuscleResult r = mme::addSensorMuscles(c.passive, noisy, smallOptions());
  EXPECT_FALSE(r.skipped);
  EXPECT_FALSE(r.candidates.empty());
  EXPECT_TRUE(r.better_than_passive) << r.not_kept_because;
  EXPECT_GT(r.noise_m, 0.0);
  EXPECT_GT(r.unknowns, 0u);
  EXPECT_GT(r.rows, r.unknowns);
}

// Threads share out the equations' sums by block rows, each row's terms in the same order: the
// candidates, the choice and the written muscles are the same bit for bit with 1 and 3 threads
// (the one-step equations, the rollout rounds and the final refit all accumulate so).
TEST(SensorMuscles, ThreadsGiveTheSameFitBitForBit) {
  const LinearControllerCase c;
  mme::Trajectory noisy = mme::sliceFrames(c.data, 0, kFitted);
  mme::addGaussianNoise(&noisy, 1e-5, 3);
  mme::SensorMuscleOptions o = smallOptions();
  const mme::SensorMuscleResult one = mme::addSensorMuscles(c.passive, noisy, o);
  o.threads = 3;
  const mme::SensorMuscleResult three = mme::addSensorMuscles(c.passive, noisy, o);
  ASSERT_FALSE(one.candidates.empty());
  ASSERT_GT(one.candidates.back().rollout_rounds, 0);  // the rounds ran
  ASSERT_EQ(one.candidates.size(), three.candidates.size());
  for (size_t k = 0; k < one.candidates.size(); ++k) {
    EXPECT_EQ(one.candidates[k].validation_rms_m, three.candidates[k].validation_rms_m) << k;
    EXPECT_EQ(one.candidates[k].bounded, three.candidates[k].bounded) << k;
  }
  EXPECT_EQ(one.chosen, three.chosen);
  EXPECT_EQ(one.validation_rms_m, three.validation_rms_m);
  EXPECT_EQ(one.residual_rms_m, three.residual_rms_m);
  EXPECT_EQ(mme::modelToYaml(one.model), mme::modelToYaml(three.model));
  o.threads = 0;
  EXPECT_THROW(mme::addSensorMuscles(c.passive, noisy, o), mme::InputError);
}

/// Each muscle's own stiffness and damping in `model`: how many are negative.
int negativeOwnSprings(const Model& model) {
  int negative = 0;
  for (const mme::BondType& type : model.bond_types) {
    if (type.kind != mme::BondKind::kMuscle) continue;
    negative += type.param(mme::kStiffness).value < 0.0;
    negative += type.param(mme::kDamping).value < 0.0;
  }
  return negative;
}

TEST(SensorMuscles, OwnStiffnessAndDampingStayNonNegative) {
  // Left free, the least-squares fit gives some muscles a negative stiffness or damping (a
  // closed loop that can leave the data); by default those are held at 0 and the rest refitted.
  const LinearControllerCase setup;
  const Model& passive = setup.passive;
  const mme::Trajectory& data = setup.data;
  mme::SensorMuscleOptions free_signs = smallOptions();
  free_signs.nonnegative_own_spring = false;
  const mme::SensorMuscleResult unconstrained =
      mme::addSensorMuscles(passive, mme::sliceFrames(data, 0, kFitted), free_signs);
  ASSERT_GT(negativeOwnSprings(unconstrained.model), 0) << "the case no longer exercises the constraint";
  const mme::SensorMuscleResult r =
      mme::addSensorMuscles(passive, mme::sliceFrames(data, 0, kFitted), smallOptions());
  EXPECT_EQ(negativeOwnSprings(r.model), 0);
  EXPECT_TRUE(r.better_than_passive);
  bool bounded = false;
  EXPECT_LT(heldOutRms(r.model, data, &bounded), 0.2 * heldOutRms(passive, data));
  EXPECT_TRUE(bounded);
}

TEST(SensorMuscles, WindowedEquationsLearnTheControllerToo) {
  // Equations summed over 2 x 3 - 1 frames with triangle weights: the same law, the same fit.
  const LinearControllerCase setup;
  const Model& passive = setup.passive;
  const mme::Trajectory& data = setup.data;
  mme::SensorMuscleOptions o = smallOptions();
  o.windows_frames = {3};
  const mme::SensorMuscleResult r = mme::addSensorMuscles(passive, mme::sliceFrames(data, 0, kFitted), o);
  EXPECT_EQ(r.window_frames, 3);
  EXPECT_TRUE(r.better_than_passive);
  EXPECT_LT(heldOutRms(r.model, data), 0.2 * heldOutRms(passive, data));
}

TEST(SensorMuscles, GapsDropEquationsNotTheFit) {
  const LinearControllerCase setup;
  const Model& passive = setup.passive;
  mme::Trajectory data = setup.data;
  const mme::SensorMuscleResult whole =
      mme::addSensorMuscles(passive, mme::sliceFrames(data, 0, kFitted), smallOptions());
  // Particle 2 hidden in frames 50..69: its rows, its partners' rows and (it is in every sensor
  // pair of this small object or not) the frames a sensor misses drop out.
  for (int t = 50; t < 70; ++t) data.occluded[t * data.numMarkers() + 2] = 1;
  const mme::SensorMuscleResult gappy =
      mme::addSensorMuscles(passive, mme::sliceFrames(data, 0, kFitted), smallOptions());
  EXPECT_LT(gappy.rows, whole.rows);
  EXPECT_GT(gappy.rows, whole.rows / 2);
  EXPECT_TRUE(gappy.better_than_passive);
  EXPECT_LT(heldOutRms(gappy.model, data), 0.2 * heldOutRms(passive, data));
}

TEST(SensorMuscles, RolloutsStartWhereAMarkerIsHidden) {
  // Particle 2 hidden in frames 0..29 and 50..69: the rollouts from those frames start with it
  // placed by its neighbours' rigid motion (from the nearest frame it was seen, later ones too),
  // so the rounds run from as many starts as on the whole data. A fifth particle tied to 1, 2
  // and 3 gives particle 2 three free neighbours (the fixed one carries no body's motion).
  Model truth = linearMuscleObject();
  mme::test::addParticle(&truth, Eigen::Vector3d(0.15, 0.05, -0.2), 0.5, false, "",
                         Eigen::Vector3d(0.0, 0.1, 0.0));
  for (int other : {1, 2, 3}) mme::test::addBond(&truth, truth.bondTypeIndex("s"), 4, other);
  const Model passive = mme::removeMuscles(truth);
  mme::Trajectory data = mme::simulateTrajectory(truth, kFitted, truth.frame_rate_hz);
  mme::SensorMuscleOptions o = smallOptions();
  o.rollout_rounds = 1;
  const mme::SensorMuscleResult whole = mme::addSensorMuscles(passive, data, o);
  for (int t = 0; t < 70; ++t)
    if (t < 30 || t >= 50) data.occluded[t * data.numMarkers() + 2] = 1;
  const mme::SensorMuscleResult gappy = mme::addSensorMuscles(passive, data, o);
  auto rounds = [](const mme::SensorMuscleResult& r) {
    int starts = 0;
    for (const mme::SensorMuscleCandidate& c : r.candidates)
      if (c.rollout_rounds > 0) {
        EXPECT_GT(c.rollout_starts, 0);
        starts = c.rollout_starts;
      }
    return starts;
  };
  const int whole_starts = rounds(whole);
  ASSERT_GT(whole_starts, 20);
  EXPECT_EQ(rounds(gappy), whole_starts);
  EXPECT_LT(gappy.rows, whole.rows);  // its own rows still drop where it is hidden
}

/// linearMuscleObject's motion with a push on particle 3 along the vertical (a muscle to a fixed
/// point 30 m below, its network reading the same bonds): a force of fixed direction in the
/// world, which muscles between the body's particles can only make by turning with the body.
/// The data have the passive model's markers (not the fixed point).
struct PushCase {
  Model passive = mme::removeMuscles(linearMuscleObject());
  mme::Trajectory data;
  /// `stiffness`: the push's own [N/m] (a pull back to the fixed point besides the push).
  explicit PushCase(double stiffness = 0.0) {
    Model truth = linearMuscleObject();
    const int world = mme::test::addParticle(&truth, Eigen::Vector3d(0.05, 0.1, -30.0), 1.0, true);
    const int push = mme::test::addMuscleType(&truth, "push", stiffness, 29.75, 0.0, 400.0, 2, 0,
                                              {0.5, -0.4, 0.03, -0.02, 0.0});
    mme::test::addMuscle(&truth, push, 3, world, {0, 1});
    std::vector<std::string> names;
    for (const mme::Particle& p : passive.particles) names.push_back(p.name);
    data = mme::remapMarkers(mme::simulateTrajectory(truth, kFrames, truth.frame_rate_hz), names, nullptr);
  }
};

TEST(SensorMuscles, AnchorMusclesLearnAPushAlongAWorldAxis) {
  // With the anchors (on by default) every particle has a muscle along x, y and z.
  const PushCase setup;
  const Model& passive = setup.passive;
  const mme::Trajectory& data = setup.data;
  const mme::Trajectory fitted = mme::sliceFrames(data, 0, kFitted);

  mme::SensorMuscleOptions without = smallOptions();
  without.anchors = false;
  const mme::SensorMuscleResult r0 = mme::addSensorMuscles(passive, fitted, without);
  const mme::SensorMuscleOptions o = smallOptions();
  ASSERT_TRUE(o.anchors) << "anchors are the default";
  const mme::SensorMuscleResult r = mme::addSensorMuscles(passive, fitted, o);
  // Three anchors, fixed, far along x, y and z from the data's centre; a muscle from each of the
  // 3 free particles to each.
  ASSERT_EQ(r.model.particles.size(), passive.particles.size() + 3);
  EXPECT_EQ(r.muscles, r0.muscles + 9);
  double lo = 1e300, hi = -1e300;
  for (int t = 0; t < kFitted; ++t)
    for (int i = 1; i < 4; ++i) {
      lo = std::min(lo, fitted.position(t, i).minCoeff());
      hi = std::max(hi, fitted.position(t, i).maxCoeff());
    }
  for (int k = 0; k < 3; ++k) {
    const mme::Particle& anchor = r.model.particles[passive.particles.size() + k];
    EXPECT_EQ(anchor.name, std::string("anchor_") + "xyz"[k]);
    EXPECT_TRUE(anchor.fixed);
    EXPECT_GT(anchor.position_m[k], hi + 10.0 * (hi - lo)) << anchor.name;
  }
  bool bounded = false;
  const double with_anchors = heldOutRms(r.model, data, &bounded);
  const double body_only = heldOutRms(r0.model, data);
  std::printf("push along the vertical, held out %d frames ahead: passive %.3g m, sensor muscles "
              "without anchors %.3g m, with %.3g m\n", kHorizon, heldOutRms(passive, data), body_only,
              with_anchors);
  EXPECT_TRUE(bounded);
  EXPECT_LT(with_anchors, 0.5 * body_only);
}

/// The largest own stiffness of a muscle to an anchor [N/m], and how many there are.
double anchorMuscleStiffness(const Model& m, int* count) {
  double largest = 0.0;
  *count = 0;
  auto anchor = [&m](int i) { return m.particles[i].name.rfind("anchor_", 0) == 0; };
  for (const mme::Bond& b : m.bonds)
    if (m.bond_types[b.type].kind == mme::BondKind::kMuscle && (anchor(b.particles[0]) || anchor(b.particles[1]))) {
      ++*count;
      largest = std::max(largest, std::abs(m.bond_types[b.type].value(mme::kStiffness)));
    }
  return largest;
}

TEST(SensorMuscles, AutoFitsAnAnchorMusclesStiffnessOnABodyTiedToTheWorldNotOnOneThatTravels) {
  // An anchor muscle's own stiffness pulls the body back to where it was recorded. The data here
  // are made with such a pull (PushCase's push with a stiffness of its own, to a fixed point 30 m
  // below) on a body the model ties to the world (its fixed particle): kAuto fits it. The same
  // motion carried across several body sizes (every marker drifting at one speed, as a walk
  // across a room) by a free body: kAuto holds it at 0 (the default fits it anyway).
  const PushCase setup(400.0);
  const mme::Trajectory fitted = mme::sliceFrames(setup.data, 0, kFitted);
  ASSERT_EQ(smallOptions().anchor_stiffness, mme::AnchorStiffness::kFitted) << "the default";
  mme::SensorMuscleOptions o = smallOptions();
  o.anchor_stiffness = mme::AnchorStiffness::kAuto;
  int count = 0;
  const mme::SensorMuscleResult in_place = mme::addSensorMuscles(setup.passive, fitted, o);
  std::printf("tied: the body travels %.3g body sizes, the largest anchor muscle stiffness %g N/m\n",
              in_place.body_travel, anchorMuscleStiffness(in_place.model, &count));
  ASSERT_TRUE(setup.passive.particles[0].fixed);
  EXPECT_TRUE(in_place.anchor_stiffness);
  EXPECT_GT(anchorMuscleStiffness(in_place.model, &count), 1.0);
  EXPECT_EQ(count, 9) << "3 free particles x 3 anchors";
  mme::SensorMuscleOptions none = o;
  none.anchor_stiffness = mme::AnchorStiffness::kNone;
  const mme::SensorMuscleResult held = mme::addSensorMuscles(setup.passive, fitted, none);
  EXPECT_FALSE(held.anchor_stiffness);
  EXPECT_EQ(anchorMuscleStiffness(held.model, &count), 0.0);
  EXPECT_EQ(count, 9);

  Model free_body = setup.passive;
  free_body.particles[0].fixed = false;
  mme::Trajectory travelling = fitted;
  double lo = 1e300, hi = -1e300;
  for (int i = 0; i < 4; ++i) {
    lo = std::min(lo, fitted.position(0, i).minCoeff());
    hi = std::max(hi, fitted.position(0, i).maxCoeff());
  }
  const double speed = 3.0 * std::sqrt(3.0) * (hi - lo) / kFitted;  // [m/frame] along x
  for (int t = 0; t < kFitted; ++t)
    for (int i = 0; i < 4; ++i) travelling.position(t, i).x() += speed * t;
  const mme::SensorMuscleResult walking = mme::addSensorMuscles(free_body, travelling, o);
  std::printf("travelling: %.3g body sizes, the largest anchor muscle stiffness %g N/m\n",
              walking.body_travel, anchorMuscleStiffness(walking.model, &count));
  EXPECT_GE(walking.body_travel, o.travel_body_sizes);
  EXPECT_FALSE(walking.anchor_stiffness);
  EXPECT_EQ(anchorMuscleStiffness(walking.model, &count), 0.0);
  EXPECT_EQ(count, 12) << "4 free particles x 3 anchors";
  // The default fits it anyway.
  const mme::SensorMuscleResult by_default = mme::addSensorMuscles(free_body, travelling, smallOptions());
  EXPECT_TRUE(by_default.anchor_stiffness);
  EXPECT_GT(anchorMuscleStiffness(by_default.model, &count), 1.0);
}

TEST(SensorMuscles, BodyTravelTellsAWalkAcrossTheRoomFromOneInPlace) {
  // The real recordings (bench_paper fig5's first 300 frames): the walks across the room travel,
  // the arm on its fixed shoulder and the treadmill walk (subject01) do not.
  struct Case {
    const char* file;
    bool travels;
  };
  for (const Case& c : {Case{"motion_capture_walk.trc", true}, Case{"Sample01_Eb015pi.c3d", true},
                        Case{"Sample26_Walking_Hybrid_1_1.c3d", true}, Case{"subject01_walk1.trc", false},
                        Case{"arm26_elbow_flex.trc", false}}) {
    mme::Trajectory data = mme::readTrajectoryFile(std::string(MME_TEST_DATA_DIR) + "/real/" + c.file);
    data = mme::sliceFrames(data, 0, std::min(data.numFrames(), 300));
    const double travel = mme::bodyTravel(mme::markerModel(data), data);
    std::printf("%s: %.3g body sizes\n", c.file, travel);
    EXPECT_EQ(travel >= mme::SensorMuscleOptions().travel_body_sizes, c.travels) << c.file << ": " << travel;
  }
  // A fixed particle does not count; nothing seen: 0.
  const Model object = mme::test::muscleObject();
  mme::Trajectory data = mme::simulateTrajectory(object, 50, object.frame_rate_hz);
  const double travel = mme::bodyTravel(object, data);
  for (int t = 0; t < data.numFrames(); ++t) data.position(t, 0) += Eigen::Vector3d(100.0 * t, 0.0, 0.0);
  ASSERT_TRUE(object.particles[0].fixed);
  EXPECT_EQ(mme::bodyTravel(object, data), travel);
  std::fill(data.occluded.begin(), data.occluded.end(), 1);
  EXPECT_EQ(mme::bodyTravel(object, data), 0.0);
}

TEST(SensorMuscles, AnActivationStateCarriesTheArmsDriveOnArm26) {
  // OpenSim's arm26 elbow flexion (a real recording's file, simulated there: no marker noise):
  // the arm is moved by muscle excitations in time, so its acceleration is not a function of
  // its posture alone and the constant-acceleration guess beats posture-driven muscles. With an
  // activation time constant, a start's activations come from the data's last frames and carry
  // the drive on. The passive model as bench_paper fig5 makes it: structure selection, then 100
  // generations; the last 20 % held out.
  const mme::Trajectory all =
      mme::readTrajectoryFile(std::string(MME_TEST_DATA_DIR) + "/real/arm26_elbow_flex.trc");
  const mme::HeldOutSplit split = mme::splitHeldOut(all, 0.2, "arm26");
  mme::StructureOptions so;
  so.identify = mme::identifyOptionsFor(mme::Preset::kDefault);
  so.identify.es.threads = 1;
  so.identify.estimate_std = false;
  Model passive = mme::selectStructure(mme::markerModel(split.fit), split.fit, so).model;
  mme::IdentifyOptions io = mme::identifyOptionsFor(mme::Preset::kDefault);
  io.generations = 100;
  io.patience_generations = 0;
  io.es.threads = 1;
  io.es.seed = 1;
  io.estimate_std = false;
  io.cost = mme::CostChoice::kShortTerm;
  const mme::IdentifyResult ir = mme::identifyModel(passive, split.fit, io);
  mme::setValues(passive, ir.parameters, ir.values);

  mme::SensorMuscleOptions instant;
  instant.activation_times_frames.clear();
  const mme::SensorMuscleResult r0 = mme::addSensorMuscles(passive, split.fit, instant);
  EXPECT_EQ(r0.activation_time_s, 0.0);
  const mme::SensorMuscleResult r = mme::addSensorMuscles(passive, split.fit);
  ASSERT_TRUE(r.better_than_passive);
  EXPECT_GT(r.activation_time_s, 0.0);
  EXPECT_LT(r.validation_rms_m, r.candidates[r.chosen].validation_rms_m);
  // Every muscle type carries it, fixed, and the model file keeps it.
  int muscle_types = 0;
  for (const mme::BondType& type : r.model.bond_types)
    if (type.kind == mme::BondKind::kMuscle) {
      ++muscle_types;
      EXPECT_EQ(type.value(mme::kActivationTime), r.activation_time_s) << type.name;
      EXPECT_FALSE(type.param(mme::kActivationTime).free);
    }
  EXPECT_EQ(muscle_types, r.selected_muscles);
  const Model loaded = mme::loadModelString(mme::modelToYaml(r.model), "arm26.yaml");
  auto held = [&](const Model& model, mme::Predictor predictor, bool* bounded) {
    return heldOutRms(model, split.held, bounded, split.held_start, predictor);
  };
  bool bounded = false;
  const double with_state = held(r.model, mme::Predictor::kModel, &bounded);
  const double posture_only = held(r0.model, mme::Predictor::kModel, nullptr);
  const double acceleration_guess = held(r.model, mme::Predictor::kConstantAcceleration, nullptr);
  EXPECT_EQ(held(loaded, mme::Predictor::kModel, nullptr), with_state);
  std::printf("arm26, held out %d frames ahead: sensor muscles %.3g mm, with an activation time "
              "constant of %g s %.3g mm, constant acceleration %.3g mm\n", kHorizon, 1e3 * posture_only,
              r.activation_time_s, 1e3 * with_state, 1e3 * acceleration_guess);
  EXPECT_TRUE(bounded);
  EXPECT_LT(with_state, 0.6 * posture_only);
  EXPECT_LT(with_state, acceleration_guess);
}

TEST(SensorMuscles, AnchorsAreKeptWhereTheyPredictTheValidationBetter) {
  // By default both layouts are fitted and the one predicting the validation frames better is
  // kept: the push along a world axis needs the anchors; on the controller between the body's
  // particles, with 0.3 mm of marker noise, their 9 extra muscles fit noise.
  struct Case {
    const char* name;
    Model passive;
    mme::Trajectory fitted, data;
    bool expect_anchors;
  };
  const PushCase push;
  LinearControllerCase noisy;
  mme::addGaussianNoise(&noisy.data, 3e-4, 7);
  const Case cases[] = {
      {"push", push.passive, mme::sliceFrames(push.data, 0, kFitted), push.data, true},
      {"noisy controller", noisy.passive, mme::sliceFrames(noisy.data, 0, kFitted), noisy.data, false}};
  for (const Case& c : cases) {
    mme::SensorMuscleOptions choose = smallOptions();
    choose.anchors_by_validation = true;
    mme::SensorMuscleOptions with = smallOptions(), without = smallOptions();
    without.anchors = false;
    const mme::SensorMuscleResult r = mme::addSensorMuscles(c.passive, c.fitted, choose);
    const mme::SensorMuscleResult rw = mme::addSensorMuscles(c.passive, c.fitted, with);
    const mme::SensorMuscleResult r0 = mme::addSensorMuscles(c.passive, c.fitted, without);
    EXPECT_TRUE(rw.anchors);
    EXPECT_FALSE(r0.anchors);
    std::printf("%s: validation with anchors %.3g m, without %.3g m; held out with %.3g m, without "
                "%.3g m\n", c.name, rw.validation_rms_m, r0.validation_rms_m, heldOutRms(rw.model, c.data),
                heldOutRms(r0.model, c.data));
    EXPECT_EQ(r.anchors, c.expect_anchors) << c.name;
    // The kept one is that layout's own fit, to the byte.
    EXPECT_EQ(mme::modelToYaml(r.model), mme::modelToYaml(r.anchors ? rw.model : r0.model)) << c.name;
    // And it predicts the held-out frames better than the other.
    EXPECT_LT(heldOutRms(r.model, c.data), heldOutRms(r.anchors ? r0.model : rw.model, c.data)) << c.name;
  }
}

TEST(SensorMuscles, TheWrittenModelStaysBoundedFromAnywhereInTheData) {
  // With 0.3 mm of marker noise and the smallest ridges among the candidates, some fits leave
  // the data over long rollouts. The written model is run open loop from 8 frames spread over
  // the fitted data, 10x the frames a held-out test of the same share would judge (validation
  // / (1 - validation_fraction), plus 2): every free particle stays within 10 extents of
  // the centre of the validation frames' box, as a held-out test bounds its rollout by its own
  // frames (what the final refit is checked for before it is kept).
  LinearControllerCase setup;
  mme::addGaussianNoise(&setup.data, 3e-4, 7);
  const mme::Trajectory fitted = mme::sliceFrames(setup.data, 0, kFitted);
  mme::SensorMuscleOptions o = smallOptions();
  o.ridges = {1e-6, 1e-4, 1e-2, 1.0};
  const mme::SensorMuscleResult r = mme::addSensorMuscles(setup.passive, fitted, o);
  ASSERT_TRUE(r.better_than_passive);
  EXPECT_TRUE(r.candidates[r.chosen].bounded);
  const int validation = kFitted - static_cast<int>(std::floor((1.0 - o.validation_fraction) * kFitted));
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (int t = kFitted - validation; t < kFitted; ++t)
    for (int i = 1; i < 4; ++i) {
      lo = lo.cwiseMin(fitted.position(t, i));
      hi = hi.cwiseMax(fitted.position(t, i));
    }
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  const double limit_m = 10.0 * (hi - lo).norm();
  const int rollout =
      static_cast<int>(std::ceil(10.0 * (validation / (1.0 - o.validation_fraction) + 2.0)));
  mme::Simulator sim(r.model);
  for (int k = 1; k <= 8; ++k) {
    const int t = 1 + (kFitted - 2) * k / 8;
    mme::State s;
    s.x_m.assign(r.model.particles.size(), Eigen::Vector3d::Zero());
    s.v_mps = s.x_m;
    for (size_t i = 0; i < r.model.particles.size(); ++i)
      s.x_m[i] = r.model.particles[i].position_m;
    for (int i = 0; i < 4; ++i) {
      s.x_m[i] = fitted.position(t, i);
      if (!r.model.particles[i].fixed) s.v_mps[i] = (fitted.position(t, i) - fitted.position(t - 1, i)) * fitted.frame_rate_hz;
    }
    for (int step = 0; step < rollout; ++step) {
      sim.stepFrame(&s, 1.0 / fitted.frame_rate_hz);
      for (int i = 1; i < 4; ++i)
        ASSERT_LT((s.x_m[i] - centre).norm(), limit_m) << "from frame " << t << ", step " << step;
    }
  }
}

TEST(SensorMuscles, ATimeLimitCutsTheSearchNotTheFit) {
  // max_time_s spent at once: the first ridge alone is judged (one candidate always is), no
  // rollout round, activation time constant or second layout is started, and the model is still
  // built, checked and written as without a limit. A limit never reached changes nothing.
  const LinearControllerCase setup;
  const mme::Trajectory fitted = mme::sliceFrames(setup.data, 0, kFitted);
  mme::SensorMuscleOptions o = smallOptions();
  o.anchors_by_validation = true;
  const mme::SensorMuscleResult full = mme::addSensorMuscles(setup.passive, fitted, o);
  EXPECT_FALSE(full.stopped_by_time);
  EXPECT_GT(full.wall_time_s, 0.0);
  const size_t plain = o.windows_frames.size() * o.ridges.size();
  ASSERT_GT(full.candidates.size(), plain);  // rounds were run
  o.max_time_s = 1e9;
  const mme::SensorMuscleResult roomy = mme::addSensorMuscles(setup.passive, fitted, o);
  EXPECT_FALSE(roomy.stopped_by_time);
  EXPECT_EQ(mme::modelToYaml(roomy.model), mme::modelToYaml(full.model));
  std::vector<std::string> lines;
  o.max_time_s = 1e-9;
  o.progress = [&](const std::string& line) { lines.push_back(line); };
  const mme::SensorMuscleResult cut = mme::addSensorMuscles(setup.passive, fitted, o);
  EXPECT_TRUE(cut.stopped_by_time);
  ASSERT_EQ(cut.candidates.size(), 1u);
  EXPECT_EQ(cut.candidates[0].ridge, o.ridges[0]);
  EXPECT_EQ(cut.candidates[0].rollout_rounds, 0);
  EXPECT_EQ(cut.chosen, 0);
  EXPECT_TRUE(cut.anchors);  // the layout fitted first; the one without anchors never started
  EXPECT_EQ(cut.activation_time_s, 0.0);
  EXPECT_EQ(mme::muscleTypeCount(cut.model), cut.selected_muscles);
  EXPECT_EQ(mme::freeParameters(cut.model).size(), mme::freeParameters(setup.passive).size());
  const auto said = [&](const std::string& what) {
    return std::any_of(lines.begin(), lines.end(),
                       [&](const std::string& l) { return l.find(what) != std::string::npos; });
  };
  EXPECT_TRUE(said("time limit of 1e-09 s spent"));
  EXPECT_TRUE(said("no further ridge"));
  EXPECT_TRUE(said("no fit without anchors"));
  EXPECT_EQ(std::count(lines.begin(), lines.end(), std::string("sensor muscles: without anchors")), 0);
  // Kept or not by the same rule as without a limit: the first ridge's own figures.
  if (cut.better_than_passive) {
    EXPECT_LT(cut.validation_rms_m, cut.passive_rms_m);
    EXPECT_TRUE(cut.candidates[0].bounded);
  } else {
    EXPECT_NE(cut.not_kept_because, "");
  }
  std::printf("time limit spent at once: 1 candidate (ridge %g, %.3g m held out in validation, "
              "kept %d) against %zu (%.3g m) without\n", cut.ridge, cut.validation_rms_m,
              cut.better_than_passive ? 1 : 0, full.candidates.size(), full.validation_rms_m);
}

TEST(SensorMuscles, TheWrittenModelMovesAsTheFittedOne) {
  const Model truth = mme::test::muscleObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, kFrames, truth.frame_rate_hz);
  const mme::SensorMuscleResult r = mme::addSensorMuscles(
      mme::removeMuscles(truth), mme::sliceFrames(data, 0, kFitted), smallOptions());
  const Model loaded = mme::loadModelString(mme::modelToYaml(r.model), "sensor_muscles.yaml");
  const mme::Trajectory a = mme::simulateTrajectory(r.model, 100, r.model.frame_rate_hz);
  const mme::Trajectory b = mme::simulateTrajectory(loaded, 100, loaded.frame_rate_hz);
  double worst = 0.0;
  for (size_t k = 0; k < a.positions_m.size(); ++k)
    worst = std::max(worst, (a.positions_m[k] - b.positions_m[k]).norm());
  EXPECT_LT(worst, 1e-9);
}

TEST(SensorMuscles, ABodyTooLargeReadsFewerSensors) {
  // With the anchors, the 4-particle object has 15 muscles: 6 sensors are 15 x 15 = 225
  // unknowns. Within 120, every muscle reads the 2 most varying pairs (15 x 7 = 105): the layout
  // shrinks instead of failing, and says so.
  const LinearControllerCase setup;
  mme::SensorMuscleOptions o = smallOptions();
  o.max_unknowns = 120;
  std::vector<std::string> lines;
  o.progress = [&](const std::string& line) { lines.push_back(line); };
  const mme::SensorMuscleResult r = mme::addSensorMuscles(setup.passive, mme::sliceFrames(setup.data, 0, kFitted), o);
  EXPECT_EQ(r.sensors, 2);
  EXPECT_EQ(r.muscles, 15);
  EXPECT_EQ(r.unknowns, 105u);
  int sensor_bonds = 0;
  for (const mme::Bond& bond : r.model.bonds) sensor_bonds += bond.name.rfind("sensor_", 0) == 0;
  EXPECT_EQ(sensor_bonds, 2);
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(std::find(lines.begin(), lines.end(),
                      "sensor muscles: 15 muscles reading 6 sensors are 225 unknowns, more than 120: 2 sensors"),
            lines.end());
  // The sensors kept are the most varying pairs: the first two of the full layout's.
  const mme::SensorMuscleResult full =
      mme::addSensorMuscles(setup.passive, mme::sliceFrames(setup.data, 0, kFitted), smallOptions());
  std::vector<std::string> kept, first;
  for (const mme::Bond& bond : r.model.bonds)
    if (bond.name.rfind("sensor_", 0) == 0) kept.push_back(bond.name);
  for (const mme::Bond& bond : full.model.bonds)
    if (bond.name.rfind("sensor_", 0) == 0 && first.size() < 2) first.push_back(bond.name);
  EXPECT_EQ(kept, first);
}

TEST(SensorMuscles, BadInputGetsClearErrors) {
  const Model truth = mme::test::muscleObject();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 100, truth.frame_rate_hz);
  const Model passive = mme::removeMuscles(truth);
  auto message = [&](const Model& m, const mme::Trajectory& d, const mme::SensorMuscleOptions& o) {
    try {
      mme::addSensorMuscles(m, d, o);
    } catch (const mme::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  mme::SensorMuscleOptions o = smallOptions();
  o.sensors = 0;
  EXPECT_NE(message(passive, data, o).find("sensors must be 1..16"), std::string::npos);
  o = smallOptions();
  o.windows_frames = {1, 0};
  EXPECT_NE(message(passive, data, o).find("window"), std::string::npos);
  o = smallOptions();
  o.ridges = {1e-3, -1.0};
  EXPECT_NE(message(passive, data, o).find("ridge"), std::string::npos);
  o = smallOptions();
  o.rollout_rounds = -1;
  EXPECT_NE(message(passive, data, o).find("rollout rounds must be 0..20"), std::string::npos);
  o = smallOptions();
  o.rollout_lower_ridges = -1;
  EXPECT_NE(message(passive, data, o).find("rollout_lower_ridges must be 0..20"), std::string::npos);
  o = smallOptions();
  o.rollout_stride_frames = 0;
  EXPECT_NE(message(passive, data, o).find("rollout stride"), std::string::npos);
  o = smallOptions();
  o.rollout_correction_frames = std::nan("");
  EXPECT_NE(message(passive, data, o).find("rollout correction"), std::string::npos);
  for (double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    o = smallOptions();
    o.activation_times_frames = {10.0, bad};
    EXPECT_NE(message(passive, data, o).find("activation time constants must be finite numbers >= 0"),
              std::string::npos) << bad;
  }
  for (double bad : {0.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    o = smallOptions();
    o.travel_body_sizes = bad;
    EXPECT_NE(message(passive, data, o).find("travel_body_sizes must be a finite number > 0"),
              std::string::npos) << bad;
  }
  EXPECT_NE(message(passive, mme::sliceFrames(data, 0, 12), smallOptions()).find("too few"),
            std::string::npos);
  Model unvalued = passive;
  mme::Param& k = unvalued.bond_types[0].param(mme::kStiffness);
  k.free = true;
  k.has_value = false;
  EXPECT_NE(message(unvalued, data, smallOptions()).find("has no value"), std::string::npos);
  // Too many unknowns (max_unknowns): refused before anything is allocated.
  Model crowd;
  crowd.frame_rate_hz = 100;
  for (int i = 0; i < 60; ++i)
    mme::test::addParticle(&crowd, Eigen::Vector3d(0.1 * (i % 8), 0.1 * (i / 8), 0.02 * (i % 3)));
  const mme::Trajectory crowd_data = mme::simulateTrajectory(crowd, 80, crowd.frame_rate_hz);
  o = smallOptions();
  o.sensors = 16;
  o.neighbours = 59;  // 1770 muscles + 180 to the anchors: 9750 unknowns even with one sensor
  o.max_unknowns = 8000;
  o.skip_without_gain = false;  // motionless data: the gain gate would not start the search
  const std::string crowded = message(crowd, crowd_data, o);
  EXPECT_NE(crowded.find("1950 muscles reading 1 sensor(s) are 9750 unknowns, more than 8000"),
            std::string::npos) << crowded;
  for (size_t bad : {size_t{0}, size_t{14001}}) {
    o = smallOptions();
    o.max_unknowns = bad;
    EXPECT_NE(message(passive, data, o).find("max_unknowns must be 1..14000"), std::string::npos) << bad;
  }
  for (double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    o = smallOptions();
    o.max_time_s = bad;
    EXPECT_NE(message(passive, data, o).find("time limit must be a finite number >= 0 s"), std::string::npos) << bad;
  }
  mme::Trajectory renamed = data;
  renamed.marker_names[1] = "elsewhere";
  EXPECT_NE(message(passive, renamed, smallOptions()).find("'elsewhere'"), std::string::npos);
}

}  // namespace

TEST(SensorMuscles, RolloutEquationsUndoTheNoiseBias) {
  // With 0.3 mm of marker noise the one-step equations are biased (noise in the regressors and,
  // over h^2, in the accelerations); the rollout rounds add the equations of the model's own
  // predictions, and the held-out error 10 frames ahead falls (measured: 20.6 -> 9.8 mm).
  LinearControllerCase setup;
  mme::addGaussianNoise(&setup.data, 3e-4, 7);
  const mme::Trajectory fitted = mme::sliceFrames(setup.data, 0, kFitted);
  mme::SensorMuscleOptions one_step = smallOptions();
  one_step.rollout_rounds = 0;
  const mme::SensorMuscleResult r0 = mme::addSensorMuscles(setup.passive, fitted, one_step);
  const mme::SensorMuscleOptions o = smallOptions();
  ASSERT_GT(o.rollout_rounds, 0) << "rollout rounds are the default";
  const mme::SensorMuscleResult r = mme::addSensorMuscles(setup.passive, fitted, o);
  // The one-step candidates first, as without rounds, then one per round from the best one's
  // ridge, when it differs from the lowest error's (its rollout unbounded), and from the next
  // rollout_lower_ridges ridges below the best's (finite errors, nearest first).
  const size_t plain = o.windows_frames.size() * o.ridges.size();
  size_t best_plain = 0, lowest = 0;  // best: bounded first, then the lowest error
  for (size_t c = 0; c < plain; ++c) {
    EXPECT_EQ(r.candidates[c].rollout_rounds, 0);
    EXPECT_EQ(r.candidates[c].validation_rms_m, r0.candidates[c].validation_rms_m);
    const mme::SensorMuscleCandidate &x = r.candidates[c], &b = r.candidates[best_plain];
    if ((x.bounded && !b.bounded) || (x.bounded == b.bounded && x.validation_rms_m < b.validation_rms_m))
      best_plain = c;
    if (x.validation_rms_m < r.candidates[lowest].validation_rms_m) lowest = c;
  }
  std::vector<double> start_ridges = {r.candidates[best_plain].ridge};
  if (lowest != best_plain) start_ridges.push_back(r.candidates[lowest].ridge);
  std::vector<double> lower;
  for (size_t c = 0; c < plain; ++c)
    if (r.candidates[c].ridge < r.candidates[best_plain].ridge && std::isfinite(r.candidates[c].validation_rms_m))
      lower.push_back(r.candidates[c].ridge);
  std::sort(lower.rbegin(), lower.rend());
  for (size_t k = 0; k < lower.size() && k < static_cast<size_t>(o.rollout_lower_ridges); ++k)
    if (std::find(start_ridges.begin(), start_ridges.end(), lower[k]) == start_ridges.end())
      start_ridges.push_back(lower[k]);
  ASSERT_GT(start_ridges.size(), 2u) << "the best one-step ridge is not the smallest here";
  ASSERT_EQ(r.candidates.size(), plain + start_ridges.size() * o.rollout_rounds);
  for (size_t start = 0; start < start_ridges.size(); ++start)
    for (int round = 1; round <= o.rollout_rounds; ++round) {
      const mme::SensorMuscleCandidate& c = r.candidates[plain + start * o.rollout_rounds + round - 1];
      EXPECT_EQ(c.rollout_rounds, round);
      EXPECT_EQ(c.ridge, start_ridges[start]);
    }
  ASSERT_GE(r.chosen, static_cast<int>(plain)) << "no round predicted the validation frames better";
  for (const mme::SensorMuscleCandidate& c : r.candidates) {
    if (c.bounded) {
      EXPECT_GE(c.validation_rms_m, r.validation_rms_m);
    }
  }
  bool bounded = false;
  const double with_rounds = heldOutRms(r.model, setup.data, &bounded);
  const double without = heldOutRms(r0.model, setup.data);
  std::printf("0.3 mm noise, held out %d frames ahead: one-step %.3g m, %d rollout round(s) %.3g "
              "m, passive %.3g m\n", kHorizon, without, r.candidates[r.chosen].rollout_rounds,
              with_rounds, heldOutRms(setup.passive, setup.data));
  EXPECT_TRUE(bounded);
  EXPECT_LT(with_rounds, 0.7 * without);
}

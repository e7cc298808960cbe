// The prediction judge: the true model predicts its own motion exactly at every horizon and the
// model-free guesses do not; each guess is exact on the motion it assumes; occluded targets do
// not count and a start tolerates short gaps; a model that blows up is caught by the rollout;
// bad horizons are refused; a marker unseen at a start is placed by its neighbours' rigid motion,
// from earlier frames only; the rollout bound is the free particles' box over the chosen frames.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/muscles/muscle_placement.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"
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

/// Five markers on a rigid body turning at 2 rad/s about a tilted axis while it drifts, 100 Hz;
/// body points b (p0 off the others' plane), or with p1..p3 on one line when `line`.
mme::Trajectory rigidMotion(int frames, bool line = false) {
  const std::vector<Eigen::Vector3d> b =
      line ? std::vector<Eigen::Vector3d>{{0.1, 0.2, 0.3}, {0, 0, 0}, {0.1, 0, 0}, {0.2, 0, 0}, {0.3, 0, 0}}
           : std::vector<Eigen::Vector3d>{{0.1, 0.2, 0.3}, {0, 0, 0}, {0.2, 0, 0}, {0, 0.15, 0}, {0.05, 0.05, -0.1}};
  mme::Trajectory d;
  for (size_t i = 0; i < b.size(); ++i) d.marker_names.push_back("p" + std::to_string(i));
  d.frame_rate_hz = 100.0;
  d.resize(frames);
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, 0.5, 0.8).normalized();
  for (int t = 0; t < frames; ++t) {
    const double time = t / 100.0;
    const Eigen::Matrix3d r = Eigen::AngleAxisd(2.0 * time, axis).toRotationMatrix();
    const Eigen::Vector3d c(0.1 * time, -0.2 * time + 0.3 * time * time, 1.0);
    for (size_t i = 0; i < b.size(); ++i) {
      d.position(t, static_cast<int>(i)) = r * b[i] + c;
      d.occluded[t * b.size() + i] = 0;
    }
  }
  return d;
}

mme::Model freeParticles(int n) {
  mme::Model m;
  m.frame_rate_hz = 100.0;
  for (int c = 0; c < 3; ++c) m.gravity_mps2[c] = mme::test::valueParam(0.0);
  for (int i = 0; i < n; ++i) mme::test::addParticle(&m, Eigen::Vector3d::Zero());
  return m;
}

/// `data` with marker 0 hidden in frames [from, to), its hidden positions garbage.
mme::Trajectory hideFirstMarker(mme::Trajectory data, int from, int to) {
  for (int t = from; t < to; ++t) {
    data.occluded[t * data.numMarkers()] = 1;
    data.position(t, 0) = Eigen::Vector3d(7, 7, 7);
  }
  return data;
}

// A marker hidden for 20 frames is placed exactly where the rigid body carries it, from earlier
// frames only; fewer than 3 neighbours seen, or neighbours on one line, place nothing.
TEST(PredictionError, AnUnseenMarkerIsPlacedByItsNeighboursRigidMotion) {
  const mme::Model model = freeParticles(5);
  const mme::Trajectory truth = rigidMotion(60);
  const mme::Trajectory data = hideFirstMarker(truth, 20, 40);
  const mme::Observations obs = mme::prepareObservations(model, data);
  for (int t = 20; t < 40; ++t) {
    Eigen::Vector3d p;
    ASSERT_TRUE(mme::fillFromNeighbours(obs, model, t, 0, &p)) << t;
    EXPECT_LT((p - truth.position(t, 0)).norm(), 1e-12) << t;
  }
  // Only frames up to t: garbage after frame 25 changes nothing there.
  mme::Trajectory later = data;
  for (int t = 26; t < 60; ++t)
    for (int i = 0; i < 5; ++i) later.position(t, i) = Eigen::Vector3d(t, -i, 3);
  Eigen::Vector3d a, b;
  ASSERT_TRUE(mme::fillFromNeighbours(obs, model, 25, 0, &a));
  ASSERT_TRUE(mme::fillFromNeighbours(mme::prepareObservations(model, later), model, 25, 0, &b));
  EXPECT_EQ(a, b);
  // Two neighbours seen at frame 30: nothing to carry it.
  mme::Trajectory sparse = data;
  for (int i : {3, 4}) sparse.occluded[30 * 5 + i] = 1;
  Eigen::Vector3d none;
  EXPECT_FALSE(mme::fillFromNeighbours(mme::prepareObservations(model, sparse), model, 30, 0, &none));
  // Neighbours on one line: the turn about that line is unknown.
  mme::Trajectory line = rigidMotion(60, true);
  for (int t = 20; t < 40; ++t) line.occluded[t * 5] = 1;
  for (int t = 10; t < 40; ++t) line.occluded[t * 5 + 4] = 1;
  EXPECT_FALSE(mme::fillFromNeighbours(mme::prepareObservations(model, line), model, 30, 0, &none));
}

// A marker hidden from the recording's first frame has no earlier picture: placed only when
// later frames may be read (fitting), then exactly, from the nearest frame where it is seen.
TEST(PredictionError, AMarkerHiddenFromTheStartIsPlacedFromLaterFrames) {
  const mme::Model model = freeParticles(5);
  const mme::Trajectory truth = rigidMotion(60);
  const mme::Trajectory data = hideFirstMarker(truth, 0, 20);
  const mme::Observations obs = mme::prepareObservations(model, data);
  for (int t = 0; t < 20; ++t) {
    Eigen::Vector3d p;
    EXPECT_FALSE(mme::fillFromNeighbours(obs, model, t, 0, &p)) << t;
    ASSERT_TRUE(mme::fillFromNeighbours(obs, model, t, 0, &p, true)) << t;
    EXPECT_LT((p - truth.position(t, 0)).norm(), 1e-12) << t;
  }
  // The nearest picture first (an earlier one at equal distance): hidden in frames 30..40, its
  // pictures after frame 40 moved 1 m off the body, frame 35 is placed from frame 29, exactly,
  // and frame 39 from frame 41, 1 m off.
  mme::Trajectory both = data;
  for (int t = 30; t <= 40; ++t) both.occluded[t * 5] = 1;
  for (int t = 41; t < 60; ++t) both.position(t, 0) += Eigen::Vector3d(1, 0, 0);
  const mme::Observations both_obs = mme::prepareObservations(model, both);
  Eigen::Vector3d p;
  ASSERT_TRUE(mme::fillFromNeighbours(both_obs, model, 35, 0, &p, true));
  EXPECT_LT((p - truth.position(35, 0)).norm(), 1e-12);
  ASSERT_TRUE(mme::fillFromNeighbours(both_obs, model, 39, 0, &p, true));
  EXPECT_NEAR((p - truth.position(39, 0)).norm(), 1.0, 1e-9);
}

// The judge starts where a marker is hidden (its start state filled; it is not scored from
// there): as many starts as without the gap. The fill is what the model simulates from: a stiff
// spring from the hidden marker at its exact (rigid) length pulls on nothing, so the bonded model
// predicts exactly as the free particles do; a misplaced start would pull.
TEST(PredictionError, StartsWhereAMarkerIsHiddenFillItFromItsNeighbours) {
  const mme::Model model = freeParticles(5);
  const mme::Trajectory motion = rigidMotion(60);
  const mme::PredictionReport all = mme::evaluatePredictions(model, motion, {1, 5});
  EXPECT_EQ(all.filled, 0);
  mme::Trajectory data = motion;
  for (int t = 20; t < 40; ++t) data.occluded[t * 5] = 1;
  const mme::PredictionReport gap = mme::evaluatePredictions(model, data, {1, 5});
  EXPECT_EQ(gap.starts, all.starts);
  EXPECT_EQ(gap.filled, 21);  // unseen at 20..39, and at 40 unseen in the 3 frames before

  mme::Model bonded = model;
  const double length = (motion.position(0, 0) - motion.position(0, 1)).norm();
  const int type = mme::test::addType(&bonded, "s", mme::BondKind::kSpring,
                                      {{mme::kStiffness, 1000.0}, {mme::kRestLength, length}}, false);
  mme::test::addBond(&bonded, type, 0, 1);
  // One frame ahead: the spring's force at the start alone moves particle 1 (further ahead the
  // free particles' straight lines stretch it whatever the start).
  const mme::PredictionReport pulled = mme::evaluatePredictions(bonded, data, {1});
  EXPECT_EQ(pulled.starts, gap.starts);
  const double free_rms = predictionRms(gap, 1, Predictor::kModel);
  EXPECT_GT(free_rms, 1e-6);  // the turn is not constant velocity
  EXPECT_NEAR(predictionRms(pulled, 1, Predictor::kModel), free_rms, 1e-6 * free_rms);
}

// Held-out frames judged after the fitted ones: a marker hidden through the whole held-out part
// is placed from the frames before first_start, which start no prediction themselves; on the
// held-out frames alone (marker 0 never seen) nothing could start.
TEST(PredictionError, FramesBeforeTheFirstStartAreHistoryOnly) {
  const mme::Model model = freeParticles(5);
  mme::Trajectory data = rigidMotion(60);
  for (int t = 30; t < 60; ++t) data.occluded[t * 5] = 1;
  const mme::PredictionReport r = mme::evaluatePredictions(model, data, {1}, 10.0, 30);
  EXPECT_EQ(r.starts, 29);  // frames 30..58
  EXPECT_EQ(r.filled, 29);
  EXPECT_EQ(r.rollout_frames, 320);  // 10x the judged frames 28..59
  EXPECT_TRUE(r.rollout_bounded);
  EXPECT_THROW(mme::evaluatePredictions(model, mme::sliceFrames(data, 30, 30), {1}), mme::InputError);
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

// The bound a rollout must stay in: the free particles' box over the chosen frames (a fixed
// particle far away neither widens it nor leaves it), 10 box diagonals around its centre, and
// nothing non-finite.
TEST(PredictionError, TheRolloutBoundIsTheFreeParticlesBoxOverTheChosenFrames) {
  mme::Model model = freeParticles(2);
  mme::test::addParticle(&model, Eigen::Vector3d(1e3, 0.0, 0.0), 1.0, true);
  mme::Trajectory data;
  data.marker_names = {model.particles[0].name, model.particles[1].name, model.particles[2].name};
  data.frame_rate_hz = 100.0;
  data.resize(4);
  data.occluded.assign(data.occluded.size(), 0);
  for (int t = 0; t < 4; ++t) {
    data.position(t, 0) = Eigen::Vector3d(0.0, 0.0, 0.0);
    data.position(t, 1) = Eigen::Vector3d(0.3, 0.4, 0.0) * (t < 2 ? 1.0 : 2.0);
    data.position(t, 2) = Eigen::Vector3d(1e3, 0.0, 0.0);
  }
  const mme::Observations obs = mme::prepareObservations(model, data);
  const mme::RolloutBound early = mme::RolloutBound::of(model, obs, 0, 2);
  EXPECT_NEAR(early.extent_m, 0.5, 1e-12);
  EXPECT_TRUE(early.centre_m.isApprox(Eigen::Vector3d(0.15, 0.2, 0.0)));
  EXPECT_NEAR(mme::RolloutBound::of(model, obs, 0, 4).extent_m, 1.0, 1e-12);
  std::vector<Eigen::Vector3d> x = {early.centre_m + Eigen::Vector3d(4.9, 0.0, 0.0), early.centre_m,
                                    Eigen::Vector3d(1e3, 0.0, 0.0)};
  EXPECT_TRUE(early.holds(model, x));
  x[0].x() += 0.2;  // 5.1 m from the centre: beyond 10 x 0.5 m
  EXPECT_FALSE(early.holds(model, x));
  x[0] = early.centre_m;
  x[1].z() = std::nan("");
  EXPECT_FALSE(early.holds(model, x));
  // Nothing seen: a 1 mm box at the origin.
  data.occluded.assign(data.occluded.size(), 1);
  const mme::RolloutBound none = mme::RolloutBound::of(model, mme::prepareObservations(model, data), 0, 4);
  EXPECT_EQ(none.extent_m, 1e-3);
  EXPECT_TRUE(none.centre_m.isZero());
}

/// muscleObject's body pushed down on particle 3 by a muscle to a fixed point far below whose
/// activation is constant (gain x tanh(bias)); `activation_time_s` on the push.
mme::Model pushedObject(double bias, double activation_time_s) {
  mme::Model m = mme::removeMuscles(mme::test::muscleObject());
  const int below = mme::test::addParticle(&m, Eigen::Vector3d(0.05, 0.1, -30.0), 1.0, true);
  const int push = mme::test::addMuscleType(&m, "push", 0.0, 29.75, 0.0, 400.0, 0, 0, {bias});
  if (activation_time_s > 0.0)
    m.bond_types[push].param(mme::kActivationTime) = mme::test::valueParam(activation_time_s);
  mme::test::addMuscle(&m, push, 3, below, {});
  return m;
}

// A muscle with activation dynamics starts where the data put it: pushed by 2 N the model does
// not know of, a model whose push muscle is silent but has a time constant reads the push from
// each start's last three frames and carries it on; the same model without one cannot.
TEST(PredictionError, AStartsActivationsComeFromTheDatasLastFrames) {
  const mme::Model truth = pushedObject(0.005, 0.0);  // 400 tanh(0.005) = 2.0 N
  const mme::Trajectory data = mme::simulateTrajectory(truth, 120, 100.0);
  const mme::PredictionReport with = mme::evaluatePredictions(pushedObject(0.0, 10.0), data, {10});
  const mme::PredictionReport without = mme::evaluatePredictions(pushedObject(0.0, 0.0), data, {10});
  const double rms_with = predictionRms(with, 10, Predictor::kModel);
  const double rms_without = predictionRms(without, 10, Predictor::kModel);
  std::printf("an unknown 2 N push, 10 frames ahead: silent muscle %.3g m, with an activation state "
              "%.3g m, constant acceleration %.3g m\n", rms_without, rms_with,
              predictionRms(with, 10, Predictor::kConstantAcceleration));
  EXPECT_GT(rms_without, 1e-3);
  EXPECT_LT(rms_with, 0.02 * rms_without);
  EXPECT_LT(rms_with, 0.1 * predictionRms(with, 10, Predictor::kConstantAcceleration));
  EXPECT_TRUE(with.rollout_bounded);
}

}  // namespace

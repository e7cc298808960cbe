// makeVisualisationSnapshot: the latest frame, a one-step prediction and a long reconstruction
// that reproduce the motion under the true model (and not under a wrong one), trails, the
// spring bonds with strain or local-cost values, the status text, occlusion, short windows.
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/live/visualisation_snapshot.h"

namespace {

const char* kModel = R"(
frame_rate_hz: 100
gravity: [0, 0, 0]
particles:
  - {name: a, mass: 1.0, position: [0, 0, 0], velocity: [0.3, 0, 0]}
  - {name: b, mass: 0.8, position: [0.12, 0, 0], velocity: [-0.2, 0.1, 0]}
  - {name: c, mass: 1.2, position: [0.05, 0.1, 0.02], velocity: [-0.12, -0.07, 0]}
bond_types:
  - {name: s1, kind: spring, stiffness: {value: 20, free: true, min: 2, max: 200}, rest_length: 0.1}
  - {name: f, kind: flexion, stiffness: 0.01, rest_angle: 2.0}
bonds:
  - {type: s1, particles: [a, b]}
  - {type: s1, particles: [b, c]}
  - {type: s1, particles: [a, c]}
  - {type: f, particles: [a, b, c]}
)";

struct Fixture : ::testing::Test {
  mme::Model model = mme::loadModelString(kModel, "test");
  mme::Trajectory truth = mme::simulateTrajectory(model, 60, 100.0);

  /// Frames [first, first + count) of the truth, as the estimator's window would hold them.
  mme::Trajectory window(int first, int count) const { return mme::sliceFrames(truth, first, count); }
  static mme::Estimate estimate() {
    mme::Estimate e;
    e.valid = true;
    e.generation = 7;
    e.global_cost = 1.2345e-5;
    e.stable = true;
    return e;
  }
};

TEST_F(Fixture, TheTrueModelPredictsAndReconstructsTheLatestFrame) {
  const mme::Trajectory w = window(10, 30);
  const auto s = mme::makeVisualisationSnapshot(model, w, estimate(), mme::BondColouring::kStrain);
  ASSERT_TRUE(s);
  EXPECT_DOUBLE_EQ(s->stamp_s, truth.times_s[39]);
  ASSERT_EQ(s->observed.size(), 3u);
  ASSERT_EQ(s->predicted.size(), 3u);
  ASSERT_EQ(s->reconstructed.size(), 3u);
  ASSERT_EQ(s->reconstruction_trails.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(s->observed[i], truth.position(39, i));
    EXPECT_EQ(s->observed_occluded[i], 0);
    EXPECT_LT((s->predicted[i] - truth.position(39, i)).norm(), 1e-12) << i;
    // 28 frames integrated from the window start land on the observed motion too.
    EXPECT_LT((s->reconstructed[i] - truth.position(39, i)).norm(), 1e-10) << i;
    // The trail: from the window's second frame (the rollout's start) to the latest frame.
    ASSERT_EQ(s->reconstruction_trails[i].size(), 29u);
    EXPECT_LT((s->reconstruction_trails[i].front() - truth.position(11, i)).norm(), 1e-15);
    EXPECT_LT((s->reconstruction_trails[i][14] - truth.position(25, i)).norm(), 1e-10);
    EXPECT_EQ(s->reconstruction_trails[i].back(), s->reconstructed[i]);
  }
}

TEST_F(Fixture, AWrongModelPredictsSomethingElse) {
  mme::Model wrong = model;
  wrong.bond_types[0].param(mme::kStiffness).value *= 3.0;
  const auto s = mme::makeVisualisationSnapshot(wrong, window(10, 30), estimate(),
                                                mme::BondColouring::kStrain);
  ASSERT_TRUE(s);
  double predicted_error = 0, reconstructed_error = 0;
  for (int i = 0; i < 3; ++i) {
    predicted_error += (s->predicted[i] - truth.position(39, i)).norm();
    reconstructed_error += (s->reconstructed[i] - truth.position(39, i)).norm();
  }
  EXPECT_GT(predicted_error, 1e-7);
  EXPECT_GT(reconstructed_error, 100 * predicted_error);  // errors grow over 28 frames
}

TEST_F(Fixture, SpringBondsCarryTheirStrainInTheLatestFrame) {
  const auto s = mme::makeVisualisationSnapshot(model, window(0, 20), estimate(),
                                                mme::BondColouring::kStrain);
  ASSERT_TRUE(s);
  // The flexion bond is not drawn: three springs in model order.
  const std::vector<std::pair<int, int>> bonds = {{0, 1}, {1, 2}, {0, 2}};
  EXPECT_EQ(s->bonds, bonds);
  ASSERT_EQ(s->bond_values.size(), 3u);
  for (size_t b = 0; b < bonds.size(); ++b) {
    const double length =
        (truth.position(19, bonds[b].second) - truth.position(19, bonds[b].first)).norm();
    EXPECT_NEAR(s->bond_values[b], length / 0.1 - 1.0, 1e-12) << b;
  }
  EXPECT_EQ(s->bond_value_lo, -0.1);
  EXPECT_EQ(s->bond_value_hi, 0.1);
  // At the start a and b are 0.12 apart (stretched: positive), by frame 19 they have come
  // together (compressed: negative).
  const auto start = mme::makeVisualisationSnapshot(model, window(0, 2), estimate(),
                                                    mme::BondColouring::kStrain);
  ASSERT_TRUE(start);
  EXPECT_GT(start->bond_values[0], 0.1);
  EXPECT_LT(s->bond_values[0], -0.1);
}

TEST_F(Fixture, LocalCostColouringAveragesTheEndsOverZeroToTheLargest) {
  mme::Estimate e = estimate();
  e.local_costs = {1e-6, 2e-6, 4e-6};
  auto s = mme::makeVisualisationSnapshot(model, window(0, 20), e, mme::BondColouring::kLocalCost);
  ASSERT_TRUE(s);
  ASSERT_EQ(s->bond_values.size(), 3u);
  EXPECT_DOUBLE_EQ(s->bond_values[0], 1.5e-6);
  EXPECT_DOUBLE_EQ(s->bond_values[1], 3e-6);
  EXPECT_DOUBLE_EQ(s->bond_values[2], 2.5e-6);
  EXPECT_EQ(s->bond_value_lo, 0.0);
  EXPECT_EQ(s->bond_value_hi, 4e-6);
  // No local costs yet: zeros over [0, 1].
  e.local_costs.clear();
  s = mme::makeVisualisationSnapshot(model, window(0, 20), e, mme::BondColouring::kLocalCost);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->bond_values, (std::vector<double>{0.0, 0.0, 0.0}));
  EXPECT_EQ(s->bond_value_hi, 1.0);
}

TEST_F(Fixture, StatusText) {
  mme::Estimate e = estimate();
  auto s = mme::makeVisualisationSnapshot(model, window(0, 5), e, mme::BondColouring::kStrain);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->text, "generation 7  cost 1.23e-05 m^2  stable");
  e.stable = false;
  e.generation = 12;
  e.global_cost = 3.0;
  s = mme::makeVisualisationSnapshot(model, window(0, 5), e, mme::BondColouring::kStrain);
  EXPECT_EQ(s->text, "generation 12  cost 3 m^2  UNSTABLE");
}

TEST_F(Fixture, OcclusionHidesWhatCannotBeComputed) {
  // Occluded in the latest frame only: flagged; prediction and reconstruction still made.
  mme::Trajectory w = window(0, 20);
  w.occluded[19 * 3 + 1] = 1;
  w.position(19, 1).setZero();
  auto s = mme::makeVisualisationSnapshot(model, w, estimate(), mme::BondColouring::kStrain);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->observed_occluded, (std::vector<uint8_t>{0, 1, 0}));
  EXPECT_EQ(s->predicted.size(), 3u);
  EXPECT_EQ(s->reconstructed.size(), 3u);
  // Occluded at the window start with two neighbours only (3 are needed to place it): no
  // reconstruction (no start state), the prediction stays.
  w = window(0, 20);
  w.occluded[0 * 3 + 2] = 1;
  s = mme::makeVisualisationSnapshot(model, w, estimate(), mme::BondColouring::kStrain);
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->reconstructed.empty());
  EXPECT_TRUE(s->reconstruction_trails.empty());
  EXPECT_EQ(s->predicted.size(), 3u);
  // Occluded two frames before the latest: no prediction, the reconstruction stays.
  w = window(0, 20);
  w.occluded[17 * 3 + 0] = 1;
  s = mme::makeVisualisationSnapshot(model, w, estimate(), mme::BondColouring::kStrain);
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->predicted.empty());
  EXPECT_EQ(s->reconstructed.size(), 3u);
}

TEST_F(Fixture, AFixedParticleNeverSeenIsAPointOfTheModelOnly) {
  // c fixed where it is (an anchor has no marker: hidden in every frame); a and b keep moving.
  mme::Model anchored = model;
  anchored.particles[2].fixed = true;
  anchored.particles[2].velocity_mps.setZero();
  const mme::Trajectory motion = mme::simulateTrajectory(anchored, 20, 100.0);
  mme::Trajectory w = motion;
  for (int t = 0; t < w.numFrames(); ++t) {
    w.occluded[t * 3 + 2] = 1;
    w.position(t, 2).setZero();
  }
  auto s = mme::makeVisualisationSnapshot(anchored, w, estimate(), mme::BondColouring::kStrain);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->model_only, (std::vector<uint8_t>{0, 0, 1}));
  // The model still predicts the seen particles (and places the anchor where it is fixed).
  ASSERT_EQ(s->predicted.size(), 3u);
  EXPECT_LT((s->predicted[0] - motion.position(19, 0)).norm(), 1e-12);
  EXPECT_LT((s->predicted[2] - anchored.particles[2].position_m).norm(), 1e-12);
  // Seen once in the window: a marker (a fixed pivot with a marker is drawn).
  w.occluded[5 * 3 + 2] = 0;
  w.position(5, 2) = motion.position(5, 2);
  s = mme::makeVisualisationSnapshot(anchored, w, estimate(), mme::BondColouring::kStrain);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->model_only, (std::vector<uint8_t>{0, 0, 0}));
  // A free particle hidden throughout is a hidden marker, not a point of the model only.
  w = window(0, 20);
  for (int t = 0; t < w.numFrames(); ++t) w.occluded[t * 3 + 1] = 1;
  s = mme::makeVisualisationSnapshot(model, w, estimate(), mme::BondColouring::kStrain);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->model_only, (std::vector<uint8_t>{0, 0, 0}));
}

TEST_F(Fixture, ShortWindowsAndMismatchedModels) {
  EXPECT_FALSE(mme::makeVisualisationSnapshot(model, window(0, 1), estimate(),
                                              mme::BondColouring::kStrain));
  // Two frames: the latest is the reconstruction's start, no prediction yet.
  const auto s = mme::makeVisualisationSnapshot(model, window(0, 2), estimate(),
                                                mme::BondColouring::kStrain);
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->predicted.empty());
  ASSERT_EQ(s->reconstructed.size(), 3u);
  EXPECT_EQ(s->reconstructed[2], truth.position(1, 2));
  // A model with other particles than the window's markers (one was loaded meanwhile).
  mme::Model other = model;
  other.particles.pop_back();
  other.bonds.resize(1);
  EXPECT_FALSE(mme::makeVisualisationSnapshot(other, window(0, 20), estimate(),
                                              mme::BondColouring::kStrain));
}

TEST(BondColouring, ParsesItsTwoNamesOnly) {
  mme::BondColouring c = mme::BondColouring::kStrain;
  EXPECT_TRUE(mme::parseBondColouring("local_cost", &c));
  EXPECT_EQ(c, mme::BondColouring::kLocalCost);
  EXPECT_TRUE(mme::parseBondColouring("strain", &c));
  EXPECT_EQ(c, mme::BondColouring::kStrain);
  EXPECT_FALSE(mme::parseBondColouring("Strain", &c));
  EXPECT_FALSE(mme::parseBondColouring("", &c));
  EXPECT_EQ(c, mme::BondColouring::kStrain);
  EXPECT_STREQ(mme::bondColouringName(mme::BondColouring::kLocalCost), "local_cost");
  EXPECT_STREQ(mme::bondColouringName(mme::BondColouring::kStrain), "strain");
}

}  // namespace

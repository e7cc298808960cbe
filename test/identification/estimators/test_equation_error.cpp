// The equation-error start: exact on noiseless one-step data for every kind it solves for, with
// occlusion; smoothing helps on noisy data; a clear reason where it does not apply.
#include <gtest/gtest.h>

#include <cmath>

#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "test_helpers.h"

namespace {

using mme::test::addBond;
using mme::test::addParticle;
using mme::test::addType;
using mme::test::maxRelativeError;

std::vector<double> truthOf(const mme::Model& m) { return mme::getValues(m, mme::freeParameters(m)); }

/// A damped chain with flexion at the inner joints, a viscous particle, a fixed end and a free
/// gravity: every kind the equation error solves for, every one of their parameters free.
mme::Model everyKind() {
  mme::Model m;
  m.frame_rate_hz = 200;
  for (int c = 0; c < 3; ++c) m.gravity_mps2[c] = mme::test::valueParam(c == 2 ? -9.81 : 0.3, true);
  addParticle(&m, Eigen::Vector3d(0, 0, 0), 1.0, true);
  for (int i = 1; i < 6; ++i)
    addParticle(&m, Eigen::Vector3d(0.1 * i, 0.02 * (i % 2), -0.03 * i), 0.2 + 0.05 * i, false, "",
                Eigen::Vector3d(0.1 * (i % 3), -0.05 * i, 0.2));
  const int s0 = addType(&m, "s0", mme::BondKind::kSpring,
                         {{mme::kStiffness, 30.0}, {mme::kRestLength, 0.09}, {mme::kDamping, 0.2}});
  const int s1 = addType(&m, "s1", mme::BondKind::kSpring,
                         {{mme::kStiffness, 50.0}, {mme::kRestLength, 0.12}});
  const int f0 = addType(&m, "f0", mme::BondKind::kFlexion,
                         {{mme::kStiffness, 0.4}, {mme::kRestAngle, 2.6}, {mme::kDamping, 0.01}});
  const int v0 = addType(&m, "v0", mme::BondKind::kViscosity, {{mme::kViscosity, 0.3}});
  for (int i = 0; i < 5; ++i) addBond(&m, i % 2 ? s1 : s0, i, i + 1);
  addBond(&m, s1, 1, 3);
  for (int i = 1; i < 5; ++i) addBond(&m, f0, i - 1, i, i + 1);
  addBond(&m, v0, 5);
  return m;
}

TEST(EquationError, ExactOnNoiselessOneStepDataForEveryKind) {
  const mme::Model truth = everyKind();
  const mme::Trajectory data = mme::simulateTrajectory(truth, 80, truth.frame_rate_hz);
  const mme::EquationErrorResult r = mme::solveEquationError(mme::test::withoutValues(truth), data);
  ASSERT_TRUE(r.applicable) << r.reason;
  EXPECT_EQ(r.values.size(), 12u);  // 3 + 2 + 3 + 1 + gravity x y z
  EXPECT_LT(maxRelativeError(r.values, truthOf(truth)), 1e-7);
  EXPECT_LT(r.residual_rms_m, 1e-12);
  EXPECT_EQ(r.rows, 3u * 5 * 78);  // 5 free particles, frames 1..78
}

// Springs stretched up to 20x their rest length hanging under gravity: k, L = (kL)/k and c
// exactly, wherever a default search range would have put L.
TEST(EquationError, ExactOnAHangingObjectAndWithOccludedSamples) {
  const mme::Model truth = mme::makeHangingObject({});
  mme::Trajectory data = mme::simulateTrajectory(truth, 200, truth.frame_rate_hz);
  const mme::Model blank = mme::test::withoutBounds(mme::test::withoutValues(truth));
  const mme::EquationErrorResult full = mme::solveEquationError(blank, data);
  ASSERT_TRUE(full.applicable) << full.reason;
  EXPECT_LT(maxRelativeError(full.values, truthOf(truth)), 1e-7);
  // 10 % of the samples occluded: rows that need one are left out, the rest stay exact.
  for (size_t k = 0; k < data.occluded.size(); ++k)
    if ((k * 7919) % 10 == 3) data.occluded[k] = 1;
  const mme::EquationErrorResult occluded = mme::solveEquationError(blank, data);
  ASSERT_TRUE(occluded.applicable);
  EXPECT_LT(occluded.rows, full.rows / 2);
  EXPECT_GT(occluded.rows, 0u);
  EXPECT_LT(maxRelativeError(occluded.values, truthOf(truth)), 1e-6);
}

// On noisy markers the quadratic fit over 7 frames gives a better start than raw differences
// (whose accelerations amplify the noise by 2.4 / h^2).
TEST(EquationError, SmoothingHelpsOnNoisyMarkers) {
  const mme::Model truth = mme::makeHangingObject({});
  mme::Trajectory data = mme::simulateTrajectory(truth, 300, truth.frame_rate_hz);
  mme::addGaussianNoise(&data, 2e-4, 3);
  const mme::Model blank = mme::test::withoutValues(truth);
  mme::EquationErrorOptions smooth;
  smooth.smoothing_half_width = 3;
  const mme::EquationErrorResult raw = mme::solveEquationError(blank, data);
  const mme::EquationErrorResult fit = mme::solveEquationError(blank, data, smooth);
  ASSERT_TRUE(raw.applicable && fit.applicable);
  double raw_sum = 0, fit_sum = 0;
  const std::vector<double> t = truthOf(truth);
  for (size_t k = 0; k < t.size(); ++k) {
    raw_sum += std::isfinite(raw.values[k]) ? std::abs(raw.values[k] / t[k] - 1) : 1.0;
    fit_sum += std::isfinite(fit.values[k]) ? std::abs(fit.values[k] / t[k] - 1) : 1.0;
  }
  EXPECT_LT(fit_sum, 0.5 * raw_sum);
}

// With the rest length known, a cubic stiffness (hardening or softening) and a quadratic
// damping are linear unknowns too: exact with k and c beside them.
TEST(EquationError, ExactForNonLinearTermsWithTheRestLengthKnown) {
  mme::Model truth;
  truth.frame_rate_hz = 200;
  for (int i = 0; i < 4; ++i)
    addParticle(&truth, Eigen::Vector3d(0.1 * i, 0.03 * (i % 2), 0.0), 0.5, i == 0, "",
                Eigen::Vector3d(0.0, 0.2 * i, -0.1 * i));
  const int hard = addType(&truth, "hard", mme::BondKind::kSpring,
                           {{mme::kStiffness, 40.0}, {mme::kRestLength, 0.08}, {mme::kStiffnessNl, 4e4},
                            {mme::kDamping, 0.2}, {mme::kDampingNl, 0.5}});
  const int soft = addType(&truth, "soft", mme::BondKind::kSpring,
                           {{mme::kStiffness, 60.0}, {mme::kRestLength, 0.12}, {mme::kStiffnessNl, -2e3}});
  for (int i = 0; i < 3; ++i) addBond(&truth, hard, i, i + 1);
  addBond(&truth, soft, 0, 2);
  addBond(&truth, soft, 1, 3);
  const mme::Trajectory data = mme::simulateTrajectory(truth, 100, truth.frame_rate_hz);
  mme::Model blank = mme::test::withoutValues(truth);
  for (mme::BondType& t : blank.bond_types) {
    t.param(mme::kRestLength).free = false;  // known: the value of the truth
    t.param(mme::kRestLength).value = truth.bond_types[&t - blank.bond_types.data()].value(mme::kRestLength);
    t.param(mme::kRestLength).has_value = true;
  }
  const mme::EquationErrorResult r = mme::solveEquationError(blank, data);
  ASSERT_TRUE(r.applicable) << r.reason;
  EXPECT_EQ(r.values.size(), 6u);  // hard: k, c, k_nl, c_nl; soft: k, k_nl
  std::vector<double> want;
  for (const mme::ParamRef& ref : mme::freeParameters(blank)) want.push_back(mme::getParam(truth, ref));
  EXPECT_LT(maxRelativeError(r.values, want), 1e-6);
  EXPECT_LT(r.residual_rms_m, 1e-12);
  // A free rest length beside a free cubic term: not linear, said so.
  mme::Model both = blank;
  both.bond_types[hard].param(mme::kRestLength).free = true;
  const mme::EquationErrorResult no = mme::solveEquationError(both, data);
  EXPECT_FALSE(no.applicable);
  EXPECT_NE(no.reason.find("hard/rest_length"), std::string::npos) << no.reason;
  // Linearised about values 5 % off (rest lengths, stiffnesses): each solve is a Gauss-Newton
  // step; a few reach the truth.
  mme::EquationErrorOptions linearized;
  linearized.linearize_rest_length = true;
  mme::Model guess = truth;
  for (mme::BondType& t : guess.bond_types) t.param(mme::kRestLength).value *= 1.05;
  for (mme::BondType& t : guess.bond_types) t.param(mme::kStiffness).value *= 0.95;
  const std::vector<mme::ParamRef> refs = mme::freeParameters(guess);
  double first_error = 0.0;
  for (int step = 0; step < 8; ++step) {
    const mme::EquationErrorResult g = mme::solveEquationError(guess, data, linearized);
    ASSERT_TRUE(g.applicable) << g.reason;
    if (step == 0) first_error = maxRelativeError(g.values, truthOf(truth));
    mme::setValues(guess, refs, g.values);
  }
  EXPECT_GT(first_error, 1e-4);  // one step is not enough from 5 % off
  EXPECT_LT(maxRelativeError(mme::getValues(guess, refs), truthOf(truth)), 1e-7);
}

TEST(EquationError, SaysWhyItDoesNotApply) {
  mme::Model m = mme::test::smallObject();
  m.bond_types[0].param(mme::kMinDistance) = mme::test::valueParam(0.1, true);
  const mme::Trajectory data = mme::simulateTrajectory(mme::test::smallObject(), 20, 100.0);
  mme::EquationErrorResult r = mme::solveEquationError(m, data);
  EXPECT_FALSE(r.applicable);
  EXPECT_NE(r.reason.find("s0/min_distance"), std::string::npos) << r.reason;

  mme::Model cubic = mme::test::smallObject();
  cubic.bond_types[1].param(mme::kStiffnessNl) = mme::test::valueParam(100.0, false);
  r = mme::solveEquationError(cubic, data);
  EXPECT_FALSE(r.applicable);
  EXPECT_NE(r.reason.find("s1/rest_length"), std::string::npos) << r.reason;
  // A non-linear term that is known (fixed) with a known rest length is fine.
  cubic.bond_types[1].param(mme::kRestLength).free = false;
  EXPECT_TRUE(mme::solveEquationError(cubic, data).applicable);
}

}  // namespace

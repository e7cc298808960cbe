// The output error's exact derivatives: forward sensitivities through the motion law against
// central differences of the simulator, on a model holding every kind the sensitivities cover
// (nonlinear damped springs, a conditional bond, flexion, viscosity, floor contact, free gravity)
// and for every column (each free parameter, each initial position and velocity); and the kinds
// they leave to finite differences, named.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "motion_model_estimation/core/bond_kind.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/motion_sensitivity.h"
#include "test_helpers.h"

namespace {

using mme::test::addType;

/// Five moving particles and one fixed: a nonlinear damped spring type, a cable (a conditional
/// spring, active here throughout), a flexion at p1, viscosity on p3, and p4 resting in a floor
/// under free gravity, sliding (inside the contact depth, so the ramp acts). 100 Hz, 2 substeps.
mme::Model everyKind() {
  mme::Model m;
  m.frame_rate_hz = 100.0;
  m.substeps = 2;
  for (int k = 0; k < 3; ++k) m.gravity_mps2[k] = mme::valueParam(k == 2 ? -9.81 : 0.3, true);
  mme::test::addParticle(&m, {0.0, 0.0, 0.5}, 0.5, false, "", {0.1, 0.0, 0.0});
  mme::test::addParticle(&m, {0.12, 0.01, 0.5}, 0.7);
  mme::test::addParticle(&m, {0.2, 0.1, 0.52}, 0.6, false, "", {0.0, -0.2, 0.1});
  mme::test::addParticle(&m, {0.05, 0.13, 0.45}, 0.4);
  mme::test::addParticle(&m, {0.3, 0.3, -0.0196}, 1.0, false, "", {0.1, 0.05, 0.01});
  mme::test::addParticle(&m, {0.0, 0.1, 0.6}, 1.0, true);
  const int s = addType(&m, "s", mme::BondKind::kSpring,
                        {{mme::kStiffness, 40.0}, {mme::kRestLength, 0.11}, {mme::kDamping, 0.3},
                         {mme::kStiffnessNl, 300.0}, {mme::kDampingNl, 0.5}});
  const int cable = addType(&m, "cable", mme::BondKind::kSpring,
                            {{mme::kStiffness, 25.0}, {mme::kRestLength, 0.1}});
  m.bond_types[cable].param(mme::kMinDistance) = mme::valueParam(0.01);  // a fixed threshold
  const int f = addType(&m, "f", mme::BondKind::kFlexion,
                        {{mme::kStiffness, 0.05}, {mme::kRestAngle, 2.4}, {mme::kDamping, 0.004}});
  const int v = addType(&m, "v", mme::BondKind::kViscosity, {{mme::kViscosity, 0.2}});
  const int g = addType(&m, "g", mme::BondKind::kFloor,
                        {{mme::kStiffness, 500.0}, {mme::kDamping, 2.0}, {mme::kFriction, 1.5},
                         {mme::kHeight, 0.0}, {mme::kContactDepth, 0.05}});
  mme::addBond(&m, s, 0, 1);
  mme::addBond(&m, s, 1, 2);
  mme::addBond(&m, s, 2, 5);
  mme::addBond(&m, cable, 0, 3);
  mme::addBond(&m, cable, 3, 5);
  mme::addBond(&m, f, 0, 1, 2);
  mme::addBond(&m, v, 3);
  mme::addBond(&m, g, 4);
  return m;
}

/// x and v of every particle after `frames` frames, flattened (x then v).
Eigen::VectorXd simulate(const mme::Model& m, const mme::State& start, int frames) {
  mme::Simulator sim(m);
  mme::State s = start;
  for (int t = 0; t < frames; ++t) sim.stepFrame(&s, 1.0 / m.frame_rate_hz);
  const int n = static_cast<int>(s.x_m.size());
  Eigen::VectorXd out(6 * n);
  for (int i = 0; i < n; ++i) {
    out.segment<3>(3 * i) = s.x_m[i];
    out.segment<3>(3 * n + 3 * i) = s.v_mps[i];
  }
  return out;
}

TEST(MotionSensitivity, MatchesCentralDifferencesOnEveryKindAndColumn) {
  const mme::Model m = everyKind();
  ASSERT_EQ(mme::sensitivityUnsupportedReason(m), "");
  const std::vector<mme::ParamRef> refs = mme::freeParameters(m);
  ASSERT_EQ(refs.size(), 5u + 2u + 3u + 1u + 5u + 3u);
  const int frames = 20, n = static_cast<int>(m.particles.size());
  const mme::State start = mme::Simulator(m).initialState();
  mme::MotionSensitivity sens(m, refs);
  sens.start(start);
  for (int t = 0; t < frames; ++t) sens.stepFrame(1.0 / m.frame_rate_hz);
  // The state itself is the simulator's.
  const Eigen::VectorXd reached = simulate(m, start, frames);
  for (int i = 0; i < n; ++i)
    EXPECT_LT((sens.state().x_m[i] - reached.segment<3>(3 * i)).norm(), 1e-12) << i;
  ASSERT_EQ(sens.columns(), static_cast<int>(refs.size()) + 6 * 5);
  const auto check = [&](int column, const Eigen::VectorXd& central, const std::string& what) {
    Eigen::VectorXd exact(6 * n);
    exact << sens.dx().col(column), sens.dv().col(column);
    const double scale = central.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0) << what << ": the column must move something";
    EXPECT_LT((exact - central).cwiseAbs().maxCoeff(), 1e-6 * scale) << what;
  };
  for (size_t c = 0; c < refs.size(); ++c) {
    const double value = mme::getParam(m, refs[c]);
    const double step = 1e-4 * std::max(std::abs(value), 1e-2);
    mme::Model plus = m, minus = m;
    mme::setParam(plus, refs[c], value + step);
    mme::setParam(minus, refs[c], value - step);
    check(static_cast<int>(c), (simulate(plus, start, frames) - simulate(minus, start, frames)) / (2 * step),
          refs[c].name);
  }
  for (int f = 0; f < 5; ++f)  // the free particles are 0..4
    for (int k = 0; k < 6; ++k) {
      const double step = 1e-6;
      mme::State plus = start, minus = start;
      (k < 3 ? plus.x_m[f][k] : plus.v_mps[f][k - 3]) += step;
      (k < 3 ? minus.x_m[f][k] : minus.v_mps[f][k - 3]) -= step;
      check(sens.stateColumn0() + 6 * f + k, (simulate(m, plus, frames) - simulate(m, minus, frames)) / (2 * step),
            "initial state of p" + std::to_string(f) + " component " + std::to_string(k));
    }
}

// Without the parameters' columns (a fit of the state alone) the state columns are the same.
TEST(MotionSensitivity, StateColumnsAloneAreTheSame) {
  const mme::Model m = everyKind();
  const mme::State start = mme::Simulator(m).initialState();
  mme::MotionSensitivity all(m, mme::freeParameters(m)), alone(m, mme::freeParameters(m));
  alone.setParameterColumns(false);
  all.start(start);
  alone.start(start);
  for (int t = 0; t < 10; ++t) {
    all.stepFrame(0.01);
    alone.stepFrame(0.01);
  }
  ASSERT_EQ(alone.columns(), 30);
  EXPECT_EQ(alone.stateColumn0(), 0);
  EXPECT_LT((all.dx().rightCols(30) - alone.dx()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((all.dv().rightCols(30) - alone.dv()).cwiseAbs().maxCoeff(), 1e-15);
}

// What the sensitivities leave to finite differences is named, and refused with a clear error.
TEST(MotionSensitivity, NamesWhatItDoesNotCover) {
  const mme::Model muscles = mme::test::muscleObject();
  EXPECT_NE(mme::sensitivityUnsupportedReason(muscles).find("muscles"), std::string::npos);
  EXPECT_THROW(mme::MotionSensitivity(muscles, mme::freeParameters(muscles)), mme::InputError);
  mme::Model clamped = everyKind();
  clamped.bond_types[0].param(mme::kMaxElongation) = mme::valueParam(0.1);
  EXPECT_NE(mme::sensitivityUnsupportedReason(clamped).find("max_elongation"), std::string::npos);
  mme::Model interacting = everyKind();
  interacting.interactions.push_back({1, "", ""});
  EXPECT_NE(mme::sensitivityUnsupportedReason(interacting).find("interactions"), std::string::npos);
  // Every kind of the catalogue is either covered or named: a model of one bond of each kind.
  for (mme::BondKind kind : mme::allBondKinds()) {
    if (kind == mme::BondKind::kMuscle) continue;  // muscleObject above
    mme::Model one;
    one.frame_rate_hz = 100.0;
    mme::test::addParticle(&one, {0, 0, 0});
    mme::test::addParticle(&one, {0.1, 0, 0});
    mme::test::addParticle(&one, {0.1, 0.1, 0});
    const int t = addType(&one, "t", kind, {{mme::bondKindInfo(kind).params.front(), 1.0}});
    mme::addBond(&one, t, 0, mme::bondKindInfo(kind).arity > 1 ? 1 : -1, mme::bondKindInfo(kind).arity > 2 ? 2 : -1);
    EXPECT_EQ(mme::sensitivityUnsupportedReason(one), "") << mme::bondKindInfo(kind).name;
  }
}

}  // namespace

// The muscle bond kind: its network's layout and names, its activation and force against hand
// computations, a zero-gain muscle is exactly its spring, the model checks of muscle wiring, and
// the one-step cost of the true model on its own data is rounding only.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "motion_model_estimation/core/muscle.h"
#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "test_helpers.h"

namespace {

using Eigen::Vector3d;
using mme::BondKind;
using mme::Model;
using mme::test::addBond;
using mme::test::addMuscle;
using mme::test::addMuscleType;
using mme::test::addParticle;
using mme::test::addType;
using mme::test::nameBond;

TEST(MuscleNetwork, LayoutSizesAndNames) {
  EXPECT_EQ(mme::muscleNetworkSize(2, 0), 5);   // w2_0..3, b2
  EXPECT_EQ(mme::muscleNetworkSize(2, 3), 19);  // 3x4 w1, 3 b1, 3 w2, b2
  EXPECT_EQ(mme::muscleNetworkSize(0, 0), 1);   // a constant activation
  EXPECT_EQ(mme::muscleNetworkKey(2, 3, 0), "w1_0_0");
  EXPECT_EQ(mme::muscleNetworkKey(2, 3, 6), "w1_1_2");
  EXPECT_EQ(mme::muscleNetworkKey(2, 3, 12), "b1_0");
  EXPECT_EQ(mme::muscleNetworkKey(2, 3, 15), "w2_0");
  EXPECT_EQ(mme::muscleNetworkKey(2, 3, 18), "b2");
  EXPECT_EQ(mme::muscleNetworkKey(2, 0, 3), "w2_3");
  EXPECT_EQ(mme::muscleNetworkKey(2, 0, 4), "b2");
  for (int hidden : {0, 1, 3})
    for (int k = 0; k < mme::muscleNetworkSize(2, hidden); ++k)
      EXPECT_EQ(mme::muscleNetworkIndex(2, hidden, mme::muscleNetworkKey(2, hidden, k)), k);
  EXPECT_EQ(mme::muscleNetworkIndex(2, 3, "w1_3_0"), -1);  // hidden unit 3 of 0..2
  EXPECT_EQ(mme::muscleNetworkIndex(2, 0, "w1_0_0"), -1);  // no hidden layer
  EXPECT_EQ(mme::muscleNetworkIndex(2, 0, "stiffness"), -1);
  EXPECT_EQ(mme::muscleNetworkLayout(2, 3), "w1_<0..2>_<0..3>, b1_<0..2>, w2_<0..2>, b2");
  EXPECT_EQ(mme::muscleNetworkLayout(1, 0), "w2_<0..1>, b2");
}

TEST(MuscleNetwork, ActivationMatchesAHandComputation) {
  const double z[2] = {0.05, -0.4};  // elongation [m], speed [m/s]
  // hidden 0: a = gain tanh(b2 + w . z)
  const double linear[3] = {8.0, -2.0, 0.1};
  EXPECT_DOUBLE_EQ(mme::muscleActivation(linear, 1, 0, 3.0, z),
                   3.0 * std::tanh(0.1 + 8.0 * 0.05 - 2.0 * -0.4));
  // hidden 2: w1 (2x2 row-major), b1, w2, b2
  const double net[9] = {10.0, 1.0, -5.0, 2.0, 0.2, -0.1, 0.7, -1.3, 0.05};
  const double h0 = std::tanh(0.2 + 10.0 * 0.05 + 1.0 * -0.4);
  const double h1 = std::tanh(-0.1 - 5.0 * 0.05 + 2.0 * -0.4);
  EXPECT_DOUBLE_EQ(mme::muscleActivation(net, 1, 2, 1.5, z),
                   1.5 * std::tanh(0.05 + 0.7 * h0 - 1.3 * h1));
}

/// p0 -- spring "in" -- p1 -- muscle (reads "in") -- p2, no gravity.
Model handModel(double gain) {
  Model m;
  m.frame_rate_hz = 100;
  addParticle(&m, Vector3d(0, 0, 0), 1.0, false, "", Vector3d(0, 0, 0));
  addParticle(&m, Vector3d(0.3, 0, 0), 1.0, false, "", Vector3d(0.1, 0.2, 0));
  addParticle(&m, Vector3d(0.3, 0.4, 0), 1.0, false, "", Vector3d(-0.1, 0.05, 0.3));
  const int s = addType(&m, "s", BondKind::kSpring, {{mme::kStiffness, 10.0}, {mme::kRestLength, 0.25}},
                        false);
  addBond(&m, s, 0, 1);
  nameBond(&m, 0, "in");
  const int mu = addMuscleType(&m, "m", 20.0, 0.35, 0.5, gain, 1, 0, {8.0, -2.0, 0.1});
  addMuscle(&m, mu, 1, 2, {0});
  return m;
}

TEST(Muscle, ForceMatchesAHandComputation) {
  const Model m = handModel(3.0);
  mme::Simulator sim(m);
  std::vector<Vector3d> f;
  sim.computeForces(sim.initialState(), &f);
  // Input "in": l = 0.3, e = 0.05 m, s = (v1 - v0).x = 0.1 m/s -> y = 0.1 + 8 e - 2 s = 0.3.
  const double activation = 3.0 * std::tanh(0.3);
  // Muscle p1 -> p2: u = +y, e = 0.05 m, s = 0.05 - 0.2 = -0.15 m/s.
  const double tension = 20.0 * 0.05 + 0.5 * -0.15 + activation;
  EXPECT_NEAR(f[0].x(), 10.0 * 0.05, 1e-15);  // the spring pulls p0 toward p1
  EXPECT_NEAR(f[1].x(), -10.0 * 0.05, 1e-15);
  EXPECT_NEAR(f[1].y(), tension, 1e-14);
  EXPECT_NEAR(f[2].y(), -tension, 1e-14);
  EXPECT_NEAR(f[2].x(), 0.0, 1e-15);
  EXPECT_NEAR(f[2].z(), 0.0, 1e-15);
  // And the activation is really there: without it the force differs by exactly it.
  mme::Simulator passive(handModel(0.0));
  std::vector<Vector3d> f0;
  passive.computeForces(passive.initialState(), &f0);
  EXPECT_NEAR(f[1].y() - f0[1].y(), activation, 1e-14);
  EXPECT_GT(std::fabs(activation), 0.5);
}

TEST(Muscle, WithZeroGainItMovesExactlyLikeItsSpring) {
  Model muscle = handModel(0.0);
  muscle.gravity_mps2[2] = mme::test::valueParam(-9.81);
  Model spring = muscle;
  mme::BondType& t = spring.bond_types[1];
  t.kind = BondKind::kSpring;
  t.param(mme::kGain) = mme::Param();
  t.network_inputs = 0;
  t.network.clear();
  spring.bonds[1].inputs.clear();
  const mme::Trajectory a = mme::simulateTrajectory(muscle, 200, 100.0);
  const mme::Trajectory b = mme::simulateTrajectory(spring, 200, 100.0);
  ASSERT_EQ(a.positions_m.size(), b.positions_m.size());
  for (size_t k = 0; k < a.positions_m.size(); ++k) ASSERT_EQ(a.positions_m[k], b.positions_m[k]) << k;
  // ... and with a gain it does not.
  const mme::Trajectory c = mme::simulateTrajectory(handModel(3.0), 200, 100.0);
  EXPECT_GT((c.position(199, 2) - mme::simulateTrajectory(handModel(0.0), 200, 100.0).position(199, 2)).norm(), 1e-3);
}

TEST(Muscle, ValidationNamesTheWiringProblem) {
  const auto reason = [](const std::function<void(Model*)>& edit) {
    Model m = handModel(1.0);
    edit(&m);
    return mme::validateModel(m);
  };
  EXPECT_EQ(reason([](Model*) {}), "");
  EXPECT_NE(reason([](Model* m) { m->bonds[1].inputs = {0, 0}; }).find("reads 1 input bond(s), the bond names 2"),
            std::string::npos);
  EXPECT_NE(reason([](Model* m) { m->bonds[1].inputs = {1}; }).find("cannot read its own bond"),
            std::string::npos);
  EXPECT_NE(reason([](Model* m) { m->bonds[0].name.clear(); }).find("has no name"), std::string::npos);
  EXPECT_NE(reason([](Model* m) { m->bonds[0].inputs = {1}; }).find("only muscle bonds have inputs"),
            std::string::npos);
  EXPECT_NE(reason([](Model* m) { m->bond_types[1].network.pop_back(); }).find("its layout needs 3"),
            std::string::npos);
  EXPECT_NE(reason([](Model* m) { m->bond_types[1].network_hidden = 99; }).find("hidden must be in"),
            std::string::npos);
  EXPECT_NE(reason([](Model* m) {
              const int f = addType(m, "f", BondKind::kFlexion, {{mme::kStiffness, 1.0}, {mme::kRestAngle, 1.0}});
              addBond(m, f, 0, 1, 2);
              nameBond(m, 2, "hinge");
              m->bonds[1].inputs = {2};
            }).find("is a flexion"),
            std::string::npos);
}

TEST(Muscle, ParametersAreNamedByTypeAndNetworkKey) {
  Model m = handModel(1.0);
  for (mme::Param& p : m.bond_types[1].network) p.free = true;
  m.bond_types[1].param(mme::kGain).free = true;
  const std::vector<mme::ParamRef> refs = mme::freeParameters(m);
  std::vector<std::string> names;
  for (const mme::ParamRef& r : refs) names.push_back(r.name);
  EXPECT_EQ(names, (std::vector<std::string>{"m/gain", "m/w2_0", "m/w2_1", "m/b2"}));
  EXPECT_TRUE(refs[1].isNetwork());
  EXPECT_FALSE(refs[0].isNetwork());
  mme::setParam(m, refs[2], -7.5);
  EXPECT_EQ(m.bond_types[1].network[1].value, -7.5);
  EXPECT_EQ(mme::getParam(m, refs[2]), -7.5);
}

TEST(Muscle, TheTrueModelCostsRoundingOnlyAndEachNetworkParameterMatters) {
  Model m = mme::test::muscleObject();
  mme::BondType& t = m.bond_types[m.bondTypeIndex("m")];
  t.param(mme::kGain).free = true;
  for (mme::Param& p : t.network) p.free = true;
  const mme::Trajectory data = mme::simulateTrajectory(m, 80, 100.0);
  mme::ShortTermCost cost(m, data);
  const std::vector<double> truth = mme::getValues(m, cost.freeParameters());
  const double c0 = cost.evaluate(truth, nullptr);
  EXPECT_LT(c0 / cost.termCount(), 1e-26);
  for (size_t k = 0; k < truth.size(); ++k) {
    std::vector<double> p = truth;
    p[k] = truth[k] * 1.05 + 0.01;
    EXPECT_GT(cost.evaluate(p, nullptr), 1e6 * c0 + 1e-20) << cost.freeParameters()[k].name;
  }
}

// An occluded end of an input bond makes the muscle's force unknown: its ends' terms drop too.
TEST(Muscle, AnOccludedInputDropsTheMusclesTerms) {
  // p0 -- spring "in" -- p1;  p2 -- muscle reading "in" -- p3: joined only through the input.
  Model m;
  m.frame_rate_hz = 100;
  addParticle(&m, Vector3d(0, 0, 0), 1.0, false, "", Vector3d(0.1, 0, 0));
  mme::addParticle(&m, Vector3d(0.3, 0, 0));
  mme::addParticle(&m, Vector3d(0, 1, 0));
  mme::addParticle(&m, Vector3d(0.3, 1, 0));
  const int s = addType(&m, "s", BondKind::kSpring, {{mme::kStiffness, 10.0}, {mme::kRestLength, 0.25}});
  addBond(&m, s, 0, 1);
  nameBond(&m, 0, "in");
  addMuscle(&m, addMuscleType(&m, "m", 20.0, 0.35, 0.5, 1.0, 1, 0, {8.0, -2.0, 0.1}), 2, 3, {0});
  const mme::Trajectory clean = mme::simulateTrajectory(m, 20, 100.0);
  mme::Trajectory gappy = clean;
  gappy.occluded[10 * 4 + 0] = 1;  // p0 at frame 10
  const uint64_t dropped = mme::ShortTermCost(m, clean).termCount() - mme::ShortTermCost(m, gappy).termCount();
  // Terms at t = 10 and 11 (x(t) or x(t-1) missing): p0, its partner p1 and, through the
  // input, the muscle's ends p2 and p3: 2 x 4. At t = 9 p0's target is missing: 1.
  EXPECT_EQ(dropped, 9u);
}

/// handModel with an activation time constant on its muscle.
Model handModelWithActivationTime(double gain, double activation_time_s) {
  Model m = handModel(gain);
  m.bond_types[m.bondTypeIndex("m")].param(mme::kActivationTime) = mme::test::valueParam(activation_time_s);
  return m;
}

TEST(MuscleActivation, AStateActivationDrivesTheForceAndRelaxesToTheExcitation) {
  const double tau_s = 0.05, dt_s = 0.004;
  const Model m = handModelWithActivationTime(3.0, tau_s);
  mme::Simulator sim(m);
  ASSERT_TRUE(sim.hasActivationState());
  const double excitation = 3.0 * std::tanh(0.3);  // ForceMatchesAHandComputation's
  mme::State s = sim.initialState();
  ASSERT_TRUE(s.activation_n.empty());
  std::vector<Vector3d> at_rest, pushed;
  sim.computeForces(s, &at_rest);  // no activation in the state: the excitation
  s.activation_n = {excitation + 2.0};
  sim.computeForces(s, &pushed);
  EXPECT_NEAR(pushed[1].y() - at_rest[1].y(), 2.0, 1e-12);  // the state's activation pulls
  EXPECT_NEAR(pushed[2].y() - at_rest[2].y(), -2.0, 1e-12);
  // One substep: the activation moves toward the excitation taken at the substep's start.
  sim.step(&s, dt_s);
  ASSERT_EQ(s.activation_n.size(), 1u);
  EXPECT_NEAR(s.activation_n[0], excitation + 2.0 * std::exp(-dt_s / tau_s), 1e-12);
  // Without a time constant the same state's activation is ignored.
  mme::Simulator instant(handModel(3.0));
  EXPECT_FALSE(instant.hasActivationState());
  std::vector<Vector3d> ignored;
  instant.computeForces(s, &ignored);
  mme::State fresh = s;
  fresh.activation_n.clear();
  std::vector<Vector3d> plain;
  instant.computeForces(fresh, &plain);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(ignored[i], plain[i]) << i;
}

TEST(MuscleActivation, AStateWithoutActivationsStartsAtRestAndLagsAfter) {
  // From a state without activations the muscle starts at its excitation: the first substep
  // is the instantaneous model's to the bit; later the activation lags the excitation.
  const Model lagging = handModelWithActivationTime(3.0, 0.2);
  mme::Simulator sim(lagging), instant(handModel(3.0));
  mme::State a = sim.initialState(), b = instant.initialState();
  sim.step(&a, 0.01);
  instant.step(&b, 0.01);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(a.x_m[i], b.x_m[i]) << i;
  for (int k = 0; k < 50; ++k) {
    sim.step(&a, 0.01);
    instant.step(&b, 0.01);
  }
  EXPECT_GT((a.x_m[2] - b.x_m[2]).norm(), 1e-4);
  // A long time constant makes the activation a near constant: it stays near its start.
  EXPECT_LT(std::fabs(a.activation_n[0] - 3.0 * std::tanh(0.3)), 0.5 * 3.0);
}

TEST(MuscleActivation, ActivationsEstimatedFromAnObservedAccelerationReproduceIt) {
  const Model m = handModelWithActivationTime(3.0, 0.05);
  mme::Simulator sim(m);
  mme::State truth = sim.initialState();
  const double excitation = 3.0 * std::tanh(0.3);
  truth.activation_n = {excitation - 1.25};
  std::vector<Vector3d> f;
  sim.computeForces(truth, &f);
  std::vector<Vector3d> acceleration(3);
  for (int i = 0; i < 3; ++i) acceleration[i] = f[i] / m.particles[i].mass_kg;
  mme::State start = sim.initialState();
  EXPECT_EQ(sim.estimateActivations(&start, acceleration, {1, 1, 1}), 1);
  ASSERT_EQ(start.activation_n.size(), 1u);
  EXPECT_NEAR(start.activation_n[0], excitation - 1.25, 1e-9);
  // Seen at one end only, the activation is still known.
  mme::State one_end = sim.initialState();
  sim.estimateActivations(&one_end, acceleration, {1, 0, 1});
  EXPECT_NEAR(one_end.activation_n[0], excitation - 1.25, 1e-9);
  // Neither end seen: nothing to go by, the excitation.
  mme::State unseen = sim.initialState();
  sim.estimateActivations(&unseen, acceleration, {1, 0, 0});
  EXPECT_NEAR(unseen.activation_n[0], excitation, 1e-12);
  // A model without activation dynamics has nothing to estimate.
  mme::Simulator instant(handModel(3.0));
  mme::State s = instant.initialState();
  s.activation_n = {1.0};
  EXPECT_EQ(instant.estimateActivations(&s, acceleration, {1, 1, 1}), 0);
  EXPECT_TRUE(s.activation_n.empty());
  EXPECT_THROW(sim.estimateActivations(&s, acceleration, {1, 1}), std::invalid_argument);
}

TEST(MuscleActivation, ANegativeTimeConstantIsRefused) {
  const std::string reason = mme::validateModel(handModelWithActivationTime(3.0, -0.1));
  EXPECT_NE(reason.find("activation_time_constant must be >= 0"), std::string::npos) << reason;
  EXPECT_EQ(mme::validateModel(handModelWithActivationTime(3.0, 0.0)), "");
}

}  // namespace

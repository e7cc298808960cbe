// Simulator: conservation laws, fixed particles, Provot clamps, substeps, interactions.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "motion_model_estimation/core/forces.h"
#include "motion_model_estimation/core/simulator.h"
#include "test_helpers.h"

namespace mme {
namespace {

using Vec = Eigen::Vector3d;

using test::addParticle;
Param value(double v) { return test::valueParam(v); }

int addSpringType(Model* m, const std::string& name, double k, double rest, double damping = 0,
                  double k_nl = 0) {
  BondType t;
  t.name = name;
  t.kind = BondKind::kSpring;
  t.param(kStiffness) = value(k);
  t.param(kRestLength) = value(rest);
  if (damping != 0) t.param(kDamping) = value(damping);
  if (k_nl != 0) t.param(kStiffnessNl) = value(k_nl);
  m->bond_types.push_back(t);
  return static_cast<int>(m->bond_types.size()) - 1;
}

int addFlexionType(Model* m, const std::string& name, double k, double rest_angle,
                   double damping = 0) {
  BondType t;
  t.name = name;
  t.kind = BondKind::kFlexion;
  t.param(kStiffness) = value(k);
  t.param(kRestAngle) = value(rest_angle);
  if (damping != 0) t.param(kDamping) = value(damping);
  m->bond_types.push_back(t);
  return static_cast<int>(m->bond_types.size()) - 1;
}

using test::addBond;

void setGravity(Model* m, double gz) { m->gravity_mps2[2] = value(gz); }

/// A small 3-D closed system: 5 particles, springs with a cubic term, two flexion bonds.
Model closedSystem(bool damped) {
  Model m;
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  const Vec pos[5] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.2}, {0.5, 0.5, 1}};
  for (int i = 0; i < 5; ++i)
    addParticle(&m, pos[i] + Vec(u(rng), u(rng), u(rng)), 0.5 + 0.25 * i, false, "",
                Vec(u(rng), u(rng), u(rng)) * 5.0);
  const int s = addSpringType(&m, "s", 20.0, 1.0, damped ? 0.3 : 0.0, 15.0);
  const int d = addSpringType(&m, "d", 8.0, 1.3, damped ? 0.1 : 0.0);
  const int f = addFlexionType(&m, "f", 0.7, 1.4, damped ? 0.05 : 0.0);
  addBond(&m, s, 0, 1);
  addBond(&m, s, 1, 2);
  addBond(&m, s, 2, 3);
  addBond(&m, s, 3, 0);
  for (int i = 0; i < 4; ++i) addBond(&m, d, i, 4);
  addBond(&m, d, 0, 2);
  addBond(&m, f, 0, 1, 2);
  addBond(&m, f, 1, 4, 3);
  return m;
}

Vec momentum(const Model& m, const State& s) {
  Vec p = Vec::Zero();
  for (size_t i = 0; i < s.v_mps.size(); ++i) p += m.particles[i].mass_kg * s.v_mps[i];
  return p;
}

TEST(Simulator, UndampedClosedSystemConservesEnergy) {
  // Semi-implicit Euler is symplectic: the energy error stays bounded, of order dt. With
  // dt = 1e-4 s here the relative deviation must stay below 1e-3 over 10000 steps.
  const double kRelativeEnergyBound = 1e-3;
  Model m = closedSystem(false);
  Simulator sim(m);
  State s = sim.initialState();
  const double e0 = sim.totalEnergy(s);
  ASSERT_GT(e0, 0.0);
  double max_dev = 0.0;
  for (int k = 0; k < 10000; ++k) {
    sim.step(&s, 1e-4);
    max_dev = std::max(max_dev, std::fabs(sim.totalEnergy(s) - e0));
  }
  EXPECT_LT(max_dev / e0, kRelativeEnergyBound);
  std::printf("relative energy deviation over 10000 steps: %.3g\n", max_dev / e0);
  // The motion is not trivial: the particles really moved.
  EXPECT_GT((s.x_m[4] - m.particles[4].position_m).norm(), 1e-2);
}

TEST(Simulator, DampedClosedSystemConservesMomentumAndLosesEnergy) {
  Model m = closedSystem(true);
  Simulator sim(m);
  State s = sim.initialState();
  const Vec p0 = momentum(m, s);
  const double e0 = sim.totalEnergy(s);
  for (int k = 0; k < 5000; ++k) sim.step(&s, 1e-3);
  EXPECT_LT((momentum(m, s) - p0).norm(), 1e-12 * (1.0 + p0.norm()));
  EXPECT_LT(sim.totalEnergy(s), e0);
}

TEST(Simulator, FixedParticlesDoNotMove) {
  Model m;
  setGravity(&m, -9.81);
  const int a = addParticle(&m, Vec(0, 0, 0), 1.0, true);
  const int b = addParticle(&m, Vec(1, 0, 0), 1.0, false);
  const int c = addParticle(&m, Vec(2, 0, 0), 1.0, true);
  const int s = addSpringType(&m, "s", 50.0, 0.8, 0.5);
  addBond(&m, s, a, b);
  addBond(&m, s, b, c);
  Simulator sim(m);
  State st = sim.initialState();
  for (int k = 0; k < 200; ++k) sim.stepFrame(&st, 0.01);
  EXPECT_EQ(st.x_m[a], m.particles[a].position_m);
  EXPECT_EQ(st.x_m[c], m.particles[c].position_m);
  EXPECT_EQ(st.v_mps[a], Vec::Zero());
  EXPECT_LT(st.x_m[b].z(), -0.01);  // the free one sagged
}

Model clampModel(bool fix_a) {
  Model m;
  addParticle(&m, Vec(0, 0, 0), 1.0, fix_a);
  addParticle(&m, Vec(2, 1, 0), 1.0, false);
  // No elastic force: only the clamp acts, so the result is exactly the clamp's.
  const int s = addSpringType(&m, "s", 0.0, 1.0);
  m.bond_types[s].param(kMaxElongation) = value(0.1);
  addBond(&m, s, 0, 1);
  return m;
}

TEST(Simulator, ProvotClampLimitsElongationBothFree) {
  Model m = clampModel(false);
  Simulator sim(m);
  State s = sim.initialState();
  const Vec mid0 = 0.5 * (s.x_m[0] + s.x_m[1]);
  sim.step(&s, 1e-3);
  EXPECT_NEAR((s.x_m[1] - s.x_m[0]).norm(), 1.1, 1e-12);
  EXPECT_LT((0.5 * (s.x_m[0] + s.x_m[1]) - mid0).norm(), 1e-12);  // moved half each
  EXPECT_EQ(s.v_mps[0], Vec::Zero());  // positions only
}

TEST(Simulator, ProvotClampMovesOnlyTheFreeEnd) {
  Model m = clampModel(true);
  Simulator sim(m);
  State s = sim.initialState();
  sim.step(&s, 1e-3);
  EXPECT_EQ(s.x_m[0], Vec::Zero());
  EXPECT_NEAR((s.x_m[1] - s.x_m[0]).norm(), 1.1, 1e-12);
  EXPECT_LT((s.x_m[1].normalized() - Vec(2, 1, 0).normalized()).norm(), 1e-12);
}

TEST(Simulator, ProvotClampMovesOnlyTheFreeEndWhenTheSecondIsFixed) {
  Model m = clampModel(false);
  m.particles[1].fixed = true;
  Simulator sim(m);
  State s = sim.initialState();
  sim.step(&s, 1e-3);
  EXPECT_EQ(s.x_m[1], Vec(2, 1, 0));
  EXPECT_NEAR((s.x_m[1] - s.x_m[0]).norm(), 1.1, 1e-12);
}

TEST(Simulator, ProvotClampLeavesShortSpringsAlone) {
  Model m = clampModel(false);
  m.particles[1].position_m = Vec(1.05, 0, 0);
  Simulator sim(m);
  State s = sim.initialState();
  sim.step(&s, 1e-3);
  EXPECT_EQ(s.x_m[1], Vec(1.05, 0, 0));
}

TEST(Simulator, StepFrameEqualsSubsteps) {
  Model m = closedSystem(true);
  setGravity(&m, -9.81);
  m.substeps = 4;
  Simulator sim(m);
  State a = sim.initialState(), b = sim.initialState();
  for (int frame = 0; frame < 20; ++frame) {
    sim.stepFrame(&a, 0.02);
    for (int k = 0; k < 4; ++k) sim.step(&b, 0.02 / 4);
  }
  for (size_t i = 0; i < a.x_m.size(); ++i) {
    EXPECT_EQ(a.x_m[i], b.x_m[i]);
    EXPECT_EQ(a.v_mps[i], b.v_mps[i]);
  }
  // And it differs from one big step (substeps really happen).
  Model m1 = m;
  m1.substeps = 1;
  Simulator sim1(m1);
  State c = sim1.initialState();
  for (int frame = 0; frame < 20; ++frame) sim1.stepFrame(&c, 0.02);
  EXPECT_GT((c.x_m[0] - a.x_m[0]).norm(), 0.0);
}

TEST(Simulator, InteractionsOnlyWithinMaxDistance) {
  Model m;
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int i = 0; i < 120; ++i)
    addParticle(&m, Vec(u(rng), u(rng), 0.3 * u(rng)), 1.0, false, i % 4 == 0 ? "jet" : "gas",
                Vec(u(rng), u(rng), 0));
  const int visc = addSpringType(&m, "visc", 0.0, 0.0, 2.5);
  m.bond_types[visc].param(kDampingNl) = value(1.25);
  m.bond_types[visc].param(kMaxDistance) = value(0.7);
  const int elast = addSpringType(&m, "elast", 2.0, 0.5);
  m.bond_types[elast].param(kMaxDistance) = value(0.5);
  m.interactions.push_back({visc, "gas", "gas"});
  m.interactions.push_back({visc, "jet", "gas"});
  m.interactions.push_back({elast, "jet", "jet"});
  m.interactions.push_back({elast, "gas", "jet"});

  Simulator sim(m);
  State s = sim.initialState();
  std::vector<Vec> f;
  sim.computeForces(s, &f);

  // Brute force: every unordered pair of each interaction within its max_distance.
  size_t expected_count = 0;
  std::vector<Vec> expected(m.particles.size(), Vec::Zero());
  for (const Interaction& in : m.interactions) {
    const BondType& type = m.bond_types[in.type];
    SpringLaw law;
    law.stiffness = type.value(kStiffness);
    law.rest_length = type.value(kRestLength);
    law.damping = type.value(kDamping);
    law.damping_nl = type.value(kDampingNl);
    law.max_distance = type.value(kMaxDistance);
    for (size_t i = 0; i < m.particles.size(); ++i)
      for (size_t j = 0; j < m.particles.size(); ++j) {
        if (i == j) continue;
        const bool ij = m.particles[i].group == in.group_a && m.particles[j].group == in.group_b;
        const bool ji = m.particles[j].group == in.group_a && m.particles[i].group == in.group_b;
        if (!ij || (ji && j < i)) continue;  // each unordered pair once
        if ((s.x_m[j] - s.x_m[i]).norm() > law.max_distance) continue;
        ++expected_count;
        addSpringForce(law, s.x_m[i], s.x_m[j], s.v_mps[i], s.v_mps[j], &expected[i], &expected[j]);
      }
  }
  ASSERT_GT(expected_count, 50u);
  EXPECT_EQ(sim.lastInteractionBondCount(), expected_count);
  for (size_t i = 0; i < f.size(); ++i) EXPECT_LT((f[i] - expected[i]).norm(), 1e-12) << i;
}

TEST(Simulator, SimulateTrajectoryShapeAndNames) {
  Model m = closedSystem(true);
  setGravity(&m, -9.81);
  const Trajectory traj = simulateTrajectory(m, 12, 50.0);
  ASSERT_EQ(traj.numFrames(), 12);
  ASSERT_EQ(traj.numMarkers(), 5);
  EXPECT_EQ(traj.validate(), "");
  for (int i = 0; i < 5; ++i) EXPECT_EQ(traj.marker_names[i], m.particles[i].name);
  EXPECT_EQ(traj.countOccluded(), 0u);
  EXPECT_DOUBLE_EQ(traj.frame_rate_hz, 50.0);
  EXPECT_DOUBLE_EQ(traj.times_s[3], 3 / 50.0);
  Simulator sim(m);
  State s = sim.initialState();
  for (int i = 0; i < 5; ++i) EXPECT_EQ(traj.position(0, i), m.particles[i].position_m);
  sim.stepFrame(&s, 1.0 / 50.0);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(traj.position(1, i), s.x_m[i]);
  EXPECT_THROW(simulateTrajectory(m, 3, 0.0), std::exception);
}

TEST(Simulator, SetParametersChangesTheMotion) {
  Model m = closedSystem(false);
  Simulator sim(m);
  State a = sim.initialState();
  sim.step(&a, 1e-2);
  m.bond_types[0].param(kStiffness).value *= 2.0;
  sim.setParameters(m);
  State b = sim.initialState();
  sim.step(&b, 1e-2);
  EXPECT_NE(a.v_mps[0], b.v_mps[0]);
}

}  // namespace
}  // namespace mme

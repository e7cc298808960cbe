// Force laws against their energies (finite differences) and the physical invariants.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <functional>
#include <random>

#include "motion_model_estimation/core/forces.h"
#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/simulator.h"

namespace mme {
namespace {

using Vec = Eigen::Vector3d;

Vec randomVec(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return Vec(u(rng), u(rng), u(rng));
}

/// Central-difference gradient of energy(x) with respect to x (one point).
Vec numericGradient(const std::function<double(const Vec&)>& energy, const Vec& x, double h) {
  Vec g;
  for (int k = 0; k < 3; ++k) {
    Vec xp = x, xm = x;
    xp[k] += h;
    xm[k] -= h;
    g[k] = (energy(xp) - energy(xm)) / (2.0 * h);
  }
  return g;
}

void expectVecNear(const Vec& a, const Vec& b, double rel_tol, double abs_floor) {
  const double scale = std::max(abs_floor, std::max(a.norm(), b.norm()));
  EXPECT_LE((a - b).norm(), rel_tol * scale) << "a = " << a.transpose() << "  b = " << b.transpose();
}

TEST(SpringForce, EqualsMinusEnergyGradientLinearAndCubic) {
  std::mt19937_64 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    SpringLaw law;
    law.stiffness = 1.0 + 10.0 * (trial % 5);
    law.rest_length = 0.5 + 0.1 * trial;
    law.stiffness_nl = (trial % 2) ? 37.0 : 0.0;
    const Vec xa = randomVec(rng, 1.0), xb = randomVec(rng, 1.0), zero = Vec::Zero();
    Vec fa = Vec::Zero(), fb = Vec::Zero();
    addSpringForce(law, xa, xb, zero, zero, &fa, &fb);
    const Vec ga = numericGradient([&](const Vec& p) { return springEnergy(law, p, xb); }, xa, 1e-6);
    const Vec gb = numericGradient([&](const Vec& p) { return springEnergy(law, xa, p); }, xb, 1e-6);
    expectVecNear(fa, -ga, 1e-6, 1e-9);
    expectVecNear(fb, -gb, 1e-6, 1e-9);
  }
}

TEST(SpringForce, InternalForcesSumToZeroWithDamping) {
  std::mt19937_64 rng(2);
  SpringLaw law{3.0, 0.7, 0.4, 5.0, 0.2, 0.0, 1e300};
  for (int trial = 0; trial < 10; ++trial) {
    Vec fa = Vec::Zero(), fb = Vec::Zero();
    addSpringForce(law, randomVec(rng, 1), randomVec(rng, 1), randomVec(rng, 2), randomVec(rng, 2),
                   &fa, &fb);
    EXPECT_GT(fa.norm(), 0.0);
    EXPECT_LE((fa + fb).norm(), 1e-14 * fa.norm());
  }
}

TEST(SpringForce, DampingOpposesRelativeVelocity) {
  std::mt19937_64 rng(3);
  for (bool quadratic : {false, true}) {
    SpringLaw law;  // damping only: no elastic force
    law.damping = quadratic ? 0.0 : 2.0;
    law.damping_nl = quadratic ? 1.5 : 0.0;
    for (int trial = 0; trial < 10; ++trial) {
      const Vec xa = randomVec(rng, 1), xb = randomVec(rng, 1);
      const Vec va = randomVec(rng, 1), vb = randomVec(rng, 1);
      Vec fa = Vec::Zero(), fb = Vec::Zero();
      addSpringForce(law, xa, xb, va, vb, &fa, &fb);
      // The force on b does negative work on the relative motion (dissipation).
      EXPECT_LT(fb.dot(vb - va), 0.0);
      const Vec u = (xb - xa).normalized();
      const double s = (vb - va).dot(u);
      const double expected = quadratic ? 1.5 * s * std::fabs(s) : 2.0 * s;
      expectVecNear(fa, expected * u, 1e-12, 1e-15);
    }
  }
}

TEST(SpringForce, ConditionalSpringZeroOutsideRangeEqualInside) {
  SpringLaw plain{4.0, 1.0, 0.3, 2.0, 0.1, 0.0, 1e300};
  SpringLaw cond = plain;
  cond.min_distance = 0.8;
  cond.max_distance = 1.5;
  const Vec xa = Vec::Zero(), va(0.1, 0, 0), vb(-0.2, 0.3, 0);
  for (double l : {0.5, 0.79, 0.8, 1.0, 1.2, 1.5, 1.51, 3.0}) {
    const Vec xb(l, 0, 0);
    Vec fa1 = Vec::Zero(), fb1 = Vec::Zero(), fa2 = Vec::Zero(), fb2 = Vec::Zero();
    addSpringForce(plain, xa, xb, va, vb, &fa1, &fb1);
    addSpringForce(cond, xa, xb, va, vb, &fa2, &fb2);
    if (l < 0.8 || l > 1.5) {
      EXPECT_EQ(fa2.norm(), 0.0) << l;
      EXPECT_EQ(fb2.norm(), 0.0) << l;
      EXPECT_EQ(springEnergy(cond, xa, xb), 0.0) << l;
    } else {
      EXPECT_EQ(fa2, fa1) << l;
      EXPECT_EQ(fb2, fb1) << l;
      EXPECT_EQ(springEnergy(cond, xa, xb), springEnergy(plain, xa, xb)) << l;
    }
  }
}

TEST(SpringForce, ZeroLengthGivesNoForceAndNoNaN) {
  SpringLaw law{4.0, 1.0, 0.3, 2.0, 0.1, 0.0, 1e300};
  Vec fa = Vec::Zero(), fb = Vec::Zero();
  addSpringForce(law, Vec(1, 2, 3), Vec(1, 2, 3), Vec(1, 0, 0), Vec(0, 1, 0), &fa, &fb);
  EXPECT_TRUE(fa.allFinite());
  EXPECT_EQ(fa.norm(), 0.0);
  EXPECT_EQ(fb.norm(), 0.0);
}

struct FlexionConfig {
  Vec a, b, c;
};

FlexionConfig randomNonDegenerate(std::mt19937_64& rng) {
  for (;;) {
    FlexionConfig cfg{randomVec(rng, 1), randomVec(rng, 1), randomVec(rng, 1)};
    const double th = flexionAngle(cfg.a, cfg.b, cfg.c);
    if ((cfg.a - cfg.b).norm() > 0.2 && (cfg.c - cfg.b).norm() > 0.2 && th > 0.1 && th < M_PI - 0.1)
      return cfg;
  }
}

void checkFlexionGradient(const FlexionLaw& law, const FlexionConfig& cfg) {
  const Vec zero = Vec::Zero();
  Vec fa = Vec::Zero(), fb = Vec::Zero(), fc = Vec::Zero();
  addFlexionForce(law, cfg.a, cfg.b, cfg.c, zero, zero, zero, &fa, &fb, &fc);
  const double h = 1e-6;
  const Vec ga = numericGradient([&](const Vec& p) { return flexionEnergy(law, p, cfg.b, cfg.c); }, cfg.a, h);
  const Vec gb = numericGradient([&](const Vec& p) { return flexionEnergy(law, cfg.a, p, cfg.c); }, cfg.b, h);
  const Vec gc = numericGradient([&](const Vec& p) { return flexionEnergy(law, cfg.a, cfg.b, p); }, cfg.c, h);
  expectVecNear(fa, -ga, 1e-6, 1e-9);
  expectVecNear(fb, -gb, 1e-6, 1e-9);
  expectVecNear(fc, -gc, 1e-6, 1e-9);
}

TEST(FlexionForce, EqualsMinusEnergyGradient) {
  std::mt19937_64 rng(4);
  for (int trial = 0; trial < 30; ++trial) {
    FlexionLaw law{0.5 + trial * 0.1, (trial % 3 == 0) ? 0.0 : 0.3 * (trial % 10), 0.0};
    checkFlexionGradient(law, randomNonDegenerate(rng));
  }
}

TEST(FlexionForce, EqualsMinusEnergyGradientNearPi) {
  // Nearly straight (theta close to pi) with rest angle pi and another rest angle.
  for (double rest : {M_PI, 2.5}) {
    for (double bend : {1e-2, 1e-3}) {
      FlexionLaw law{2.0, rest, 0.0};
      FlexionConfig cfg{Vec(-1, 0, 0), Vec(0, 0, 0), Vec(std::cos(bend), std::sin(bend), 0.1 * bend)};
      ASSERT_GT(flexionAngle(cfg.a, cfg.b, cfg.c), M_PI - 0.02);
      checkFlexionGradient(law, cfg);
    }
  }
}

TEST(FlexionForce, AngleIsCorrect) {
  EXPECT_NEAR(flexionAngle(Vec(1, 0, 0), Vec::Zero(), Vec(0, 1, 0)), M_PI / 2, 1e-15);
  EXPECT_NEAR(flexionAngle(Vec(1, 0, 0), Vec::Zero(), Vec(-1, 0, 0)), M_PI, 1e-15);
  EXPECT_NEAR(flexionAngle(Vec(2, 0, 0), Vec::Zero(), Vec(1, 1, 0)), M_PI / 4, 1e-15);
}

TEST(FlexionForce, SumAndTorqueZeroWithDamping) {
  std::mt19937_64 rng(5);
  FlexionLaw law{1.3, 0.8, 0.4};
  for (int trial = 0; trial < 20; ++trial) {
    const FlexionConfig cfg = randomNonDegenerate(rng);
    Vec fa = Vec::Zero(), fb = Vec::Zero(), fc = Vec::Zero();
    addFlexionForce(law, cfg.a, cfg.b, cfg.c, randomVec(rng, 1), randomVec(rng, 1),
                    randomVec(rng, 1), &fa, &fb, &fc);
    const double scale = fa.norm() + fb.norm() + fc.norm();
    ASSERT_GT(scale, 0.0);
    EXPECT_LE((fa + fb + fc).norm(), 1e-13 * scale);
    const Vec torque = cfg.a.cross(fa) + cfg.b.cross(fb) + cfg.c.cross(fc);
    EXPECT_LE(torque.norm(), 1e-13 * scale);
  }
}

TEST(FlexionForce, DampingOpposesAngularVelocity) {
  // Damping alone: the power of the three forces is -c (dtheta/dt)^2 < 0 (dissipation), and
  // dtheta/dt from a finite difference of the angle matches the force magnitude.
  std::mt19937_64 rng(6);
  FlexionLaw law{0.0, 0.0, 0.7};
  for (int trial = 0; trial < 20; ++trial) {
    const FlexionConfig cfg = randomNonDegenerate(rng);
    const Vec va = randomVec(rng, 1), vb = randomVec(rng, 1), vc = randomVec(rng, 1);
    Vec fa = Vec::Zero(), fb = Vec::Zero(), fc = Vec::Zero();
    addFlexionForce(law, cfg.a, cfg.b, cfg.c, va, vb, vc, &fa, &fb, &fc);
    const double power = fa.dot(va) + fb.dot(vb) + fc.dot(vc);
    const double h = 1e-7;
    const double theta_dot = (flexionAngle(cfg.a + h * va, cfg.b + h * vb, cfg.c + h * vc) -
                              flexionAngle(cfg.a - h * va, cfg.b - h * vb, cfg.c - h * vc)) /
                             (2 * h);
    EXPECT_LT(power, 0.0);
    EXPECT_NEAR(power, -0.7 * theta_dot * theta_dot, 1e-6 * (1.0 + std::fabs(power)));
  }
}

TEST(FlexionForce, DegenerateConfigurationsGiveNoForce) {
  FlexionLaw law{1.0, 1.0, 1.0};
  const Vec zero = Vec::Zero(), v(1, 2, 3);
  for (const FlexionConfig& cfg : {FlexionConfig{Vec(1, 0, 0), Vec(0, 0, 0), Vec(-2, 0, 0)},
                                   FlexionConfig{Vec(1, 0, 0), Vec(0, 0, 0), Vec(2, 0, 0)},
                                   FlexionConfig{Vec(0, 0, 0), Vec(0, 0, 0), Vec(1, 1, 0)}}) {
    Vec fa = Vec::Zero(), fb = Vec::Zero(), fc = Vec::Zero();
    addFlexionForce(law, cfg.a, cfg.b, cfg.c, v, zero, v, &fa, &fb, &fc);
    EXPECT_EQ(fa.norm() + fb.norm() + fc.norm(), 0.0);
  }
}

// Gravity and unary viscosity through the simulator's force evaluation.
TEST(UnaryForces, GravityIsMinusGradientOfPotentialAndViscosityIsMinusCV) {
  Model model;
  model.gravity_mps2[0].present = true;
  model.gravity_mps2[0].value = 0.5;
  model.gravity_mps2[2].present = true;
  model.gravity_mps2[2].value = -9.81;
  Particle p;
  p.name = "p";
  p.mass_kg = 2.5;
  p.position_m = Vec(0.3, -0.2, 1.0);
  p.velocity_mps = Vec(1.0, -2.0, 0.5);
  model.particles.push_back(p);
  Particle q = p;
  q.name = "q";
  q.fixed = true;  // gravity acts on fixed particles too
  model.particles.push_back(q);
  BondType visc;
  visc.name = "air";
  visc.kind = BondKind::kViscosity;
  visc.param(kViscosity).present = true;
  visc.param(kViscosity).has_value = true;
  visc.param(kViscosity).value = 0.8;
  model.bond_types.push_back(visc);
  Bond b;
  b.type = 0;
  b.particles = {{0, -1, -1}};
  model.bonds.push_back(b);

  Simulator sim(model);
  State s = sim.initialState();
  std::vector<Vec> f;
  sim.computeForces(s, &f);
  // Gravitational potential U = -m g.x; force = -grad U, checked by central differences.
  const Vec g = model.gravity();
  // The potential is linear, so a large step is exact up to rounding (~eps |U| / h).
  const Vec grad = numericGradient([&](const Vec& x) { return -p.mass_kg * g.dot(x); }, p.position_m, 1e-2);
  expectVecNear(f[1], -grad, 1e-12, 1e-12);
  expectVecNear(f[1], p.mass_kg * g, 1e-15, 1e-15);
  expectVecNear(f[0], -grad - 0.8 * p.velocity_mps, 1e-12, 1e-12);
  const Vec viscous = f[0] - f[1];
  EXPECT_LT(viscous.dot(p.velocity_mps), 0.0);
}

}  // namespace
}  // namespace mme

// ShortTermCost: zero at the truth, sensitivity to every parameter, occlusion rules, static
// single-frame mode, interactions, thread determinism, and agreement with the Simulator.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "test_helpers.h"

namespace mme {
namespace {

using Vec = Eigen::Vector3d;

using test::addBond;
using test::addParticle;
using test::addType;
Param value(double v, bool free = false) { return test::valueParam(v, free); }

/// A 4x3 sheet with every kind of bond and every parameter free (all non-zero so a 1%
/// perturbation changes something), one fixed corner, gravity free.
Model sheetModel() {
  Model m;
  m.frame_rate_hz = 100.0;
  m.gravity_mps2[2] = value(-9.81, true);
  const int nx = 4, ny = 3;
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      addParticle(&m, Vec(0.5 * i, 0.5 * j, 0.1 * u(rng)), 0.2 + 0.05 * i, i == 0 && j == 0, "",
                  Vec(u(rng), u(rng), u(rng)));
  const int s = addType(&m, "s", BondKind::kSpring,
                        {{kStiffness, 40.0}, {kRestLength, 0.45}, {kDamping, 0.3},
                         {kStiffnessNl, 200.0}, {kDampingNl, 0.2}});
  const int d = addType(&m, "d", BondKind::kSpring, {{kStiffness, 15.0}, {kRestLength, 0.72}});
  const int f = addType(&m, "f", BondKind::kFlexion,
                        {{kStiffness, 0.5}, {kRestAngle, 2.8}, {kDamping, 0.02}});
  const int v = addType(&m, "air", BondKind::kViscosity, {{kViscosity, 0.05}});
  auto id = [nx](int i, int j) { return j * nx + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (i + 1 < nx) addBond(&m, s, id(i, j), id(i + 1, j));
      if (j + 1 < ny) addBond(&m, s, id(i, j), id(i, j + 1));
      if (i + 1 < nx && j + 1 < ny) addBond(&m, d, id(i, j), id(i + 1, j + 1));
      if (i + 2 < nx) addBond(&m, f, id(i, j), id(i + 1, j), id(i + 2, j));
      addBond(&m, v, id(i, j));
    }
  return m;
}

/// Reference cost computed with the Simulator, independently of ShortTermCost's bookkeeping.
double referenceCost(const Model& model, const Trajectory& traj) {
  Simulator sim(model);
  const double h = 1.0 / model.frame_rate_hz;
  const int n = traj.numMarkers();
  double total = 0.0;
  for (int t = 1; t + 1 < traj.numFrames(); ++t) {
    State s = sim.initialState();
    for (int i = 0; i < n; ++i) {
      s.x_m[i] = traj.position(t, i);
      if (!model.particles[i].fixed) s.v_mps[i] = (traj.position(t, i) - traj.position(t - 1, i)) / h;
    }
    sim.stepFrame(&s, h);
    for (int i = 0; i < n; ++i) total += (s.x_m[i] - traj.position(t + 1, i)).squaredNorm();
  }
  return total;
}

TEST(Cost, ZeroAtTruthAndGrowsWhenAnyParameterIsPerturbed) {
  const Model model = sheetModel();
  const Trajectory traj = simulateTrajectory(model, 40, model.frame_rate_hz);
  ShortTermCost cost(model, traj);
  const std::vector<double> truth = getValues(model, cost.freeParameters());
  ASSERT_EQ(truth.size(), 12u);
  ASSERT_EQ(cost.termCount(), 38u * 12u);
  const double c0 = cost.evaluate(truth, nullptr);
  // At the truth the only error is the rounding of the observed velocity (x(t) - x(t-1))/h:
  // ~1e-16 m per coordinate, i.e. ~1e-32 m^2 per term. Bound: 1e-26 m^2 per term.
  EXPECT_LT(c0 / cost.termCount(), 1e-26);
  std::printf("sheet: cost at truth %.3g m^2 over %llu terms\n", c0,
              static_cast<unsigned long long>(cost.termCount()));
  for (size_t k = 0; k < truth.size(); ++k)
    for (double factor : {1.01, 0.99}) {
      std::vector<double> p = truth;
      p[k] *= factor;
      const double c = cost.evaluate(p, nullptr);
      EXPECT_TRUE(std::isfinite(c));
      EXPECT_GT(c, 1e6 * c0 + 1e-24) << cost.freeParameters()[k].name << " x" << factor;
    }
}

TEST(Cost, LocalCostsSumToGlobalAndMatchTheSimulator) {
  Model model = sheetModel();
  model.substeps = 3;
  // Clamps active: the rest length is short and max_elongation small.
  model.bond_types[0].param(kMaxElongation) = value(0.05);
  Trajectory traj = simulateTrajectory(model, 30, model.frame_rate_hz);
  addGaussianNoise(&traj, 1e-3, 7);
  ShortTermCost cost(model, traj);
  const std::vector<double> truth = getValues(model, cost.freeParameters());
  std::vector<double> local;
  const double c = cost.evaluate(truth, &local);
  ASSERT_EQ(local.size(), 12u);
  double sum = 0.0;
  for (double l : local) {
    EXPECT_GE(l, 0.0);
    sum += l;
  }
  EXPECT_EQ(sum, c);
  const double ref = referenceCost(model, traj);
  EXPECT_GT(ref, 0.0);
  EXPECT_NEAR(c, ref, 1e-12 * ref);
}

TEST(Cost, ParallelEqualsSerialAndIsDeterministic) {
  const Model model = sheetModel();
  Trajectory traj = simulateTrajectory(model, 60, model.frame_rate_hz);
  addGaussianNoise(&traj, 1e-4, 3);
  ShortTermCost cost(model, traj);
  std::vector<double> p = getValues(model, cost.freeParameters());
  p[0] *= 1.1;
  std::vector<double> l1, l2, l2b, l5;
  const double c1 = cost.evaluate(p, &l1);
  const double c2 = cost.evaluateParallel(p, &l2, 2);
  const double c2b = cost.evaluateParallel(p, &l2b, 2);
  const double c5 = cost.evaluateParallel(p, &l5, 5);
  EXPECT_NEAR(c2, c1, 1e-12 * c1);
  EXPECT_NEAR(c5, c1, 1e-12 * c1);
  EXPECT_EQ(c2, c2b);  // bit for bit
  EXPECT_EQ(l2, l2b);
  for (size_t i = 0; i < l1.size(); ++i) EXPECT_NEAR(l2[i], l1[i], 1e-12 * c1);
  // More threads than frames and a single thread fall back gracefully.
  EXPECT_NEAR(cost.evaluateParallel(p, nullptr, 1000), c1, 1e-12 * c1);
  EXPECT_EQ(cost.evaluateParallel(p, nullptr, 1), c1);
}

/// A chain p0 - p1 - ... - p7 of springs (hop distance = index distance).
Model chainModel(int substeps) {
  Model m;
  m.frame_rate_hz = 50.0;
  m.substeps = substeps;
  for (int i = 0; i < 8; ++i) addParticle(&m, Vec(i, 0.1 * (i % 2), 0), 1.0, false, "", Vec(0, 0.5 * i, 0));
  const int s = addType(&m, "s", BondKind::kSpring, {{kStiffness, 5.0}, {kRestLength, 0.9}});
  for (int i = 0; i + 1 < 8; ++i) addBond(&m, s, i, i + 1);
  return m;
}

// The residual vector behind the cost (least-squares refinements use it): its squares sum to
// the cost, one x y z triple per term, zero at the truth and moved by a parameter change, with
// occluded terms left out.
TEST(Cost, ResidualsAreTheCostAsASumOfSquares) {
  const Model model = chainModel(1);  // one explicit step per frame: exact at the truth
  Trajectory traj = simulateTrajectory(model, 20, 50.0);
  traj.occluded[10 * 8 + 3] = 1;
  traj.position(10, 3) = Vec::Zero();
  ShortTermCost cost(model, traj);
  ASSERT_EQ(cost.residualCount(), 3 * cost.termCount());
  std::vector<double> p = getValues(model, cost.freeParameters());
  std::vector<double> r;
  EXPECT_NEAR(cost.residuals(p, &r), 0.0, 1e-20);
  ASSERT_EQ(r.size(), cost.residualCount());
  for (double x : r) EXPECT_NEAR(x, 0.0, 1e-10);
  p[0] *= 1.3;
  const double c = cost.residuals(p, &r);
  double sum = 0.0, largest = 0.0;
  for (double x : r) {
    sum += x * x;
    largest = std::max(largest, std::abs(x));
  }
  EXPECT_GT(largest, 1e-6);
  EXPECT_NEAR(sum, c, 1e-12 * c);
  EXPECT_EQ(c, cost.evaluate(p, nullptr));  // the same cost, summed the same way
}

TEST(Cost, OcclusionDropsExactlyTheExpectedTerms) {
  for (int substeps : {1, 2}) {
    const Model model = chainModel(substeps);
    const Trajectory full = simulateTrajectory(model, 20, 50.0);
    Trajectory occ = full;
    const int k = 3, t0 = 10;
    occ.occluded[t0 * 8 + k] = 1;
    occ.position(t0, k) = Vec::Zero();
    ShortTermCost cf(model, full), co(model, occ);
    // Dropped: (k, t0-1) because x_k(t0) is the target; frames t0 and t0+1 (x(t) resp.
    // x(t-1) missing) for every particle within `substeps` hops of k.
    const uint64_t near = 2 * substeps + 1;
    EXPECT_EQ(cf.termCount() - co.termCount(), 1 + 2 * near) << substeps;
    std::vector<double> p = getValues(model, cf.freeParameters());
    p[0] *= 1.3;
    std::vector<double> lf, lo;
    cf.evaluate(p, &lf);
    const double c = co.evaluate(p, &lo);
    EXPECT_TRUE(std::isfinite(c));
    for (int i = 0; i < 8; ++i) {
      if (std::abs(i - k) > substeps)
        EXPECT_EQ(lo[i], lf[i]) << "particle " << i;  // untouched terms: identical predictions
      else
        EXPECT_LT(lo[i], lf[i]) << "particle " << i;
    }
  }
}

TEST(Cost, FullyOccludedParticleKeepsCostFinite) {
  const Model model = chainModel(1);
  Trajectory traj = simulateTrajectory(model, 10, 50.0);
  for (int t = 0; t < 10; ++t) traj.occluded[t * 8 + 7] = 1;
  ShortTermCost cost(model, traj);
  EXPECT_EQ(cost.termCount(), 8u * 6u);  // p6 and p7 never valid
  EXPECT_TRUE(std::isfinite(cost.evaluate(getValues(model, cost.freeParameters()), nullptr)));
}

// A fixed particle is where the model holds it, seen or not: hiding it in every frame (an
// anchor without a marker) drops its own terms only, not its neighbours' (they once all went,
// and a model with anchors, every particle bonded to one, had no term at all).
TEST(Cost, AHiddenFixedParticleDropsOnlyItsOwnTerms) {
  const Model model = sheetModel();
  ASSERT_TRUE(model.particles[0].fixed);
  const Trajectory full = simulateTrajectory(model, 12, 100.0);
  Trajectory hidden = full;
  for (int t = 0; t < hidden.numFrames(); ++t) {
    hidden.occluded[t * 12 + 0] = 1;
    hidden.position(t, 0) = Vec::Zero();
  }
  ShortTermCost cf(model, full), ch(model, hidden);
  EXPECT_EQ(cf.termCount() - ch.termCount(), 10u);  // (0, t) for t = 1..10
  std::vector<double> p = getValues(model, cf.freeParameters());
  EXPECT_LT(ch.evaluate(p, nullptr), 1e-24);
  p[0] *= 1.3;
  std::vector<double> lf, lh;
  cf.evaluate(p, &lf);
  ch.evaluate(p, &lh);
  EXPECT_GT(lh[1], 0.0);
  for (int i = 1; i < 12; ++i) EXPECT_EQ(lh[i], lf[i]) << "particle " << i;
}

Trajectory singleFrame(const Model& model) {
  Trajectory traj;
  for (const Particle& p : model.particles) traj.marker_names.push_back(p.name);
  traj.resize(1);
  for (size_t i = 0; i < model.particles.size(); ++i) {
    traj.positions_m[i] = model.particles[i].position_m;
    traj.occluded[i] = 0;
  }
  return traj;
}

TEST(Cost, StaticSingleFrameZeroAtEquilibrium) {
  // A mass hanging under gravity from a fixed anchor at exactly its equilibrium length.
  Model hanging;
  hanging.frame_rate_hz = 30.0;
  hanging.gravity_mps2[2] = value(-9.81);
  const double k = 50.0, rest = 0.4, mass = 0.3;
  const int s = addType(&hanging, "s", BondKind::kSpring, {{kStiffness, k}, {kRestLength, rest}});
  addParticle(&hanging, Vec(0, 0, 0), 1.0, true);
  addParticle(&hanging, Vec(0, 0, -(rest + mass * 9.81 / k)), mass);
  addBond(&hanging, s, 0, 1);
  ShortTermCost cost(hanging, singleFrame(hanging));
  EXPECT_EQ(cost.termCount(), 2u);
  EXPECT_EQ(cost.bondEvaluationsPerCall(), 1u);
  const std::vector<double> truth = getValues(hanging, cost.freeParameters());
  ASSERT_EQ(truth.size(), 2u);
  // Only the rounding of k e vs m g remains: ~1e-15 N, i.e. ~1e-18 m over one frame.
  EXPECT_LT(cost.evaluate(truth, nullptr), 1e-30);
  for (size_t p = 0; p < truth.size(); ++p) {
    std::vector<double> off = truth;
    off[p] *= 1.01;
    EXPECT_GT(cost.evaluate(off, nullptr), 1e-12);
  }

  // A particle midway between two fixed anchors, no gravity: exactly balanced.
  Model between;
  between.frame_rate_hz = 30.0;
  const int h = addType(&between, "h", BondKind::kSpring, {{kStiffness, 7.0}, {kRestLength, 0.8}});
  addParticle(&between, Vec(2, 0, 0), 1.0, true);
  addParticle(&between, Vec(3, 0, 0), 1.0, false);
  addParticle(&between, Vec(4, 0, 0), 1.0, true);
  addBond(&between, h, 0, 1);
  addBond(&between, h, 1, 2);
  ShortTermCost cost2(between, singleFrame(between));
  const std::vector<double> t2 = getValues(between, cost2.freeParameters());
  EXPECT_EQ(cost2.evaluate(t2, nullptr), 0.0);
  between.particles[1].position_m.x() = 3.1;  // off equilibrium
  ShortTermCost cost3(between, singleFrame(between));
  EXPECT_GT(cost3.evaluate(t2, nullptr), 1e-12);
}

TEST(Cost, StaticSingleFrameNeedsModelRate) {
  Model m = chainModel(1);
  m.frame_rate_hz = 0.0;
  Trajectory one = singleFrame(m);
  one.frame_rate_hz = 100.0;
  EXPECT_THROW(ShortTermCost(m, one), InputError);
}

TEST(Cost, RejectsMismatchedTrajectoryAndMissingRate) {
  Model m = chainModel(1);
  Trajectory traj = simulateTrajectory(m, 5, 50.0);
  Model fewer = m;
  fewer.particles.pop_back();
  fewer.bonds.pop_back();
  EXPECT_THROW(ShortTermCost(fewer, traj), InputError);
  Model no_rate = m;
  no_rate.frame_rate_hz = 0.0;
  traj.frame_rate_hz = 0.0;
  EXPECT_THROW(ShortTermCost(no_rate, traj), InputError);
  traj.frame_rate_hz = 50.0;  // the data's rate is used when the model has none
  EXPECT_NO_THROW(ShortTermCost(no_rate, traj));
}

/// Small 2-D fluid: gas on a unit grid, a jet of fast particles shot into it.
Model fluidModel(bool free_max_distance) {
  Model m;
  m.frame_rate_hz = 25.0;
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) addParticle(&m, Vec(i, j, 0), 1.0, false, "gas");
  for (int i = 0; i < 6; ++i)
    addParticle(&m, Vec(-1.0 - 0.7 * i, 3.5 + 0.3 * (i % 2), 0), 1.0, false, "jet", Vec(6, 0, 0));
  const int gas_visc = addType(&m, "gas_visc", BondKind::kSpring,
                               {{kDamping, 2.5}, {kDampingNl, 1.25}, {kMaxDistance, 1.5}});
  const int jet_visc = addType(&m, "jet_visc", BondKind::kSpring,
                               {{kDamping, 4.0}, {kDampingNl, 2.0}, {kMaxDistance, 2.0}});
  const int elast = addType(&m, "elast", BondKind::kSpring,
                            {{kStiffness, 2.0}, {kRestLength, 1.1}, {kMaxDistance, 1.1}});
  for (BondType& t : m.bond_types) {
    t.param(kMaxDistance).free = free_max_distance;
    t.param(kMaxDistance).has_max = free_max_distance;
    t.param(kMaxDistance).max = 1.3 * t.param(kMaxDistance).value;
  }
  m.interactions.push_back({gas_visc, "gas", "gas"});
  m.interactions.push_back({jet_visc, "jet", "gas"});
  m.interactions.push_back({jet_visc, "jet", "jet"});
  m.interactions.push_back({elast, "gas", "gas"});
  m.interactions.push_back({elast, "gas", "jet"});
  m.interactions.push_back({elast, "jet", "jet"});
  return m;
}

uint64_t bruteForceCandidates(const Model& m, const Trajectory& traj, int t, double scale) {
  uint64_t count = 0;
  const int n = traj.numMarkers();
  for (const Interaction& in : m.interactions) {
    const double cutoff = scale * m.bond_types[in.type].param(kMaxDistance).value;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        if (i == j) continue;
        const bool ij = m.particles[i].group == in.group_a && m.particles[j].group == in.group_b;
        const bool ji = m.particles[j].group == in.group_a && m.particles[i].group == in.group_b;
        if (!ij || (ji && j < i)) continue;
        if ((traj.position(t, j) - traj.position(t, i)).norm() <= cutoff) ++count;
      }
  }
  return count;
}

TEST(Cost, InteractionSceneZeroAtTruthAndCountsCandidates) {
  for (bool free_max : {false, true}) {
    const Model model = fluidModel(free_max);
    const Trajectory traj = simulateTrajectory(model, 25, model.frame_rate_hz);
    ShortTermCost cost(model, traj);
    const std::vector<double> truth = getValues(model, cost.freeParameters());
    const double c0 = cost.evaluate(truth, nullptr);
    EXPECT_LT(c0 / cost.termCount(), 1e-26) << free_max;
    std::printf("fluid (free max_distance %d): cost at truth %.3g m^2 over %llu terms\n",
                free_max, c0, static_cast<unsigned long long>(cost.termCount()));
    // Candidates: pairs within max_distance (fixed) or within its upper bound (free).
    uint64_t expected = 0;
    for (int t = 1; t + 1 < traj.numFrames(); ++t)
      expected += bruteForceCandidates(model, traj, t, free_max ? 1.3 : 1.0);
    EXPECT_EQ(cost.bondEvaluationsPerCall(), expected) << free_max;
    std::vector<double> p = truth;
    p[0] *= 1.01;  // gas_visc damping
    EXPECT_GT(cost.evaluate(p, nullptr), 1e6 * c0 + 1e-24);
    EXPECT_NEAR(cost.evaluateParallel(p, nullptr, 2), cost.evaluate(p, nullptr),
                1e-12 * cost.evaluate(p, nullptr));
  }
}

TEST(Cost, InteractionSubstepsMatchTheSimulator) {
  // With substeps the simulator re-finds neighbours every substep; the cost's candidate lists
  // (from frame start, with a motion margin) must still contain every pair that becomes active.
  Model model = fluidModel(false);
  model.substeps = 4;
  Trajectory traj = simulateTrajectory(model, 25, model.frame_rate_hz);
  addGaussianNoise(&traj, 1e-3, 5);
  ShortTermCost cost(model, traj);
  const double c = cost.evaluate(getValues(model, cost.freeParameters()), nullptr);
  const double ref = referenceCost(model, traj);
  EXPECT_GT(ref, 0.0);
  EXPECT_NEAR(c, ref, 1e-12 * ref);
}

TEST(Cost, InteractionGroupOcclusionDropsPartnerGroups) {
  const Model model = fluidModel(false);
  const Trajectory full = simulateTrajectory(model, 10, model.frame_rate_hz);
  Trajectory occ = full;
  const int gas0 = 0, t0 = 5;
  occ.occluded[t0 * occ.numMarkers() + gas0] = 1;
  ShortTermCost cf(model, full), co(model, occ);
  // gas interacts with gas and jet: every particle is dropped in frames t0 and t0+1, plus
  // the target term (gas0, t0-1).
  EXPECT_EQ(cf.termCount() - co.termCount(), 2u * 70u + 1u);
}

TEST(Cost, InteractionGroupOcclusionOnlyDropsInteractingGroups) {
  // Only jet-gas interactions: a missing jet particle hides the gas particles' neighbours (all
  // gas dropped) but not the other jets' (their only partners, the gas, are all known).
  Model model = fluidModel(false);
  model.interactions = {{1, "jet", "gas"}};
  const Trajectory full = simulateTrajectory(model, 10, model.frame_rate_hz);
  Trajectory occ = full;
  const int jet0 = 64, t0 = 5;
  occ.occluded[t0 * occ.numMarkers() + jet0] = 1;
  ShortTermCost cf(model, full), co(model, occ);
  EXPECT_EQ(cf.termCount() - co.termCount(), 2u * (64u + 1u) + 1u);
}

}  // namespace
}  // namespace mme

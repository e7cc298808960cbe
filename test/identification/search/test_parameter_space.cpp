// ParameterSpace: log/linear transforms, bounds, the paper's initialisation, types and sites.
#include <gtest/gtest.h>

#include <cmath>

#include "motion_model_estimation/core/random.h"
#include "motion_model_estimation/identification/search/parameter_space.h"

namespace {

mme::Model twoTypeModel() {
  mme::Model m;
  m.frame_rate_hz = 100;
  for (int i = 0; i < 4; ++i) {
    mme::Particle p;
    p.name = "p" + std::to_string(i);
    p.position_m = Eigen::Vector3d(0.1 * i, 0.02 * i * i, 0);
    m.particles.push_back(p);
  }
  mme::BondType a;
  a.name = "a";
  a.param(mme::kStiffness) = {10.0, true, true, true, 1.0, 100.0, true, true};
  a.param(mme::kRestLength).present = true;
  a.param(mme::kRestLength).free = true;  // no value: initialised from the data
  mme::BondType b;
  b.name = "b";
  b.kind = mme::BondKind::kFlexion;
  b.param(mme::kStiffness) = {2.0, true, true, false};
  b.param(mme::kRestAngle) = {2.5, true, true, true};
  m.bond_types = {a, b};
  m.bonds.push_back({0, {{0, 1, -1}}, "", {}});
  m.bonds.push_back({0, {{1, 2, -1}}, "", {}});
  m.bonds.push_back({1, {{1, 2, 3}}, "", {}});
  m.gravity_mps2[2] = {-9.81, true, true, true};
  return m;
}

mme::Trajectory dataOf(const mme::Model& m) {
  mme::Trajectory t;
  for (const auto& p : m.particles) t.marker_names.push_back(p.name);
  t.frame_rate_hz = 100;
  t.resize(3);
  for (int f = 0; f < 3; ++f)
    for (int i = 0; i < 4; ++i) {
      t.position(f, i) = m.particles[i].position_m * (1.0 + 0.1 * f);
      t.occluded[f * 4 + i] = 0;
    }
  return t;
}

TEST(ParameterSpace, GenesScalesAndBounds) {
  const mme::Model m = twoTypeModel();
  mme::ParameterSpace space(m, dataOf(m));
  ASSERT_EQ(space.size(), 4u);  // a/stiffness, a/rest_length, b/rest_angle, gravity/z
  EXPECT_EQ(space.gene(0).ref.name, "a/stiffness");
  EXPECT_TRUE(space.gene(0).log_scale);
  EXPECT_DOUBLE_EQ(space.gene(0).lower, std::log(1.0));
  EXPECT_DOUBLE_EQ(space.gene(0).upper, std::log(100.0));
  EXPECT_FALSE(space.gene(2).log_scale);  // an angle may be anything in [0, pi]
  EXPECT_DOUBLE_EQ(space.gene(2).upper, M_PI);
  EXPECT_FALSE(space.gene(3).log_scale);  // gravity has a sign
  const std::vector<double> x{0.37, 0.37, 0.37, -9.0};
  const std::vector<double> back = space.toPhysical(space.toSearch(x));
  for (size_t k = 0; k < space.size(); ++k) EXPECT_NEAR(back[k], x[k], 1e-15);
}

TEST(ParameterSpace, RestLengthStartsAtTheAverageObservedDistance) {
  const mme::Model m = twoTypeModel();
  const mme::Trajectory t = dataOf(m);
  mme::ParameterSpace space(m, t);
  double sum = 0;
  int n = 0;
  for (int f = 0; f < 3; ++f) {
    sum += (t.position(f, 1) - t.position(f, 0)).norm() + (t.position(f, 2) - t.position(f, 1)).norm();
    n += 2;
  }
  EXPECT_NEAR(std::exp(space.gene(1).init_center), sum / n, 1e-12);
  // Stiffness has an initial value: the log-Gaussian is centred on it.
  EXPECT_NEAR(std::exp(space.gene(0).init_center), 10.0, 1e-12);
}

TEST(ParameterSpace, ReflectAndSamplesStayInBounds) {
  const mme::Model m = twoTypeModel();
  mme::ParameterSpace space(m, dataOf(m));
  mme::Random random(3);
  for (size_t k = 0; k < space.size(); ++k) {
    const mme::Gene& g = space.gene(k);
    for (double v : {g.lower - 5.3 * (g.upper - g.lower), g.upper + 0.2, g.lower - 1e-9, 1e300,
                     std::nan("")}) {
      const double r = space.reflect(k, v);
      EXPECT_GE(r, g.lower);
      EXPECT_LE(r, g.upper);
    }
    for (int i = 0; i < 1000; ++i) {
      const double s = space.sampleInitial(k, random);
      EXPECT_GE(s, g.lower);
      EXPECT_LE(s, g.upper);
    }
  }
}

TEST(ParameterSpace, GenesAndSitesPerType) {
  const mme::Model m = twoTypeModel();
  mme::ParameterSpace space(m, dataOf(m));
  ASSERT_EQ(space.genesOfType().size(), 3u);  // two types + gravity
  EXPECT_EQ(space.genesOfType()[0], (std::vector<int>{0, 1}));
  EXPECT_EQ(space.genesOfType()[1], (std::vector<int>{2}));
  EXPECT_EQ(space.genesOfType()[2], (std::vector<int>{3}));
  EXPECT_EQ(space.sitesOfType()[0], (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(space.sitesOfType()[1], (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(space.typesWithGenes(), (std::vector<int>{0, 1, 2}));
}

TEST(ParameterSpace, MaxElongationIsSearchedAsAClampLengthAtTheLongestObservedBond) {
  mme::Model m = twoTypeModel();
  m.bond_types[0].param(mme::kMaxElongation) = {0.0, true, false, true};  // free, no value
  const mme::Trajectory t = dataOf(m);
  mme::ParameterSpace space(m, t);
  ASSERT_EQ(space.size(), 5u);  // a/stiffness, a/rest_length, a/max_elongation, b/..., gravity
  const mme::Gene& tau = space.gene(2);
  ASSERT_EQ(tau.ref.name, "a/max_elongation");
  EXPECT_TRUE(tau.clamp_length);
  EXPECT_EQ(tau.rest_gene, 1);
  double longest = 0;
  for (int f = 0; f < 3; ++f)
    longest = std::max({longest, (t.position(f, 1) - t.position(f, 0)).norm(),
                        (t.position(f, 2) - t.position(f, 1)).norm()});
  EXPECT_NEAR(std::exp(tau.init_center), longest, 1e-12);

  // The gene is ln((1 + tau) L): moving the rest length moves tau, not the clamp length.
  std::vector<double> genes{std::log(10.0), std::log(0.1), std::log(0.13), 2.0, -9.81};
  std::vector<double> v = space.toPhysical(genes);
  EXPECT_NEAR(v[1], 0.1, 1e-15);
  EXPECT_NEAR(v[2], 0.3, 1e-12);
  genes[1] = std::log(0.104);
  v = space.toPhysical(genes);
  EXPECT_NEAR((1.0 + v[2]) * v[1], 0.13, 1e-12);
  // Round trip, and d tau / d gene = 1 + tau (checked by a difference quotient).
  const std::vector<double> back = space.toSearch(v);
  for (size_t k = 0; k < genes.size(); ++k) EXPECT_NEAR(back[k], genes[k], 1e-12);
  std::vector<double> moved = genes;
  moved[2] += 1e-7;
  EXPECT_NEAR(space.physicalSlope(2, genes), (space.toPhysical(moved)[2] - v[2]) / 1e-7, 1e-6);
  // A clamp shorter than the rest length is tau's lower bound, not a negative tau.
  genes[2] = std::log(0.05);
  EXPECT_DOUBLE_EQ(space.toPhysical(genes)[2], tau.tau_lower);
  EXPECT_DOUBLE_EQ(space.physicalSlope(2, genes), 0.0);
}

}  // namespace

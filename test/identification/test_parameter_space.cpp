// ParameterSpace: log/linear transforms, bounds, the paper's initialisation, types and sites.
#include <gtest/gtest.h>

#include <cmath>

#include "motion_model_estimation/core/random.h"
#include "motion_model_estimation/identification/parameter_space.h"

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
  m.bonds.push_back({0, {{0, 1, -1}}});
  m.bonds.push_back({0, {{1, 2, -1}}});
  m.bonds.push_back({1, {{1, 2, 3}}});
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
  for (size_t k = 0; k < space.size(); ++k) {
    const double x = k == 3 ? -9.0 : 0.37;
    EXPECT_NEAR(space.toPhysical(k, space.toSearch(k, x)), x, 1e-15);
  }
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

}  // namespace

// Sanity checks on an identified model (pipeline/result_checks.h): a free gravity far from the
// Earth's and a spring whose rest length is nothing next to its markers' distance are said in
// plain words; a plausible model gives no warning; the parameter table's units come from the
// catalogue (per radian on a flexion, m/s^2 for gravity).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/pipeline/result_checks.h"
#include "test_helpers.h"

namespace {


/// Two markers 25 cm apart joined by one spring of the given rest length; gravity free at g.
mme::Model twoMarkers(double rest_length_m, double gravity_z_mps2) {
  mme::Model m;
  m.frame_rate_hz = 100.0;
  mme::test::addParticle(&m, Eigen::Vector3d(0, 0, 0));
  mme::test::addParticle(&m, Eigen::Vector3d(0.25, 0, 0));
  const int type = mme::test::addType(&m, "s00", mme::BondKind::kSpring,
                           {{mme::kStiffness, 100.0}, {mme::kRestLength, rest_length_m}});
  mme::addBond(&m, type, 0, 1);
  for (int c = 0; c < 3; ++c) {
    m.gravity_mps2[c] = mme::valueParam(c == 2 ? gravity_z_mps2 : 0.0);
    m.gravity_mps2[c].free = true;
  }
  return m;
}

mme::Trajectory staticFrames(const mme::Model& m) {
  return mme::simulateTrajectory(m, 5, m.frame_rate_hz);
}

TEST(ResultChecks, PlausibleModelGivesNoWarning) {
  const mme::Model m = twoMarkers(0.25, -9.81);
  EXPECT_TRUE(mme::identifiedModelWarnings(m, staticFrames(m)).empty());
}

TEST(ResultChecks, GravityFarFromEarthsIsFlaggedWithTheUnits) {
  const mme::Model m = twoMarkers(0.25, -327.0);
  const std::vector<std::string> w = mme::identifiedModelWarnings(m, staticFrames(twoMarkers(0.25, 0.0)));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("the identified gravity is 327 m/s^2, the Earth's is 9.81"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("millimetres read as metres"), std::string::npos) << w[0];
  // Far below: the markers do not fall freely (held, driven, or metres read as millimetres).
  const mme::Model low = twoMarkers(0.25, -0.02);
  const std::vector<std::string> held = mme::identifiedModelWarnings(low, staticFrames(twoMarkers(0.25, 0.0)));
  ASSERT_EQ(held.size(), 1u);
  EXPECT_NE(held[0].find("the identified gravity is 0.02 m/s^2, the Earth's is 9.81: the markers do not fall"),
            std::string::npos)
      << held[0];
}

TEST(ResultChecks, FixedGravityIsNotJudged) {
  mme::Model m = twoMarkers(0.25, 0.0);
  for (mme::Param& g : m.gravity_mps2) g.free = false;  // a model in space: gravity 0 given
  EXPECT_TRUE(mme::identifiedModelWarnings(m, staticFrames(m)).empty());
}

TEST(ResultChecks, TinyRestLengthIsFlaggedNamingTheMarkers) {
  const mme::Model truth = twoMarkers(0.25, 0.0);
  const mme::Model identified = twoMarkers(0.00035, -9.81);
  const std::vector<std::string> w = mme::identifiedModelWarnings(identified, staticFrames(truth));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("bond type 's00' (p0 - p1): rest length 0.35 mm against a median distance of 25 cm"),
            std::string::npos)
      << w[0];
}

TEST(ResultChecks, UnitsFromTheCatalogue) {
  mme::Model m = twoMarkers(0.25, -9.81);
  mme::test::addParticle(&m, Eigen::Vector3d(0, 0.25, 0));
  const int flex = mme::test::addType(&m, "f00", mme::BondKind::kFlexion,
                           {{mme::kStiffness, 1.0}, {mme::kRestAngle, 1.0}, {mme::kDamping, 0.1}});
  mme::addBond(&m, flex, 1, 0, 2);
  std::vector<std::string> units;
  for (const mme::ParamRef& ref : mme::freeParameters(m)) units.push_back(ref.name + " " + mme::parameterUnit(m, ref));
  const std::vector<std::string> expected = {"s00/stiffness N/m", "s00/rest_length m",
                                             "f00/stiffness N m/rad", "f00/rest_angle rad",
                                             "f00/damping N m s/rad", "gravity/x m/s^2",
                                             "gravity/y m/s^2", "gravity/z m/s^2"};
  EXPECT_EQ(units, expected);
  EXPECT_TRUE(mme::unitMasses(m));
  m.particles[1].mass_kg = 0.5;
  EXPECT_FALSE(mme::unitMasses(m));
}

// The chosen structure against the model-free guesses on the held-out frames (arm26's figures):
// a guess that predicts better is named with both figures; a structure that wins is not flagged.
TEST(ResultChecks, ChosenModelLosingToAGuessIsSaid) {
  mme::StructureResult r;
  mme::StructureCandidate loser;
  loser.name = "springs";
  loser.chosen = true;
  loser.held_out_rms_m[0] = 0.1e-3;
  loser.held_out_rms_m[1] = 0.5e-3;
  loser.held_out_rms_m[2] = 2.18e-3;
  r.candidates.push_back(loser);
  const double guesses[3][3] = {{0.2e-3, 0.9e-3, 1.91e-3}, {0.2e-3, 0.6e-3, 0.54e-3}, {1e-3, 5e-3, 9e-3}};
  for (int g = 0; g < 3; ++g)
    for (int h = 0; h < 3; ++h) r.guess_rms_m[g][h] = guesses[g][h];
  const std::vector<std::string> w = mme::chosenStructureWarnings(r);
  ASSERT_EQ(w.size(), 1u) << ::testing::PrintToString(w);
  EXPECT_NE(w[0].find("the chosen model ('springs') predicts the held-out frames worse than a guess that "
                      "needs no model (10 frame(s) ahead 2.18 mm against constant velocity 1.91 mm, "
                      "constant acceleration 0.54 mm)"),
            std::string::npos)
      << w[0];
  r.candidates[0].held_out_rms_m[2] = 0.5e-3;
  EXPECT_TRUE(mme::chosenStructureWarnings(r).empty());
}

}  // namespace

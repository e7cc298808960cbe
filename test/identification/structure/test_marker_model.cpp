// markerModel: the starting model of a capture without one.
#include <gtest/gtest.h>

#include <cmath>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/structure/marker_model.h"
#include "motion_model_estimation/io/trajectory_io.h"

namespace {

// Four markers over 50 frames: a-b rigid (0.3 m), c moves against both, d seen in half the
// frames only but rigid with a.
mme::Trajectory fourMarkers() {
  mme::Trajectory data;
  data.marker_names = {"a", "b", "c", "d"};
  data.frame_rate_hz = 50.0;
  data.resize(50);
  for (int t = 0; t < 50; ++t) {
    const double s = 0.01 * t;
    data.position(t, 0) = Eigen::Vector3d(s, 0, 1);
    data.position(t, 1) = Eigen::Vector3d(s + 0.3, 0, 1);
    data.position(t, 2) = Eigen::Vector3d(0.2 * std::sin(0.3 * t), 0.5, 1);
    data.position(t, 3) = Eigen::Vector3d(s, 0.1, 1);
    for (int i = 0; i < 3; ++i) data.occluded[t * 4 + i] = 0;
    data.occluded[t * 4 + 3] = t % 2;
  }
  return data;
}

TEST(MarkerModel, ParticlesAreTheMarkersWithUnitMassAndFreeGravity) {
  const mme::Model m = mme::markerModel(fourMarkers());
  ASSERT_EQ(m.particles.size(), 4u);
  EXPECT_EQ(m.particles[2].name, "c");
  for (const mme::Particle& p : m.particles) {
    EXPECT_EQ(p.mass_kg, 1.0);
    EXPECT_FALSE(p.fixed);
  }
  EXPECT_TRUE(m.bonds.empty());
  EXPECT_TRUE(m.bond_types.empty());
  EXPECT_EQ(m.frame_rate_hz, 50.0);
  const std::vector<mme::ParamRef> free = mme::freeParameters(m);
  ASSERT_EQ(free.size(), 3u);
  EXPECT_EQ(free[0].name, "gravity/x");
}

TEST(MarkerModel, RigidPairsFirstAndRarelySeenPairsLeftOut) {
  const mme::Model m = mme::markerModel(fourMarkers(), 2);
  ASSERT_EQ(m.bonds.size(), 2u);
  ASSERT_EQ(m.bond_types.size(), 2u);
  // a-b is the only rigid pair seen in 80 % of the frames (a-d is rigid but d is seen in half).
  EXPECT_EQ(m.bonds[0].particles[0], 0);
  EXPECT_EQ(m.bonds[0].particles[1], 1);
  for (const mme::Bond& b : m.bonds) {
    EXPECT_NE(b.particles[0], 3);
    EXPECT_NE(b.particles[1], 3);
  }
  EXPECT_EQ(mme::freeParameters(m).size(), 3u + 2u * 3u);
}

TEST(MarkerModel, EveryMarkerOfARealCaptureAndNothingWithoutMarkers) {
  const mme::Trajectory data =
      mme::readTrajectoryFile(std::string(MME_TEST_DATA_DIR) + "/real/Sample26_Walking_Hybrid_1_1.c3d");
  const mme::Model m = mme::markerModel(data);
  ASSERT_EQ(static_cast<int>(m.particles.size()), data.numMarkers());
  for (int i = 0; i < data.numMarkers(); ++i) EXPECT_EQ(m.particles[i].name, data.marker_names[i]);
  EXPECT_EQ(m.frame_rate_hz, 240.0);
  EXPECT_THROW(mme::markerModel(mme::Trajectory()), mme::InputError);
}

}  // namespace

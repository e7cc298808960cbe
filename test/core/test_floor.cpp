// The floor bond kind (ground contact): its force against a hand computation, with and without a
// contact depth; a dropped particle comes to rest on the floor at the penetration that carries
// its weight, friction stops a slide; with a contact depth the motion is continuous in the start
// state (without one it jumps); the model file reads and writes it, and the evolution strategy
// identifies a bouncing ball's contact parameters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/forces.h"
#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "test_helpers.h"

namespace {

using Eigen::Vector3d;
using mme::BondKind;
using mme::Model;

constexpr double kStiffness = 2000.0, kDamping = 15.0, kFriction = 4.0, kHeight = 0.05;

TEST(Floor, ForceMatchesAHandComputation) {
  mme::FloorLaw law{kStiffness, kDamping, kFriction, kHeight};
  Vector3d f = Vector3d::Zero();
  mme::addFloorForce(law, Vector3d(1, 2, 0.06), Vector3d(0.3, -0.2, -1.0), &f);
  EXPECT_EQ(f, Vector3d::Zero()) << "above the floor: no force";
  mme::addFloorForce(law, Vector3d(1, 2, 0.04), Vector3d(0.3, -0.2, -0.5), &f);
  EXPECT_NEAR(f.x(), -kFriction * 0.3, 1e-12);
  EXPECT_NEAR(f.y(), kFriction * 0.2, 1e-12);
  EXPECT_NEAR(f.z(), kStiffness * 0.01 + kDamping * 0.5, 1e-12);
  // Leaving fast: the damping would pull it down; the floor only pushes.
  f.setZero();
  mme::addFloorForce(law, Vector3d(0, 0, 0.049), Vector3d(0, 0, 5.0), &f);
  EXPECT_EQ(f.z(), 0.0);
}

TEST(Floor, AContactDepthRampsDampingAndFrictionIn) {
  const double depth_m = 0.004;
  mme::FloorLaw law{kStiffness, kDamping, kFriction, kHeight, depth_m};
  Vector3d f = Vector3d::Zero();
  // A quarter of the depth in: a quarter of the damping and friction, all of the stiffness.
  mme::addFloorForce(law, Vector3d(1, 2, kHeight - 0.001), Vector3d(0.3, -0.2, -0.5), &f);
  EXPECT_NEAR(f.x(), -0.25 * kFriction * 0.3, 1e-12);
  EXPECT_NEAR(f.y(), 0.25 * kFriction * 0.2, 1e-12);
  EXPECT_NEAR(f.z(), kStiffness * 0.001 + 0.25 * kDamping * 0.5, 1e-12);
  // Deeper than the depth: the full law, as without one.
  f.setZero();
  Vector3d full = Vector3d::Zero();
  law.contact_depth = 0.0;
  mme::addFloorForce(law, Vector3d(1, 2, kHeight - 0.006), Vector3d(0.3, -0.2, -0.5), &full);
  law.contact_depth = depth_m;
  mme::addFloorForce(law, Vector3d(1, 2, kHeight - 0.006), Vector3d(0.3, -0.2, -0.5), &f);
  EXPECT_EQ(f, full);
  // At touch-down the force starts from nothing: no jump.
  f.setZero();
  mme::addFloorForce(law, Vector3d(1, 2, kHeight - 1e-12), Vector3d(0.3, -0.2, -0.5), &f);
  EXPECT_LT(f.norm(), 1e-8);
}

/// One particle of 0.5 kg dropped from 0.2 m with a sideways speed onto a floor at 5 cm.
Model ball(bool free) {
  Model m;
  m.frame_rate_hz = 100;
  for (int k = 0; k < 3; ++k) m.gravity_mps2[k] = mme::test::valueParam(k == 2 ? -9.81 : 0.0);
  mme::test::addParticle(&m, Vector3d(0, 0, 0.2), 0.5, false, "", Vector3d(0.8, 0.3, 0));
  const int t = mme::test::addType(&m, "ground", BondKind::kFloor,
                                   {{mme::kStiffness, kStiffness}, {mme::kDamping, kDamping},
                                    {mme::kFriction, kFriction}},
                                   free);
  m.bond_types[t].param(mme::kHeight) = mme::test::valueParam(kHeight);
  mme::test::addBond(&m, t, 0);
  return m;
}

TEST(Floor, ADroppedParticleComesToRestCarriedByTheFloor) {
  const mme::Trajectory traj = mme::simulateTrajectory(ball(false), 400, 100.0);
  double lowest = 1.0;
  for (int t = 0; t < traj.numFrames(); ++t) lowest = std::min(lowest, traj.position(t, 0).z());
  EXPECT_GT(lowest, kHeight - 0.03) << "the floor holds";  // impact at 1.7 m/s: 2.7 cm
  const Vector3d end = traj.position(399, 0), before = traj.position(398, 0);
  // At rest: weight = k x penetration.
  EXPECT_NEAR(end.z(), kHeight - 0.5 * 9.81 / kStiffness, 1e-6);
  EXPECT_LT((end - before).norm(), 1e-7);
  // It slid a while (friction only acts in contact) and stopped.
  EXPECT_GT(end.head<2>().norm(), 0.1);
}

/// The ball's position after 0.5 s against its drop height, scanned in steps much finer than
/// the distance it falls in one step: the largest change between neighbouring heights over the
/// median change. A force that jumps at touch-down makes the motion jump where the first contact
/// moves from one step to the next.
double largestOverMedianStep(double contact_depth_m) {
  std::vector<Vector3d> ends;
  for (int k = 0; k <= 400; ++k) {
    Model m = ball(false);
    m.bond_types[0].param(mme::kContactDepth) = mme::test::valueParam(contact_depth_m);
    m.particles[0].position_m.z() = 0.2 + 5e-5 * k;
    ends.push_back(mme::simulateTrajectory(m, 50, 100.0).position(49, 0));
  }
  std::vector<double> steps;
  for (size_t k = 1; k < ends.size(); ++k) steps.push_back((ends[k] - ends[k - 1]).norm());
  const double largest = *std::max_element(steps.begin(), steps.end());
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return largest / steps[steps.size() / 2];
}

TEST(Floor, AContactDepthMakesTheMotionContinuousInTheStartState) {
  const double jumping = largestOverMedianStep(0.0), ramped = largestOverMedianStep(0.01);
  EXPECT_GT(jumping, 50.0) << "the law without a depth jumps (else this test shows nothing)";
  EXPECT_LT(ramped, 10.0) << "a 1 cm contact depth: no jump";
}

TEST(Floor, ReadAndWrittenByTheModelFile) {
  const Model m = mme::loadModelString(
      "particles: [{name: foot, mass: 1, position: [0, 0, 0.1]}]\n"
      "bond_types:\n"
      "  - {name: ground, kind: floor, stiffness: {value: 1000, free: true}, damping: 5,\n"
      "     friction: 2, height: {value: 0.0, free: true, min: -0.1, max: 0.1},\n"
      "     contact_depth: 0.002}\n"
      "bonds: [{type: ground, particles: [foot]}]\n",
      "floor.yaml");
  const mme::BondType& t = m.bond_types[0];
  EXPECT_EQ(t.kind, BondKind::kFloor);
  EXPECT_EQ(t.value(mme::kFriction), 2.0);
  EXPECT_TRUE(t.param(mme::kHeight).free);
  EXPECT_EQ(t.value(mme::kContactDepth), 0.002);
  std::vector<std::string> names;
  for (const mme::ParamRef& r : mme::freeParameters(m)) names.push_back(r.name);
  EXPECT_EQ(names, (std::vector<std::string>{"ground/stiffness", "ground/height"}));
  const std::string text = mme::modelToYaml(m);
  EXPECT_EQ(mme::modelToYaml(mme::loadModelString(text, "back.yaml")), text);
  try {
    mme::loadModelString(
        "particles: [{name: foot, mass: 1}]\n"
        "bond_types: [{name: g, kind: floor, rest_length: 1}]\n",
        "bad.yaml");
    ADD_FAILURE() << "a floor has no rest_length";
  } catch (const mme::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown key for a floor"), std::string::npos) << e.what();
  }
  try {
    mme::loadModelString(
        "particles: [{name: foot, mass: 1}]\n"
        "bond_types: [{name: g, kind: floor, stiffness: 10, contact_depth: -0.001}]\n",
        "negative.yaml");
    ADD_FAILURE() << "a negative contact depth";
  } catch (const mme::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("contact_depth must be >= 0"), std::string::npos) << e.what();
  }
}

TEST(Floor, TheEvolutionStrategyIdentifiesABouncingBallsContact) {
  const Model truth = ball(true);
  const mme::Trajectory data = mme::simulateTrajectory(truth, 120, 100.0);
  mme::IdentifyOptions options;
  options.generations = 200;
  options.estimate_std = false;
  const mme::IdentifyResult r = mme::identifyModel(mme::test::withoutValues(truth), data, options);
  const std::vector<double> want = {kStiffness, kDamping, kFriction};
  EXPECT_LT(mme::test::maxRelativeError(r.values, want), 1e-4) << "cost " << r.global_cost;
}

}  // namespace

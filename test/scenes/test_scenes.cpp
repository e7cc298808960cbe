// Tests of scenes/scenes.cpp: the built-in scenes of SPEC section 8 have the documented
// structure and true values, are deterministic, and behave as the paper's experiments need
// (the object vibrates, the cloth's single frame is its hanging equilibrium with clamped
// springs, the jet activates ~80 000 interaction bonds, the walker trots on the floor).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace mme {
namespace {

std::vector<std::string> freeNames(const Model& model) {
  std::vector<std::string> names;
  for (const ParamRef& r : freeParameters(model)) names.push_back(r.name);
  return names;
}

double freeValue(const Model& model, const std::string& name) {
  for (const ParamRef& r : freeParameters(model))
    if (r.name == name) return getParam(model, r);
  ADD_FAILURE() << "no free parameter " << name;
  return NAN;
}

double bondLength(const std::vector<Eigen::Vector3d>& x, const Bond& bond) {
  return (x[bond.particles[1]] - x[bond.particles[0]]).norm();
}

std::vector<Eigen::Vector3d> initialPositions(const Model& model) {
  std::vector<Eigen::Vector3d> x;
  for (const Particle& p : model.particles) x.push_back(p.position_m);
  return x;
}

std::vector<Eigen::Vector3d> framePositions(const Trajectory& trajectory, int t) {
  std::vector<Eigen::Vector3d> x;
  for (int i = 0; i < trajectory.numMarkers(); ++i) x.push_back(trajectory.position(t, i));
  return x;
}

/// Cost of the true values on `data` (the model's own trajectory or equilibrium).
double costAtTruth(const Model& model, const Trajectory& data) {
  ShortTermCost cost(model, data);
  return cost.evaluate(getValues(model, cost.freeParameters()), nullptr);
}

/// Largest displacement of any particle from its initial position over the trajectory [m].
double maxDisplacement(const Model& model, const Trajectory& trajectory) {
  double d = 0.0;
  for (int t = 0; t < trajectory.numFrames(); ++t)
    for (int i = 0; i < trajectory.numMarkers(); ++i)
      d = std::max(d, (trajectory.position(t, i) - model.particles[i].position_m).norm());
  return d;
}

/// The cloth scene takes about a second to build (its equilibrium): built once for its tests.
const Scene& provotCloth() {
  static const Scene scene = makeScene("provot_cloth");
  return scene;
}

bool allFinite(const Trajectory& trajectory) {
  for (const Eigen::Vector3d& x : trajectory.positions_m)
    if (!x.allFinite()) return false;
  return true;
}

// ------------------------------------------------------------------------------- all scenes

TEST(Scenes, NamesAreTheFourOfTheSpec) {
  EXPECT_EQ(sceneNames(), (std::vector<std::string>{"paper_object", "provot_cloth", "fluid_jet", "walker"}));
}

TEST(Scenes, UnknownNameThrowsInputErrorListingTheKnownOnes) {
  try {
    makeScene("nope");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "unknown scene 'nope' (known: paper_object, provot_cloth, fluid_jet, walker)");
  }
  EXPECT_THROW(makeScene(""), InputError);
  EXPECT_THROW(makeScene("Paper_Object"), InputError);
}

TEST(Scenes, EverySceneIsValidWithBoundsBracketingTheTruth) {
  for (const std::string& name : sceneNames()) {
    SCOPED_TRACE(name);
    const Scene scene = makeScene(name);
    const Model& model = scene.model;
    EXPECT_EQ(validateModel(model), "");
    EXPECT_GT(model.frame_rate_hz, 0.0);
    EXPECT_GE(model.substeps, 1);
    EXPECT_GT(scene.default_frames, 0);
    const std::vector<ParamRef> free = freeParameters(model);
    EXPECT_FALSE(free.empty());
    for (const ParamRef& r : free) {
      SCOPED_TRACE(r.name);
      ASSERT_GE(r.bond_type, 0) << "gravity is never free in the scenes";
      const Param& p = model.bond_types[r.bond_type].params[r.param];
      EXPECT_TRUE(p.has_value) << "the truth is kept as the value";
      ASSERT_TRUE(p.has_min && p.has_max);
      EXPECT_GT(p.min, 0.0);
      EXPECT_LT(p.min, p.value);
      EXPECT_GT(p.max, p.value);
      EXPECT_LE(p.max / p.min, 100.0 + 1e-9);
    }
    if (name != "provot_cloth") {
      EXPECT_EQ(scene.reference_data.numFrames(), 0);
    }
  }
}

TEST(Scenes, MakeSceneIsDeterministic) {
  for (const std::string& name : sceneNames()) {
    SCOPED_TRACE(name);
    const Scene a = makeScene(name), b = makeScene(name);
    ASSERT_EQ(a.model.particles.size(), b.model.particles.size());
    for (size_t i = 0; i < a.model.particles.size(); ++i) {
      const Particle &p = a.model.particles[i], &q = b.model.particles[i];
      EXPECT_EQ(p.name, q.name);
      EXPECT_EQ(p.mass_kg, q.mass_kg);
      EXPECT_EQ(p.position_m, q.position_m);
      EXPECT_EQ(p.velocity_mps, q.velocity_mps);
      EXPECT_EQ(p.fixed, q.fixed);
      EXPECT_EQ(p.group, q.group);
    }
    ASSERT_EQ(a.model.bond_types.size(), b.model.bond_types.size());
    for (size_t t = 0; t < a.model.bond_types.size(); ++t)
      for (int k = 0; k < kParamCount; ++k) {
        EXPECT_EQ(a.model.bond_types[t].params[k].value, b.model.bond_types[t].params[k].value);
        EXPECT_EQ(a.model.bond_types[t].params[k].free, b.model.bond_types[t].params[k].free);
      }
    ASSERT_EQ(a.model.bonds.size(), b.model.bonds.size());
    for (size_t k = 0; k < a.model.bonds.size(); ++k) {
      EXPECT_EQ(a.model.bonds[k].type, b.model.bonds[k].type);
      EXPECT_EQ(a.model.bonds[k].particles, b.model.bonds[k].particles);
    }
    EXPECT_EQ(a.model.interactions.size(), b.model.interactions.size());
    EXPECT_EQ(a.default_frames, b.default_frames);
    EXPECT_EQ(a.reference_data.positions_m, b.reference_data.positions_m);
  }
}

// ----------------------------------------------------------------------------- paper_object

TEST(PaperObject, HasTheStructureOfThePapersFigure1) {
  const Scene scene = makeScene("paper_object");
  const Model& model = scene.model;
  EXPECT_EQ(model.particles.size(), 15u);
  ASSERT_EQ(model.bond_types.size(), 10u);
  EXPECT_EQ(model.bonds.size(), 31u);
  EXPECT_EQ(model.frame_rate_hz, 100.0);
  EXPECT_EQ(model.substeps, 1);
  EXPECT_EQ(scene.default_frames, 100);
  std::vector<std::string> expected;
  for (int t = 0; t < 10; ++t) {
    const std::string type = std::string("s0") + std::to_string(t);
    EXPECT_EQ(model.bond_types[t].name, type);
    EXPECT_EQ(model.bond_types[t].kind, BondKind::kSpring);
    expected.push_back(type + "/stiffness");
    expected.push_back(type + "/rest_length");
    const double k = model.bond_types[t].value(kStiffness);
    EXPECT_GE(k, 10.0);
    EXPECT_LE(k, 100.0);
  }
  EXPECT_EQ(freeNames(model), expected);
  // Floating, no gravity, moving.
  EXPECT_EQ(model.gravity(), Eigen::Vector3d::Zero());
  for (const Particle& p : model.particles) {
    EXPECT_FALSE(p.fixed);
    EXPECT_GE(p.mass_kg, 0.5);
    EXPECT_LE(p.mass_kg, 2.0);
    EXPECT_GT(p.velocity_mps.norm(), 0.0);
  }
  // Every type used at least 3 times; bonds 0.1..0.3 m; rest lengths differ from the distances.
  const std::vector<Eigen::Vector3d> x = initialPositions(model);
  std::vector<int> uses(10, 0);
  for (const Bond& bond : model.bonds) {
    ++uses[bond.type];
    const double l = bondLength(x, bond);
    EXPECT_GE(l, 0.1 - 1e-12);
    EXPECT_LE(l, 0.3);
    EXPECT_GT(std::abs(l - model.bond_types[bond.type].value(kRestLength)), 1e-3);
  }
  for (int u : uses) EXPECT_GE(u, 3);
  // Connected (breadth-first search over the bonds) and truly 3-D.
  std::vector<bool> seen(15, false);
  std::vector<int> queue = {0};
  seen[0] = true;
  for (size_t k = 0; k < queue.size(); ++k)
    for (const Bond& bond : model.bonds)
      for (int e = 0; e < 2; ++e)
        if (bond.particles[e] == queue[k] && !seen[bond.particles[1 - e]]) {
          seen[bond.particles[1 - e]] = true;
          queue.push_back(bond.particles[1 - e]);
        }
  EXPECT_EQ(queue.size(), 15u);
  Eigen::Vector3d lo = x[0], hi = x[0];
  for (const Eigen::Vector3d& p : x) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  EXPECT_GT((hi - lo).minCoeff(), 0.1);
}

TEST(PaperObject, StiffestModeIsWellBelowTheExplicitStabilityLimit) {
  // omega_max of the linearised springs (k u u^T per bond, mass-normalised) times h.
  const Model model = makeScene("paper_object").model;
  const int n = static_cast<int>(model.particles.size());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  const std::vector<Eigen::Vector3d> x = initialPositions(model);
  for (const Bond& bond : model.bonds) {
    const int a = bond.particles[0], b = bond.particles[1];
    const Eigen::Vector3d u = (x[b] - x[a]).normalized();
    const Eigen::Matrix3d k = model.bond_types[bond.type].value(kStiffness) * u * u.transpose();
    K.block<3, 3>(3 * a, 3 * a) += k;
    K.block<3, 3>(3 * b, 3 * b) += k;
    K.block<3, 3>(3 * a, 3 * b) -= k;
    K.block<3, 3>(3 * b, 3 * a) -= k;
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      K.block<3, 3>(3 * i, 3 * j) /= std::sqrt(model.particles[i].mass_kg * model.particles[j].mass_kg);
  const double lambda_max = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(K).eigenvalues().maxCoeff();
  const double omega_h = std::sqrt(lambda_max) / model.frame_rate_hz / model.substeps;
  EXPECT_LT(omega_h, 0.5);
  EXPECT_GT(omega_h, 0.02) << "stiff enough to vibrate visibly within 100 frames";
}

TEST(PaperObject, SimulatesToABoundedVibration) {
  const Scene scene = makeScene("paper_object");
  const Model& model = scene.model;
  const Trajectory trajectory = simulateTrajectory(model, scene.default_frames, model.frame_rate_hz);
  ASSERT_EQ(trajectory.numFrames(), 100);
  EXPECT_TRUE(allFinite(trajectory));
  const double d = maxDisplacement(model, trajectory);
  EXPECT_GT(d, 1e-3);
  EXPECT_LT(d, 1.0);
  // Vibration: every bond's length changes by more than 1 mm and stays within 50 % of its rest.
  for (const Bond& bond : model.bonds) {
    double lo = 1e9, hi = 0.0;
    for (int t = 0; t < trajectory.numFrames(); ++t) {
      const double l = bondLength(framePositions(trajectory, t), bond);
      lo = std::min(lo, l);
      hi = std::max(hi, l);
    }
    const double rest = model.bond_types[bond.type].value(kRestLength);
    EXPECT_GT(hi - lo, 1e-3);
    EXPECT_GT(lo, 0.5 * rest);
    EXPECT_LT(hi, 1.5 * rest);
  }
  // One step per frame: the paper's prediction reproduces the true model's motion exactly.
  EXPECT_LT(costAtTruth(model, trajectory), 1e-20);
}

// ----------------------------------------------------------------------------- provot_cloth

TEST(ProvotCloth, HasProvotsMeshAndTheParametersOfTableI) {
  const Scene& scene = provotCloth();
  const Model& model = scene.model;
  ASSERT_EQ(model.particles.size(), 289u);
  EXPECT_EQ(scene.default_frames, 300);
  EXPECT_EQ(model.frame_rate_hz, 100.0);
  EXPECT_EQ(model.gravity(), Eigen::Vector3d(0.0, 0.0, -9.81));
  for (int r = 0; r < 17; ++r)
    for (int c = 0; c < 17; ++c) {
      const Particle& p = model.particles[r * 17 + c];
      EXPECT_EQ(p.name, "c_" + std::to_string(r) + "_" + std::to_string(c));
      EXPECT_EQ(p.fixed, r == 0 && (c == 0 || c == 16)) << p.name;
      EXPECT_NEAR(p.position_m.z(), 0.0, 1e-15) << "released horizontally";
    }
  const std::vector<std::string> springs = {"struct_h", "struct_v", "shear_d1", "shear_d2", "flex_h", "flex_v"};
  const double rest[6] = {0.09375, 0.09375, 0.132583, 0.132583, 0.1875, 0.1875};
  const size_t counts[6] = {272, 272, 256, 256, 255, 255};
  std::vector<std::string> expected;
  int spring_types = 0;
  for (const BondType& type : model.bond_types) spring_types += type.kind == BondKind::kSpring;
  EXPECT_EQ(spring_types, 6);
  for (int t = 0; t < 6; ++t) {
    const int index = model.bondTypeIndex(springs[t]);
    ASSERT_GE(index, 0) << springs[t];
    const BondType& type = model.bond_types[index];
    EXPECT_EQ(type.kind, BondKind::kSpring);
    EXPECT_EQ(type.value(kRestLength), rest[t]);
    EXPECT_TRUE(type.param(kDamping).present && !type.param(kDamping).free) << "known damping";
    size_t count = 0;
    for (const Bond& bond : model.bonds) count += bond.type == index;
    EXPECT_EQ(count, counts[t]) << springs[t];
    for (const char* p : {"stiffness", "rest_length", "stiffness_nl"}) expected.push_back(springs[t] + "/" + p);
    if (t < 2) {
      expected.push_back(springs[t] + "/max_elongation");
      EXPECT_EQ(type.value(kMaxElongation), 0.5);
    } else {
      EXPECT_FALSE(type.param(kMaxElongation).present);
    }
  }
  std::vector<std::string> names = freeNames(model);
  std::sort(names.begin(), names.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(names, expected);
  EXPECT_EQ(names.size(), 20u);
  EXPECT_EQ(freeValue(model, "struct_h/stiffness"), 4.0);
}

TEST(ProvotCloth, ReferenceDataIsTheHangingEquilibriumWithClampedSprings) {
  const Scene& scene = provotCloth();
  const Model& model = scene.model;
  const Trajectory& data = scene.reference_data;
  ASSERT_EQ(data.numFrames(), 1);
  ASSERT_EQ(data.numMarkers(), 289);
  EXPECT_EQ(data.validate(), "");
  EXPECT_EQ(data.countOccluded(), 0u);
  EXPECT_EQ(data.frame_rate_hz, model.frame_rate_hz);
  for (int i = 0; i < 289; ++i) EXPECT_EQ(data.marker_names[i], model.particles[i].name);
  const std::vector<Eigen::Vector3d> x = framePositions(data, 0);
  // Corners where they were; the rest hangs below them, well below (visible sag).
  double lowest = 0.0;
  for (int i = 0; i < 289; ++i) {
    if (model.particles[i].fixed) {
      EXPECT_EQ(x[i], model.particles[i].position_m);
      continue;
    }
    EXPECT_LT(x[i].z(), 0.0) << model.particles[i].name;
    lowest = std::min(lowest, x[i].z());
  }
  EXPECT_LT(lowest, -1.5);
  // Provot's clamp is active: on both structural types some springs sit exactly at (1+tau) L,
  // none beyond it.
  for (const char* name : {"struct_h", "struct_v"}) {
    SCOPED_TRACE(name);
    const int index = model.bondTypeIndex(name);
    const BondType& type = model.bond_types[index];
    const double clamp = (1.0 + type.value(kMaxElongation)) * type.value(kRestLength);
    int at_clamp = 0;
    for (const Bond& bond : model.bonds) {
      if (bond.type != index) continue;
      const double l = bondLength(x, bond);
      EXPECT_LE(l, clamp + 1e-9);
      at_clamp += std::abs(l - clamp) < 1e-9;
    }
    EXPECT_GE(at_clamp, 1);
  }
  // Static mode (x(t-1) = x(t) = x(t+1)): the true model predicts no motion; a 1 % change of a
  // rest length or of tau does.
  ShortTermCost cost(model, data);
  std::vector<double> values = getValues(model, cost.freeParameters());
  const double at_truth = cost.evaluate(values, nullptr);
  EXPECT_LT(at_truth, 1e-20);
  for (size_t k = 0; k < values.size(); ++k) {
    const std::string& name = cost.freeParameters()[k].name;
    if (name.find("rest_length") == std::string::npos && name.find("max_elongation") == std::string::npos)
      continue;
    std::vector<double> changed = values;
    changed[k] *= 1.01;
    EXPECT_GT(cost.evaluate(changed, nullptr), std::max(1e4 * at_truth, 1e-10)) << name;
  }
}

// -------------------------------------------------------------------------------- fluid_jet

TEST(FluidJet, HasTheEightParametersOfTableII) {
  const Scene scene = makeScene("fluid_jet");
  const Model& model = scene.model;
  const std::vector<std::pair<std::string, double>> table2 = {
      {"gas_visc/damping", 2.5}, {"gas_visc/damping_nl", 1.25}, {"gas_visc/max_distance", 1.5},
      {"jet_visc/damping", 4.0}, {"jet_visc/damping_nl", 2.0},  {"jet_visc/max_distance", 2.0},
      {"elast/stiffness", 2.0},  {"elast/max_distance", 1.1}};
  std::vector<std::string> expected;
  for (const auto& p : table2) expected.push_back(p.first);
  EXPECT_EQ(freeNames(model), expected);
  for (const auto& p : table2) EXPECT_EQ(freeValue(model, p.first), p.second) << p.first;
  const BondType& elast = model.bond_types[model.bondTypeIndex("elast")];
  EXPECT_EQ(elast.value(kRestLength), 1.1);
  EXPECT_FALSE(elast.param(kRestLength).free);
  // 2-D, no gravity, no installed bonds: only conditional interactions between gas and jet.
  EXPECT_EQ(model.gravity(), Eigen::Vector3d::Zero());
  EXPECT_TRUE(model.bonds.empty());
  EXPECT_EQ(model.interactions.size(), 6u);
  int gas = 0, jet = 0;
  for (const Particle& p : model.particles) {
    EXPECT_EQ(p.position_m.z(), 0.0);
    EXPECT_EQ(p.velocity_mps.z(), 0.0);
    EXPECT_EQ(p.mass_kg, 1.0);
    EXPECT_FALSE(p.fixed);
    gas += p.group == "gas";
    jet += p.group == "jet";
    if (p.group == "jet") {
      EXPECT_EQ(p.velocity_mps, Eigen::Vector3d(10.0, 0.0, 0.0));
    }
  }
  EXPECT_EQ(gas, 288);
  EXPECT_EQ(jet, 60);
  EXPECT_EQ(scene.default_frames, 200);
}

TEST(FluidJet, ActivatesAbout80000InteractionBondsOverItsDefaultFrames) {
  const Scene scene = makeScene("fluid_jet");
  const Model& model = scene.model;
  Simulator simulator(model);
  State state = simulator.initialState();
  std::vector<Eigen::Vector3d> forces;
  simulator.computeForces(state, &forces);
  size_t total = simulator.lastInteractionBondCount();  // frame 0
  for (int frame = 1; frame < scene.default_frames; ++frame) {
    simulator.stepFrame(&state, 1.0 / model.frame_rate_hz);
    total += simulator.lastInteractionBondCount();
  }
  EXPECT_GE(total, 50000u);
  EXPECT_LE(total, 120000u);
  for (const Eigen::Vector3d& x : state.x_m) {
    EXPECT_TRUE(x.allFinite());
    EXPECT_EQ(x.z(), 0.0);
  }
  // The jet went into the gas: its mean x is past the gas's left edge.
  double jet_x = 0.0;
  int jet = 0;
  for (size_t i = 0; i < state.x_m.size(); ++i)
    if (model.particles[i].group == "jet") {
      jet_x += state.x_m[i].x();
      ++jet;
    }
  EXPECT_GT(jet_x / jet, 2.0);
}

TEST(FluidJet, TrueModelPredictsItsOwnMotionExactly) {
  const Scene scene = makeScene("fluid_jet");
  const Trajectory trajectory = simulateTrajectory(scene.model, scene.default_frames, scene.model.frame_rate_hz);
  EXPECT_LT(costAtTruth(scene.model, trajectory), 1e-18);
}

// ----------------------------------------------------------------------------------- walker

TEST(Walker, HasTheHorseMarkerSet) {
  const Scene scene = makeScene("walker");
  const Model& model = scene.model;
  ASSERT_EQ(model.particles.size(), 35u);
  EXPECT_EQ(model.frame_rate_hz, 50.0);
  EXPECT_EQ(scene.default_frames, 250);
  EXPECT_EQ(model.gravity(), Eigen::Vector3d(0.0, 0.0, -9.81));
  std::set<std::string> names;
  for (const Particle& p : model.particles) {
    names.insert(p.name);
    EXPECT_FALSE(p.fixed) << p.name << ": the hooves stand on the floor, nothing is fixed";
  }
  for (const char* leg : {"fl", "fr", "hl", "hr"})
    for (int k = 0; k < 5; ++k) EXPECT_TRUE(names.count(std::string("leg_") + leg + "_" + std::to_string(k)));
  for (int k = 0; k < 15; ++k) {
    char name[16];
    std::snprintf(name, sizeof(name), "body_%02d", k);
    EXPECT_TRUE(names.count(name)) << name;
  }
  EXPECT_EQ(validateModel(model), "");
  // Every hoof has a floor bond, and only the hooves.
  std::set<std::string> on_floor;
  int muscles = 0;
  for (const Bond& bond : model.bonds) {
    const BondKind kind = model.bond_types[bond.type].kind;
    if (kind == BondKind::kFloor) on_floor.insert(model.particles[bond.particles[0]].name);
    muscles += kind == BondKind::kMuscle;
  }
  EXPECT_EQ(on_floor, (std::set<std::string>{"leg_fl_4", "leg_fr_4", "leg_hl_4", "leg_hr_4"}));
  EXPECT_EQ(muscles, 9) << "the tail's drive, and a swing and a lift muscle per leg";
  // Free: the passive mechanics (springs, flexions, contact); the controllers are known.
  const std::vector<std::string> free = freeNames(model);
  EXPECT_EQ(free.size(), 40u);
  for (const char* name : {"leg_spring/stiffness", "leg_spring/damping", "leg_spring/rest_length",
                           "body_spring/stiffness", "knee/stiffness", "knee/rest_angle",
                           "fetlock/stiffness", "hip/rest_angle", "splay/stiffness", "cannon/rest_length",
                           "ground/stiffness", "ground/damping", "ground/friction"})
    EXPECT_NE(std::find(free.begin(), free.end(), name), free.end()) << name;
  for (const ParamRef& r : freeParameters(model))
    EXPECT_NE(model.bond_types[r.bond_type].kind, BondKind::kMuscle) << r.name;
}

/// Gait figures of one hoof over a trajectory: it is in stance while below the floor (z < 0, the
/// floor bond acting), and a swing is an excursion between two stances that rises above 2 cm.
struct HoofGait {
  int stance_frames = 0;
  int swings = 0;
  double swing_forward_m = 0.0;  ///< summed over the swings: x at touch-down - x at lift-off
  std::vector<bool> lifted;      ///< per frame: above 2 cm
};

HoofGait hoofGait(const Trajectory& trajectory, int marker) {
  HoofGait gait;
  bool in_stance = false;
  double peak = 0.0, x_lift_off = 0.0;
  for (int t = 0; t < trajectory.numFrames(); ++t) {
    const Eigen::Vector3d x = trajectory.position(t, marker);
    const bool stance = x.z() < 0.0;
    gait.stance_frames += stance;
    gait.lifted.push_back(x.z() > 0.02);
    if (stance && !in_stance && t > 0 && peak > 0.02) {
      ++gait.swings;
      gait.swing_forward_m += x.x() - x_lift_off;
    }
    if (!stance && in_stance) x_lift_off = x.x(), peak = 0.0;
    if (!stance) peak = std::max(peak, x.z());
    in_stance = stance;
  }
  return gait;
}

/// Mean x of the eight trunk markers body_00..07 [m].
double trunkX(const Model& model, const Trajectory& trajectory, int t) {
  double x = 0.0;
  for (int k = 0; k < 8; ++k) x += trajectory.position(t, model.particleIndex("body_0" + std::to_string(k))).x();
  return x / 8.0;
}

// The default 250 frames (5 s): every hoof alternates stance and swings lifted above 2 cm that
// carry it forward, diagonal hooves are lifted together more often than lateral ones (a trot),
// and the trunk advances. Measured (0.3 mm contact depth): 6-9 swings per hoof, co-lifted frames
// 34 diagonal against 13 fore/hind, 1.27 m.
TEST(Walker, TrotsHoovesAlternateStanceAndSwingAndTheTrunkAdvances) {
  const Scene scene = makeScene("walker");
  const Model& model = scene.model;
  const Trajectory trajectory = simulateTrajectory(model, scene.default_frames, model.frame_rate_hz);
  std::map<std::string, HoofGait> gait;
  for (const char* leg : {"fl", "fr", "hl", "hr"}) {
    const HoofGait g = hoofGait(trajectory, model.particleIndex(std::string("leg_") + leg + "_4"));
    SCOPED_TRACE(leg);
    EXPECT_GE(g.swings, 6);
    EXPECT_GT(g.stance_frames, 0.2 * trajectory.numFrames());
    EXPECT_LT(g.stance_frames, 0.8 * trajectory.numFrames());
    EXPECT_GT(g.swing_forward_m / g.swings, 0.03) << "a swing carries the hoof forward";
    gait[leg] = g;
  }
  auto together = [&](const char* a, const char* b) {
    int n = 0;
    for (int t = 0; t < trajectory.numFrames(); ++t) n += gait[a].lifted[t] && gait[b].lifted[t];
    return n;
  };
  EXPECT_GT(together("fl", "hr") + together("fr", "hl"), together("fl", "fr") + together("hl", "hr"));
  const double forward_m = trunkX(model, trajectory, trajectory.numFrames() - 1) - trunkX(model, trajectory, 0);
  EXPECT_GT(forward_m, 0.3);
}

// Over the default frames the walker stays upright and bounded: finite, the withers and the head
// high, no hoof deep in the floor or far above it, the trunk level and near its line.
TEST(Walker, StaysUprightAndBounded) {
  const Scene scene = makeScene("walker");
  const Model& model = scene.model;
  const Trajectory trajectory = simulateTrajectory(model, scene.default_frames, model.frame_rate_hz);
  ASSERT_TRUE(allFinite(trajectory));
  const int withers = model.particleIndex("body_03"), rump = model.particleIndex("body_00");
  for (int t = 0; t < trajectory.numFrames(); ++t) {
    SCOPED_TRACE("frame " + std::to_string(t));
    const Eigen::Vector3d w = trajectory.position(t, withers), r = trajectory.position(t, rump);
    ASSERT_GT(w.z(), 1.6);
    ASSERT_LT(w.z(), 2.0);
    ASSERT_GT(trajectory.position(t, model.particleIndex("body_14")).z(), 1.4);
    ASSERT_LT(std::abs(w.z() - r.z()), 0.15) << "level";
    ASSERT_LT(std::abs(w.y()), 1.0);
    for (const char* leg : {"leg_fl_4", "leg_fr_4", "leg_hl_4", "leg_hr_4"}) {
      const double z = trajectory.position(t, model.particleIndex(leg)).z();
      ASSERT_GT(z, -0.02) << leg;
      ASSERT_LT(z, 0.3) << leg;
    }
  }
}

// Identification needs the motion to depend smoothly on the parameters: at the walker's 80
// substeps a 1e-8 relative change of every free parameter moves no marker more than 10 um over
// the first second (measured 0.55 um; with 20 substeps the motion was chaotic at round-off).
TEST(Walker, MotionDependsSmoothlyOnItsParameters) {
  const Scene scene = makeScene("walker");
  const Model& model = scene.model;
  const Trajectory truth = simulateTrajectory(model, 51, model.frame_rate_hz);
  Model nudged = model;
  const std::vector<ParamRef> refs = freeParameters(model);
  std::vector<double> values = getValues(model, refs);
  for (size_t k = 0; k < values.size(); ++k) values[k] *= 1.0 + (k % 2 ? 1e-8 : -1e-8);
  setValues(nudged, refs, values);
  const Trajectory moved = simulateTrajectory(nudged, 51, model.frame_rate_hz);
  double largest_m = 0.0;
  for (int t = 0; t < truth.numFrames(); ++t)
    for (int i = 0; i < truth.numMarkers(); ++i)
      largest_m = std::max(largest_m, (moved.position(t, i) - truth.position(t, i)).norm());
  EXPECT_GT(largest_m, 0.0);
  EXPECT_LT(largest_m, 1e-5);
}

}  // namespace
}  // namespace mme

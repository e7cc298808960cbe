// Tests of core/model.cpp: parameter tables, free/present parameter order and names
// ("<type>/<param>", "gravity/x"), get/set of values, and validateModel's checks.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"

namespace mme {
namespace {

Param fixedParam(double v) {
  Param p;
  p.present = p.has_value = true;
  p.value = v;
  return p;
}

Param freeParam(double v) {
  Param p = fixedParam(v);
  p.free = true;
  return p;
}

/// Three particles, a spring type, a flexion type, a viscosity type and one bond of each.
/// Parameters are put in the "wrong" order on purpose (damping before stiffness) to check that
/// the canonical order comes from paramsOfKind, not from the order of assignment.
Model makeModel() {
  Model m;
  for (const char* n : {"a", "b", "c"}) {
    Particle p;
    p.name = n;
    p.group = "g";
    m.particles.push_back(p);
  }
  BondType s;
  s.name = "s01";
  s.kind = BondKind::kSpring;
  s.param(kDamping) = freeParam(0.5);
  s.param(kStiffness) = freeParam(4.0);
  s.param(kRestLength) = fixedParam(0.1);
  s.param(kMaxDistance) = freeParam(2.0);
  BondType f;
  f.name = "bend";
  f.kind = BondKind::kFlexion;
  f.param(kRestAngle) = freeParam(3.0);
  f.param(kStiffness) = fixedParam(1.0);
  BondType v;
  v.name = "air";
  v.kind = BondKind::kViscosity;
  v.param(kViscosity) = freeParam(0.2);
  // A parameter not of this kind must never be listed, even if set.
  v.param(kStiffness) = freeParam(99.0);
  m.bond_types = {s, f, v};
  m.bonds.push_back(Bond{0, {{0, 1, -1}}, "", {}});
  m.bonds.push_back(Bond{1, {{0, 1, 2}}, "", {}});
  m.bonds.push_back(Bond{2, {{2, -1, -1}}, "", {}});
  m.gravity_mps2[0] = fixedParam(0.0);
  m.gravity_mps2[1] = fixedParam(0.0);
  m.gravity_mps2[2] = freeParam(-9.81);
  return m;
}

std::vector<std::string> namesOf(const std::vector<ParamRef>& refs) {
  std::vector<std::string> out;
  for (const ParamRef& r : refs) out.push_back(r.name);
  return out;
}

TEST(ModelTables, ParamKeysKindsAndArities) {
  EXPECT_STREQ(paramKey(kStiffness), "stiffness");
  EXPECT_STREQ(paramKey(kRestLength), "rest_length");
  EXPECT_STREQ(paramKey(kStiffnessNl), "stiffness_nl");
  EXPECT_STREQ(paramKey(kDampingNl), "damping_nl");
  EXPECT_STREQ(paramKey(kMaxElongation), "max_elongation");
  EXPECT_STREQ(paramKey(kRestAngle), "rest_angle");
  EXPECT_STREQ(paramKey(kViscosity), "viscosity");
  EXPECT_EQ(paramsOfKind(BondKind::kSpring).size(), 8u);
  EXPECT_EQ(paramsOfKind(BondKind::kFlexion),
            (std::vector<ParamId>{kStiffness, kRestAngle, kDamping}));
  EXPECT_EQ(paramsOfKind(BondKind::kViscosity), std::vector<ParamId>{kViscosity});
  EXPECT_EQ(kindArity(BondKind::kSpring), 2);
  EXPECT_EQ(kindArity(BondKind::kFlexion), 3);
  EXPECT_EQ(kindArity(BondKind::kViscosity), 1);
  EXPECT_STREQ(kindName(BondKind::kFlexion), "flexion");
}

TEST(ModelLookup, IndicesAndGravity) {
  const Model m = makeModel();
  EXPECT_EQ(m.particleIndex("c"), 2);
  EXPECT_EQ(m.particleIndex("zz"), -1);
  EXPECT_EQ(m.bondTypeIndex("air"), 2);
  EXPECT_EQ(m.bondTypeIndex("nope"), -1);
  EXPECT_EQ(m.gravity(), Eigen::Vector3d(0, 0, -9.81));
  Model no_g = m;
  no_g.gravity_mps2[2].present = false;  // absent = 0
  EXPECT_EQ(no_g.gravity(), Eigen::Vector3d::Zero());
  EXPECT_EQ(m.bond_types[0].value(kMinDistance), 0.0);  // absent = 0
  EXPECT_EQ(m.bond_types[0].value(kStiffness), 4.0);
}

TEST(ModelParams, FreeParametersOrderAndNames) {
  const Model m = makeModel();
  const std::vector<ParamRef> refs = freeParameters(m);
  EXPECT_EQ(namesOf(refs), (std::vector<std::string>{"s01/stiffness", "s01/damping",
                                                    "s01/max_distance", "bend/rest_angle",
                                                    "air/viscosity", "gravity/z"}));
  ASSERT_EQ(refs.size(), 6u);
  EXPECT_EQ(refs[0].bond_type, 0);
  EXPECT_EQ(refs[0].param, kStiffness);
  EXPECT_EQ(refs[3].bond_type, 1);
  EXPECT_EQ(refs[3].param, kRestAngle);
  EXPECT_EQ(refs[5].bond_type, -1);
  EXPECT_EQ(refs[5].param, 2);
}

TEST(ModelParams, PresentParametersIncludeFixedOnes) {
  const Model m = makeModel();
  EXPECT_EQ(namesOf(presentParameters(m)),
            (std::vector<std::string>{"s01/stiffness", "s01/rest_length", "s01/damping",
                                      "s01/max_distance", "bend/stiffness", "bend/rest_angle",
                                      "air/viscosity", "gravity/x", "gravity/y", "gravity/z"}));
}

TEST(ModelParams, GravityAxesAreNamedXYZ) {
  Model m = makeModel();
  for (Param& g : m.gravity_mps2) g.free = true;
  const std::vector<ParamRef> refs = freeParameters(m);
  ASSERT_GE(refs.size(), 3u);
  EXPECT_EQ(refs[refs.size() - 3].name, "gravity/x");
  EXPECT_EQ(refs[refs.size() - 2].name, "gravity/y");
  EXPECT_EQ(refs[refs.size() - 1].name, "gravity/z");
}

TEST(ModelParams, GetAndSetValues) {
  Model m = makeModel();
  const std::vector<ParamRef> refs = freeParameters(m);
  EXPECT_EQ(getValues(m, refs), (std::vector<double>{4.0, 0.5, 2.0, 3.0, 0.2, -9.81}));
  const std::vector<double> values = {10.0, 1.5, 3.5, 2.5, 0.7, -1.62};
  setValues(m, refs, values);
  EXPECT_EQ(getValues(m, refs), values);
  // The values land in the right places.
  EXPECT_EQ(m.bond_types[0].param(kStiffness).value, 10.0);
  EXPECT_EQ(m.bond_types[0].param(kDamping).value, 1.5);
  EXPECT_EQ(m.bond_types[1].param(kRestAngle).value, 2.5);
  EXPECT_EQ(m.bond_types[2].param(kViscosity).value, 0.7);
  EXPECT_EQ(m.gravity(), Eigen::Vector3d(0, 0, -1.62));
  // Fixed parameters are untouched.
  EXPECT_EQ(m.bond_types[0].param(kRestLength).value, 0.1);
  EXPECT_EQ(m.bond_types[1].param(kStiffness).value, 1.0);
}

TEST(ModelParams, SetParamGivesAValueToAFreeParameterWithoutOne) {
  Model m = makeModel();
  Param& p = m.bond_types[0].param(kStiffness);
  p.has_value = false;
  p.value = 0.0;
  const ParamRef ref = freeParameters(m)[0];
  setParam(m, ref, 7.25);
  EXPECT_TRUE(p.has_value);
  EXPECT_TRUE(p.present);
  EXPECT_EQ(getParam(m, ref), 7.25);
}

TEST(ModelParams, SetValuesStopsAtTheShorterList) {
  Model m = makeModel();
  const std::vector<ParamRef> refs = freeParameters(m);
  setValues(m, refs, {11.0});
  EXPECT_EQ(getValues(m, refs), (std::vector<double>{11.0, 0.5, 2.0, 3.0, 0.2, -9.81}));
}

// ------------------------------------------------------------------------ validateModel

/// validateModel's message for `m`, which must mention `fragment`.
void expectInvalid(const Model& m, const std::string& fragment) {
  const std::string reason = validateModel(m);
  EXPECT_FALSE(reason.empty()) << "expected: " << fragment;
  EXPECT_NE(reason.find(fragment), std::string::npos) << reason;
}

TEST(ModelValidate, ValidModelPasses) {
  Model m = makeModel();
  EXPECT_EQ(validateModel(m), "");
  // A free parameter may have no value (initial guess taken elsewhere).
  m.bond_types[0].param(kStiffness).has_value = false;
  EXPECT_EQ(validateModel(m), "");
  EXPECT_EQ(validateModel(Model()), "");
}

TEST(ModelValidate, SubstepsAndFrameRate) {
  Model m = makeModel();
  m.substeps = 0;
  expectInvalid(m, "substeps must be >= 1");
  m = makeModel();
  m.frame_rate_hz = -1.0;
  expectInvalid(m, "frame_rate_hz must be >= 0");
  m.frame_rate_hz = std::numeric_limits<double>::infinity();
  expectInvalid(m, "frame_rate_hz");
  m.frame_rate_hz = std::nan("");
  expectInvalid(m, "frame_rate_hz");
}

TEST(ModelValidate, Masses) {
  Model m = makeModel();
  m.particles[1].mass_kg = 0.0;
  expectInvalid(m, "particle 'b': mass must be > 0");
  m.particles[1].mass_kg = -3.0;
  expectInvalid(m, "particle 'b': mass must be > 0");
  m.particles[1].mass_kg = std::nan("");
  expectInvalid(m, "mass must be > 0");
}

TEST(ModelValidate, NonFiniteState) {
  Model m = makeModel();
  m.particles[2].velocity_mps.x() = std::numeric_limits<double>::infinity();
  expectInvalid(m, "particle 'c': position and velocity must be finite");
}

TEST(ModelValidate, DuplicateParticleName) {
  Model m = makeModel();
  m.particles[2].name = "a";
  expectInvalid(m, "duplicate particle name 'a'");
}

TEST(ModelValidate, BondIndices) {
  Model m = makeModel();
  m.bonds[1].type = 3;
  expectInvalid(m, "bond 1: unknown bond type");
  m = makeModel();
  m.bonds[0].particles[1] = 3;
  expectInvalid(m, "bond 0: particle index out of range");
  m = makeModel();
  m.bonds[1].particles[2] = -1;  // flexion needs the third index
  expectInvalid(m, "bond 1: particle index out of range");
  m = makeModel();
  m.bonds[1].particles[2] = 0;
  expectInvalid(m, "bond 1: joins particle 'a' to itself");
}

TEST(ModelValidate, Interactions) {
  Model m = makeModel();
  m.interactions.push_back(Interaction{1, "g", "g"});
  expectInvalid(m, "interaction type 'bend' must be a spring");
  m.interactions[0].type = 0;
  EXPECT_EQ(validateModel(m), "");  // s01 has max_distance
  m.bond_types[0].param(kMaxDistance).present = false;
  expectInvalid(m, "interaction type 's01' needs max_distance");
  m.interactions[0].type = 7;
  expectInvalid(m, "interaction: unknown bond type");
}

TEST(ModelValidate, ParameterBlocks) {
  Model m = makeModel();
  Param& k = m.bond_types[0].param(kStiffness);
  k.has_min = k.has_max = true;
  k.min = 5.0;
  k.max = 1.0;
  expectInvalid(m, "bond type 's01': stiffness has min > max");
  k.max = 5.0;  // min == max is allowed
  EXPECT_EQ(validateModel(m), "");
  Param& L = m.bond_types[0].param(kRestLength);
  L.has_value = false;
  expectInvalid(m, "bond type 's01': rest_length is fixed but has no value");
  L.has_value = true;
  L.value = std::numeric_limits<double>::infinity();
  expectInvalid(m, "bond type 's01': rest_length must be finite");
}

}  // namespace
}  // namespace mme

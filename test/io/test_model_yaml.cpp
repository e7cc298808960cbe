// Tests of the model file loader/writer (SPEC sections 2 and 4): values, free flags and bounds
// of a complete example, exact round trips, one clear error per kind of bad file, and atomic
// writes.

#include <dirent.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <utility>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "test_helpers.h"

namespace mme {
namespace {

const double kInf = std::numeric_limits<double>::infinity();

// Every bond kind, all 8 spring parameters, a gravity block, a fixed particle, interactions.
const char* kFullModel = R"(frame_id: mocap
frame_rate_hz: 120.5
substeps: 4
gravity: {value: [0.1, -0.2, -9.81], free: true, min: -20, max: [1, ~, 0]}
particles:
  - {name: p0, mass: 1.5, position: [0, 0, 1], velocity: [0.1, 0, 0], fixed: true, group: body}
  - {name: p1, mass: 2, position: [1, 0, 1], group: body}
  - {name: p2, position: [1, 1, 1], group: gas}
  - {name: p3, mass: 0.25, group: gas}
bond_types:
  - name: s01
    kind: spring
    stiffness: {value: 4.0, free: true, min: 0.0, max: 1e4}
    rest_length: {free: true}
    damping: 0.5
    stiffness_nl: {value: 1.25, free: false, min: -3, max: 3}
    damping_nl: {value: 0.125, std: 0.01}
    min_distance: 0.05
    max_distance: {value: 2.5, free: true, max: 10}
    max_elongation: 0.1
  - name: f012
    kind: flexion
    stiffness: {value: 0.3, free: true, min: 0}
    rest_angle: 3.141592653589793
    damping: {value: 0.01, free: true}
  - name: visc
    kind: viscosity
    viscosity: {value: 0.2, free: true, min: 0, max: 5}
  - name: gas_visc
    kind: spring
    stiffness: 1
    max_distance: 0.3
bonds:
  - {type: s01, particles: [p0, p1]}
  - {type: f012, particles: [p0, p1, p2]}
  - {type: visc, particles: [p3]}
interactions:
  - {type: gas_visc, groups: [gas, gas]}
  - {type: gas_visc, groups: [body, gas]}
identification: {method: es, global_cost: 1}
)";

// ------------------------------------------------------------------------ comparison helpers

bool sameBits(double a, double b) {
  std::uint64_t x = 0, y = 0;
  std::memcpy(&x, &a, sizeof x);
  std::memcpy(&y, &b, sizeof y);
  return x == y;
}

#define EXPECT_BITS(a, b) EXPECT_TRUE(sameBits((a), (b))) << #a << " = " << (a) << " vs " << (b)

void expectSameParam(const Param& a, const Param& b, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_EQ(a.present, b.present);
  EXPECT_EQ(a.has_value, b.has_value);
  EXPECT_EQ(a.free, b.free);
  EXPECT_EQ(a.has_min, b.has_min);
  EXPECT_EQ(a.has_max, b.has_max);
  EXPECT_BITS(a.value, b.value);
  EXPECT_BITS(a.min, b.min);
  EXPECT_BITS(a.max, b.max);
}

void expectSameModel(const Model& a, const Model& b) {
  EXPECT_EQ(a.frame_id, b.frame_id);
  EXPECT_BITS(a.frame_rate_hz, b.frame_rate_hz);
  EXPECT_EQ(a.substeps, b.substeps);
  for (int k = 0; k < 3; ++k)
    expectSameParam(a.gravity_mps2[k], b.gravity_mps2[k], "gravity " + std::to_string(k));
  ASSERT_EQ(a.particles.size(), b.particles.size());
  for (size_t i = 0; i < a.particles.size(); ++i) {
    const Particle& p = a.particles[i];
    const Particle& q = b.particles[i];
    SCOPED_TRACE("particle " + p.name);
    EXPECT_EQ(p.name, q.name);
    EXPECT_BITS(p.mass_kg, q.mass_kg);
    for (int k = 0; k < 3; ++k) {
      EXPECT_BITS(p.position_m[k], q.position_m[k]);
      EXPECT_BITS(p.velocity_mps[k], q.velocity_mps[k]);
    }
    EXPECT_EQ(p.fixed, q.fixed);
    EXPECT_EQ(p.group, q.group);
  }
  ASSERT_EQ(a.bond_types.size(), b.bond_types.size());
  for (size_t t = 0; t < a.bond_types.size(); ++t) {
    EXPECT_EQ(a.bond_types[t].name, b.bond_types[t].name);
    EXPECT_EQ(a.bond_types[t].kind, b.bond_types[t].kind);
    for (int id = 0; id < kParamCount; ++id)
      expectSameParam(a.bond_types[t].params[id], b.bond_types[t].params[id],
                      a.bond_types[t].name + "/" + paramKey(static_cast<ParamId>(id)));
    EXPECT_EQ(a.bond_types[t].network_inputs, b.bond_types[t].network_inputs);
    EXPECT_EQ(a.bond_types[t].network_hidden, b.bond_types[t].network_hidden);
    ASSERT_EQ(a.bond_types[t].network.size(), b.bond_types[t].network.size());
    for (size_t k = 0; k < a.bond_types[t].network.size(); ++k)
      expectSameParam(a.bond_types[t].network[k], b.bond_types[t].network[k],
                      a.bond_types[t].name + "/network " + std::to_string(k));
  }
  ASSERT_EQ(a.bonds.size(), b.bonds.size());
  for (size_t i = 0; i < a.bonds.size(); ++i) {
    EXPECT_EQ(a.bonds[i].type, b.bonds[i].type);
    EXPECT_EQ(a.bonds[i].particles, b.bonds[i].particles);
    EXPECT_EQ(a.bonds[i].name, b.bonds[i].name);
    EXPECT_EQ(a.bonds[i].inputs, b.bonds[i].inputs);
  }
  ASSERT_EQ(a.interactions.size(), b.interactions.size());
  for (size_t i = 0; i < a.interactions.size(); ++i) {
    EXPECT_EQ(a.interactions[i].type, b.interactions[i].type);
    EXPECT_EQ(a.interactions[i].group_a, b.interactions[i].group_a);
    EXPECT_EQ(a.interactions[i].group_b, b.interactions[i].group_b);
  }
}

// ------------------------------------------------------------------------------ loading

TEST(ModelYaml, FullExampleLoadsEveryField) {
  const Model m = loadModelString(kFullModel, "full.yaml");
  EXPECT_EQ(m.frame_id, "mocap");
  EXPECT_EQ(m.frame_rate_hz, 120.5);
  EXPECT_EQ(m.substeps, 4);

  // Gravity block: all present and free; scalar min for every axis, per-axis max with ~.
  const double gv[3] = {0.1, -0.2, -9.81};
  for (int k = 0; k < 3; ++k) {
    const Param& g = m.gravity_mps2[k];
    EXPECT_TRUE(g.present && g.has_value && g.free) << k;
    EXPECT_EQ(g.value, gv[k]);
    EXPECT_TRUE(g.has_min);
    EXPECT_EQ(g.min, -20.0);
  }
  EXPECT_TRUE(m.gravity_mps2[0].has_max);
  EXPECT_EQ(m.gravity_mps2[0].max, 1.0);
  EXPECT_FALSE(m.gravity_mps2[1].has_max);
  EXPECT_EQ(m.gravity_mps2[1].max, kInf);
  EXPECT_TRUE(m.gravity_mps2[2].has_max);
  EXPECT_EQ(m.gravity_mps2[2].max, 0.0);

  ASSERT_EQ(m.particles.size(), 4u);
  EXPECT_EQ(m.particles[0].name, "p0");
  EXPECT_EQ(m.particles[0].mass_kg, 1.5);
  EXPECT_EQ(m.particles[0].position_m, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(m.particles[0].velocity_mps, Eigen::Vector3d(0.1, 0, 0));
  EXPECT_TRUE(m.particles[0].fixed);
  EXPECT_EQ(m.particles[0].group, "body");
  EXPECT_FALSE(m.particles[1].fixed);
  EXPECT_EQ(m.particles[1].velocity_mps, Eigen::Vector3d::Zero());
  EXPECT_EQ(m.particles[2].mass_kg, 1.0);  // default mass
  EXPECT_EQ(m.particles[3].position_m, Eigen::Vector3d::Zero());  // default position
  EXPECT_EQ(m.particles[3].group, "gas");

  ASSERT_EQ(m.bond_types.size(), 4u);
  const BondType& s = m.bond_types[0];
  EXPECT_EQ(s.name, "s01");
  EXPECT_EQ(s.kind, BondKind::kSpring);
  const Param& k = s.param(kStiffness);
  EXPECT_TRUE(k.present && k.has_value && k.free && k.has_min && k.has_max);
  EXPECT_EQ(k.value, 4.0);
  EXPECT_EQ(k.min, 0.0);
  EXPECT_EQ(k.max, 1e4);
  const Param& L = s.param(kRestLength);  // free without value
  EXPECT_TRUE(L.present && L.free);
  EXPECT_FALSE(L.has_value || L.has_min || L.has_max);
  const Param& c = s.param(kDamping);  // plain number: fixed
  EXPECT_TRUE(c.present && c.has_value);
  EXPECT_FALSE(c.free || c.has_min || c.has_max);
  EXPECT_EQ(c.value, 0.5);
  const Param& knl = s.param(kStiffnessNl);  // fixed with bounds
  EXPECT_FALSE(knl.free);
  EXPECT_EQ(knl.value, 1.25);
  EXPECT_EQ(knl.min, -3.0);
  EXPECT_EQ(knl.max, 3.0);
  EXPECT_EQ(s.param(kDampingNl).value, 0.125);  // std accepted and ignored
  EXPECT_FALSE(s.param(kDampingNl).free);
  EXPECT_EQ(s.param(kMinDistance).value, 0.05);
  EXPECT_TRUE(s.param(kMaxDistance).free);
  EXPECT_FALSE(s.param(kMaxDistance).has_min);
  EXPECT_EQ(s.param(kMaxDistance).max, 10.0);
  EXPECT_EQ(s.param(kMaxElongation).value, 0.1);
  EXPECT_FALSE(s.param(kRestAngle).present);
  EXPECT_FALSE(s.param(kViscosity).present);

  const BondType& f = m.bond_types[1];
  EXPECT_EQ(f.kind, BondKind::kFlexion);
  EXPECT_EQ(f.param(kRestAngle).value, 3.141592653589793);
  EXPECT_TRUE(f.param(kStiffness).free);
  EXPECT_TRUE(f.param(kDamping).free);
  EXPECT_FALSE(f.param(kRestLength).present);
  const BondType& v = m.bond_types[2];
  EXPECT_EQ(v.kind, BondKind::kViscosity);
  EXPECT_EQ(v.param(kViscosity).value, 0.2);
  EXPECT_EQ(v.param(kViscosity).max, 5.0);

  ASSERT_EQ(m.bonds.size(), 3u);
  EXPECT_EQ(m.bonds[0].type, 0);
  EXPECT_EQ(m.bonds[0].particles[0], 0);
  EXPECT_EQ(m.bonds[0].particles[1], 1);
  EXPECT_EQ(m.bonds[1].type, 1);
  EXPECT_EQ(m.bonds[1].particles[1], 1);  // vertex
  EXPECT_EQ(m.bonds[1].particles[2], 2);
  EXPECT_EQ(m.bonds[2].type, 2);
  EXPECT_EQ(m.bonds[2].particles[0], 3);

  ASSERT_EQ(m.interactions.size(), 2u);
  EXPECT_EQ(m.interactions[0].type, 3);
  EXPECT_EQ(m.interactions[0].group_a, "gas");
  EXPECT_EQ(m.interactions[1].group_a, "body");
  EXPECT_EQ(m.interactions[1].group_b, "gas");

  std::vector<std::string> names;
  for (const ParamRef& r : freeParameters(m)) names.push_back(r.name);
  EXPECT_EQ(names, (std::vector<std::string>{"s01/stiffness", "s01/rest_length",
                                             "s01/max_distance", "f012/stiffness",
                                             "f012/damping", "visc/viscosity", "gravity/x",
                                             "gravity/y", "gravity/z"}));
}

TEST(ModelYaml, DefaultsAndPlainGravity) {
  const Model m = loadModelString("gravity: [0, 0, -9.81]\nparticles:\n  - {name: a}\n", "d.yaml");
  EXPECT_EQ(m.frame_id, "world");
  EXPECT_EQ(m.frame_rate_hz, 0.0);
  EXPECT_EQ(m.substeps, 1);
  for (const Param& g : m.gravity_mps2) {
    EXPECT_TRUE(g.present && g.has_value);
    EXPECT_FALSE(g.free || g.has_min || g.has_max);
  }
  EXPECT_EQ(m.gravity(), Eigen::Vector3d(0, 0, -9.81));
  EXPECT_TRUE(freeParameters(m).empty());
  EXPECT_EQ(presentParameters(m).size(), 3u);

  const Model none = loadModelString("particles: []\n", "n.yaml");
  EXPECT_FALSE(none.gravity_mps2[2].present);
  EXPECT_EQ(none.gravity(), Eigen::Vector3d::Zero());
}

TEST(ModelYaml, SectionsMayComeInAnyOrder) {
  // YAML maps are unordered: bonds before the particles and types they refer to must work.
  const Model m = loadModelString(
      "bonds: [{type: s, particles: [a, b]}]\n"
      "bond_types: [{name: s, kind: spring, stiffness: 1}]\n"
      "particles: [{name: a}, {name: b}]\n",
      "o.yaml");
  ASSERT_EQ(m.bonds.size(), 1u);
  EXPECT_EQ(m.bonds[0].particles[1], 1);
}

TEST(ModelYaml, PerAxisGravityFreeFlags) {
  const Model m =
      loadModelString("gravity: {value: [0, 0, -9.8], free: [false, false, true]}\n", "g.yaml");
  EXPECT_FALSE(m.gravity_mps2[0].free);
  EXPECT_TRUE(m.gravity_mps2[2].free);
  ASSERT_EQ(freeParameters(m).size(), 1u);
  EXPECT_EQ(freeParameters(m)[0].name, "gravity/z");
}

// ---------------------------------------------------------------------------- round trips

TEST(ModelYaml, RoundTripIsExact) {
  const Model m = loadModelString(kFullModel, "full.yaml");
  const std::string text = modelToYaml(m);
  const Model back = loadModelString(text, "export.yaml");
  expectSameModel(m, back);
  EXPECT_EQ(text.find("identification"), std::string::npos);
  EXPECT_EQ(text.find("std:"), std::string::npos);
  // Fixed unbounded parameters are plain numbers; particles are one flow map per line.
  EXPECT_NE(text.find("damping: 0.5\n"), std::string::npos) << text;
  EXPECT_NE(text.find("- {name: p0, mass: 1.5, position: [0, 0, 1], velocity: [0.1, 0, 0], "
                      "fixed: true, group: body}\n"),
            std::string::npos)
      << text;
  // Exporting again gives the same text (nothing drifts).
  EXPECT_EQ(modelToYaml(back), text);
}

TEST(ModelYaml, RoundTripKeepsEveryBitOfAwkwardNumbers) {
  Model m = loadModelString(kFullModel, "full.yaml");
  const double awkward[] = {0.1 + 0.2, 1.0 / 3.0, -0.0, 1e-300, 4.9406564584124654e-324,
                            1.7976931348623157e308, 2.0 / 3.0 * 1e-7, 123456789.12345678};
  int i = 0;
  for (const ParamRef& r : presentParameters(m)) setParam(m, r, awkward[i++ % 8]);
  m.particles[1].position_m = Eigen::Vector3d(awkward[0], awkward[1], awkward[2]);
  m.particles[1].velocity_mps = Eigen::Vector3d(awkward[3], awkward[5], awkward[7]);
  m.particles[1].mass_kg = awkward[1];
  m.frame_rate_hz = awkward[7];
  m.bond_types[0].param(kStiffness).min = -awkward[6];
  // Bounds must stay consistent with min <= max for the reload.
  m.bond_types[0].param(kStiffness).max = awkward[5];
  const Model back = loadModelString(modelToYaml(m), "awkward.yaml");
  expectSameModel(m, back);
}

TEST(ModelYaml, RoundTripWithIdentificationInfo) {
  const Model m = loadModelString(kFullModel, "full.yaml");
  IdentificationInfo info;
  info.method = "es";
  info.global_cost = 0.0123456789;
  info.frames = 100;
  info.generations = 250;
  info.wall_time_s = 12.5;
  info.std_names = {"s01/stiffness", "s01/rest_length", "gravity/z", "visc/viscosity"};
  info.std_values = {0.25, 1e-3, 0.0625, 0.5};
  const std::string text = modelToYaml(m, &info);

  EXPECT_NE(text.find("stiffness: {value: 4, free: true, min: 0, max: 10000, std: 0.25}"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("rest_length: {free: true, std: 0.001}"), std::string::npos) << text;
  EXPECT_NE(text.find("viscosity: {value: 0.2, free: true, min: 0, max: 5, std: 0.5}"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("std: [~, ~, 0.0625]"), std::string::npos) << text;  // gravity
  EXPECT_NE(text.find("identification:\n  method: es\n  global_cost: 0.0123456789\n"
                      "  frames: 100\n  generations: 250\n  wall_time_s: 12.5"),
            std::string::npos)
      << text;
  // Parameters without a std are unchanged.
  EXPECT_NE(text.find("damping: 0.5\n"), std::string::npos) << text;

  // An export is a model file again (std and identification accepted, ignored).
  const Model back = loadModelString(text, "identified.yaml");
  expectSameModel(m, back);
}

TEST(ModelYaml, NamesThatLookLikeOtherTypesStayStrings) {
  Model m;
  m.particles.resize(3);
  m.particles[0].name = "true";
  m.particles[1].name = "007";
  m.particles[2].name = "null";
  m.particles[2].group = "1.5";
  BondType t;
  t.name = "yes";
  t.kind = BondKind::kViscosity;
  t.param(kViscosity).present = t.param(kViscosity).has_value = true;
  t.param(kViscosity).value = 1.0;
  m.bond_types.push_back(t);
  m.bonds.push_back(Bond{0, {{1, -1, -1}}, "", {}});
  const std::string text = modelToYaml(m);
  EXPECT_NE(text.find("name: \"007\""), std::string::npos) << text;
  expectSameModel(m, loadModelString(text, "names.yaml"));
}

// Found by fuzz_model_yaml: a bond type named "\r" loaded, was exported plain and read back as a
// line break ("expected a name"). Names that would not survive a plain scalar are quoted.
TEST(ModelYaml, NamesWithControlCharactersAndBlanksRoundTrip) {
  Model m;
  m.particles.resize(3);
  m.particles[0].name = " lead";
  m.particles[1].name = "trail ";
  m.particles[2].name = "tab\there";
  BondType t;
  t.name = "\r";
  t.kind = BondKind::kViscosity;
  t.param(kViscosity).present = t.param(kViscosity).has_value = true;
  t.param(kViscosity).value = 1.0;
  m.bond_types.push_back(t);
  t.name = "a\nb";
  m.bond_types.push_back(t);
  m.bonds.push_back(Bond{0, {{1, -1, -1}}, "", {}});
  m.bonds.push_back(Bond{1, {{2, -1, -1}}, "", {}});
  const std::string text = modelToYaml(m);
  expectSameModel(m, loadModelString(text, "control_names.yaml"));
}

TEST(ModelYaml, ExportRejectsInvalidModel) {
  Model m;
  m.particles.resize(1);
  m.particles[0].mass_kg = -1.0;
  EXPECT_THROW(modelToYaml(m), InputError);
}

// ---------------------------------------------------------------------------- bad files

// A small valid model; the error tests replace or append one line, so the expected line
// number is known exactly.
const std::vector<std::string> kBase = {
    "frame_id: world",                       // 1
    "particles:",                            // 2
    "  - {name: a, mass: 1}",                // 3
    "  - {name: b, mass: 1}",                // 4
    "  - {name: c, mass: 1, group: g}",      // 5
    "bond_types:",                           // 6
    "  - name: s",                           // 7
    "    kind: spring",                      // 8
    "    stiffness: 1",                      // 9
    "    rest_length: 1",                    // 10
    "  - name: f",                           // 11
    "    kind: flexion",                     // 12
    "    stiffness: 1",                      // 13
    "bonds:",                                // 14
    "  - {type: s, particles: [a, b]}",      // 15
};

/// `base` with line `line` (1-based) replaced by `text`; line = size+1 appends.
std::string editedLines(const std::vector<std::string>& base, int line, const std::string& text) {
  std::string out;
  for (int i = 1; i <= static_cast<int>(base.size()) + 1; ++i) {
    if (i == line)
      out += text + "\n";
    else if (i <= static_cast<int>(base.size()))
      out += base[i - 1] + "\n";
  }
  return out;
}

std::string edited(int line, const std::string& text) { return editedLines(kBase, line, text); }

std::string errorOf(const std::string& yaml, const std::string& source = "bad.yaml") {
  try {
    loadModelString(yaml, source);
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no error>";
}

/// The message must start with "bad.yaml:LINE: key 'KEY': " and contain `reason`.
void expectError(const std::string& yaml, int line, const std::string& key,
                 const std::string& reason) {
  const std::string msg = errorOf(yaml);
  const std::string prefix = "bad.yaml:" + std::to_string(line) + ": key '" + key + "': ";
  EXPECT_EQ(msg.rfind(prefix, 0), 0u) << "message: " << msg << "\nexpected prefix: " << prefix;
  EXPECT_NE(msg.find(reason), std::string::npos) << "message: " << msg << "\nexpected: " << reason;
}

TEST(ModelYamlErrors, BaseModelIsValid) {
  const Model m = loadModelString(edited(99, ""), "bad.yaml");
  EXPECT_EQ(m.bonds.size(), 1u);
}

TEST(ModelYamlErrors, UnknownTopLevelKey) {
  expectError(edited(16, "colour: red"), 16, "colour", "unknown top-level key");
}

TEST(ModelYamlErrors, UnknownKeyInBondType) {
  expectError(edited(10, "    stifness: 1"), 10, "stifness", "bond type 's'");
}

TEST(ModelYamlErrors, ParameterOfAnotherKind) {
  expectError(edited(10, "    rest_angle: 1"), 10, "rest_angle", "spring");
}

TEST(ModelYamlErrors, UnknownKeyInParameterBlock) {
  expectError(edited(9, "    stiffness: {value: 1, mn: 0}"), 9, "stiffness.mn",
              "unknown key in a parameter block in bond type 's'");
}

TEST(ModelYamlErrors, UnknownKeyInParticle) {
  expectError(edited(4, "  - {name: b, mas: 1}"), 4, "mas", "unknown key in particle 'b'");
}

TEST(ModelYamlErrors, UnknownParticleInBond) {
  expectError(edited(15, "  - {type: s, particles: [a, zz]}"), 15, "particles",
              "unknown particle 'zz' in bonds[0]");
}

TEST(ModelYamlErrors, ThreeParticlesOnASpring) {
  expectError(edited(15, "  - {type: s, particles: [a, b, c]}"), 15, "particles",
              "joins 2 particles, got 3");
}

TEST(ModelYamlErrors, TwoParticlesOnAFlexion) {
  expectError(edited(15, "  - {type: f, particles: [a, b]}"), 15, "particles",
              "joins 3 particles, got 2");
}

TEST(ModelYamlErrors, BondJoiningAParticleToItself) {
  expectError(edited(15, "  - {type: s, particles: [a, a]}"), 15, "particles",
              "joins particle 'a' to itself");
}

TEST(ModelYamlErrors, NegativeAndZeroMass) {
  expectError(edited(4, "  - {name: b, mass: -2}"), 4, "mass", "mass must be > 0");
  expectError(edited(4, "  - {name: b, mass: 0}"), 4, "mass", "particle 'b'");
}

TEST(ModelYamlErrors, BondTypeMissing) {
  expectError(edited(15, "  - {particles: [a, b]}"), 15, "type", "bond type missing in bonds[0]");
}

TEST(ModelYamlErrors, UnknownBondType) {
  expectError(edited(15, "  - {type: spring9, particles: [a, b]}"), 15, "type",
              "unknown bond type 'spring9'");
}

TEST(ModelYamlErrors, DuplicateParticleName) {
  expectError(edited(5, "  - {name: a, mass: 1}"), 5, "name",
              "duplicate particle name 'a' (first at line 3)");
}

TEST(ModelYamlErrors, DuplicateBondTypeName) {
  expectError(edited(11, "  - name: s"), 11, "name", "duplicate bond type name 's'");
}

TEST(ModelYamlErrors, FixedParameterWithoutValue) {
  expectError(edited(9, "    stiffness: {free: false, min: 0}"), 9, "stiffness",
              "a fixed parameter needs a value");
}

TEST(ModelYamlErrors, MinGreaterThanMax) {
  expectError(edited(9, "    stiffness: {value: 1, free: true, min: 5, max: 1}"), 9, "stiffness",
              "min (5) > max (1) in bond type 's'");
}

TEST(ModelYamlErrors, MalformedNumber) {
  expectError(edited(9, "    stiffness: {value: abc, free: true}"), 9, "stiffness.value",
              "expected a number, got 'abc'");
  expectError(edited(16, "substeps: 1.5"), 16, "substeps", "expected an integer");
  expectError(edited(16, "substeps: 0"), 16, "substeps", "must be >= 1");
  expectError(edited(16, "frame_rate_hz: -1"), 16, "frame_rate_hz", "must be >= 0");
  expectError(edited(3, "  - {name: a, position: [1, 2]}"), 3, "position", "3 numbers");
}

TEST(ModelYamlErrors, UnknownKind) {
  expectError(edited(12, "    kind: hinge"), 12, "kind",
              "unknown kind 'hinge' (expected spring, flexion, viscosity, muscle or floor)");
}

// ------------------------------------------------------------------------------ muscles

// A muscle reading two springs, one of them declared after it; hidden layer of 1.
const std::vector<std::string> kMuscleBase = {
    "particles:",                                                       // 1
    "  - {name: a, mass: 1}",                                           // 2
    "  - {name: b, mass: 1}",                                           // 3
    "  - {name: c, mass: 1}",                                           // 4
    "bond_types:",                                                      // 5
    "  - {name: s, kind: spring, stiffness: 10, rest_length: 0.2}",     // 6
    "  - {name: f, kind: flexion, stiffness: 1, rest_angle: 2}",        // 7
    "  - name: m",                                                      // 8
    "    kind: muscle",                                                 // 9
    "    stiffness: {value: 40, free: true, min: 1, max: 400}",         // 10
    "    rest_length: 0.25",                                            // 11
    "    damping: 0.5",                                                 // 12
    "    gain: {value: 2.5, free: true, std: 0.1}",                     // 13
    "    inputs: 2",                                                    // 14
    "    hidden: 1",                                                    // 15
    "    w1_0_0: {value: 30, free: true, min: -50, max: 50}",           // 16
    "    w1_0_3: -1.5",                                                 // 17
    "    w2_0: {value: 1.25, free: true}",                              // 18
    "    b2: 0.1",                                                      // 19
    "bonds:",                                                           // 20
    "  - {type: s, particles: [a, b], name: ab}",                       // 21
    "  - {type: m, particles: [a, c], inputs: [ab, bc]}",               // 22
    "  - {type: s, particles: [b, c], name: bc}",                       // 23
    "  - {type: f, particles: [a, b, c], name: abc}",                   // 24
};

std::string muscleEdited(int line, const std::string& text) {
  return editedLines(kMuscleBase, line, text);
}

TEST(ModelYaml, MuscleLoadsItsNetworkAndInputs) {
  const Model m = loadModelString(muscleEdited(99, ""), "muscle.yaml");
  const BondType& t = m.bond_types[m.bondTypeIndex("m")];
  EXPECT_EQ(t.kind, BondKind::kMuscle);
  EXPECT_EQ(t.network_inputs, 2);
  EXPECT_EQ(t.network_hidden, 1);
  ASSERT_EQ(t.network.size(), 7u);  // w1_0_0..3, b1_0, w2_0, b2
  EXPECT_TRUE(t.network[0].free);
  EXPECT_EQ(t.network[0].max, 50.0);
  EXPECT_EQ(t.network[3].value, -1.5);
  EXPECT_FALSE(t.network[1].present);  // absent: 0, fixed
  EXPECT_FALSE(t.network[4].present);
  EXPECT_EQ(t.network[5].value, 1.25);
  EXPECT_EQ(t.network[6].value, 0.1);
  EXPECT_EQ(t.value(kGain), 2.5);
  EXPECT_EQ(m.bonds[1].inputs, (std::vector<int>{0, 2}));
  EXPECT_EQ(m.bonds[0].name, "ab");
  std::vector<std::string> names;
  for (const ParamRef& r : freeParameters(m)) names.push_back(r.name);
  EXPECT_EQ(names, (std::vector<std::string>{"m/stiffness", "m/gain", "m/w1_0_0", "m/w2_0"}));
}

TEST(ModelYaml, MuscleActivationTimeConstantLoadsRoundTripsAndIsChecked) {
  const Model m = loadModelString(muscleEdited(12, "    damping: 0.5\n    activation_time_constant: 0.05"),
                                  "tau.yaml");
  EXPECT_EQ(m.bond_types[m.bondTypeIndex("m")].value(kActivationTime), 0.05);
  const std::string text = modelToYaml(m);
  EXPECT_NE(text.find("activation_time_constant"), std::string::npos);
  expectSameModel(m, loadModelString(text, "back.yaml"));
  // Without the key the muscle has none (and the file does not mention it).
  const Model plain = loadModelString(muscleEdited(99, ""), "muscle.yaml");
  EXPECT_FALSE(plain.bond_types[plain.bondTypeIndex("m")].param(kActivationTime).present);
  EXPECT_EQ(modelToYaml(loadModelString(muscleEdited(99, ""), "m.yaml")).find("activation_time"),
            std::string::npos);
  try {
    loadModelString(muscleEdited(12, "    damping: 0.5\n    activation_time_constant: -0.1"), "neg.yaml");
    ADD_FAILURE() << "a negative time constant was accepted";
  } catch (const mme::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("activation_time_constant must be >= 0"), std::string::npos)
        << e.what();
  }
}

TEST(ModelYaml, MuscleRoundTripIsExact) {
  const Model m = loadModelString(muscleEdited(99, ""), "muscle.yaml");
  const std::string text = modelToYaml(m);
  const Model back = loadModelString(text, "back.yaml");
  expectSameModel(m, back);
  EXPECT_EQ(modelToYaml(back), text);
  // The test helpers' muscle object (built in code) too.
  const Model object = mme::test::muscleObject();
  expectSameModel(object, loadModelString(modelToYaml(object), "object.yaml"));
}

TEST(ModelYamlErrors, BadMuscleDefinitions) {
  expectError(muscleEdited(22, "  - {type: m, particles: [a, c], inputs: [ab, xy]}"), 22, "inputs",
              "unknown input bond 'xy' (no bond has that name) in bonds[1]");
  expectError(muscleEdited(22, "  - {type: m, particles: [a, c], inputs: [ab]}"), 22, "inputs",
              "muscle type 'm' reads 2 input bond(s), got 1 in bonds[1]");
  expectError(muscleEdited(22, "  - {type: m, particles: [a, c]}"), 22, "inputs",
              "a muscle bond (type 'm') names its 2 input bond(s)");
  expectError(muscleEdited(22, "  - {type: m, particles: [a, c], inputs: [ab, abc]}"), 22, "inputs",
              "input bond 'abc' is a flexion (inputs must be springs or muscles");
  expectError(muscleEdited(22, "  - {type: m, particles: [a, c], inputs: [ab, me], name: me}"), 22,
              "inputs", "a muscle cannot read its own bond");
  expectError(muscleEdited(21, "  - {type: s, particles: [a, b], name: ab, inputs: [bc]}"), 21,
              "inputs", "only muscle bonds have inputs (type 's' is a spring)");
  expectError(muscleEdited(23, "  - {type: s, particles: [b, c], name: ab}"), 23, "name",
              "duplicate bond name 'ab' (first at line 21)");
  expectError(muscleEdited(17, "    w1_1_0: 2"), 17, "w1_1_0",
              "unknown key for a muscle in bond type 'm' (allowed: name, kind, stiffness, "
              "rest_length, damping, gain, activation_time_constant, inputs, hidden, and the network's "
              "w1_<0..0>_<0..3>, b1_<0..0>, w2_<0..0>, b2 (inputs 2, hidden 1))");
  expectError(muscleEdited(15, "    hidden: 40"), 15, "hidden", "must be in [0, 32]");
  // A muscle reading no bond (a constant activation gain tanh(b2)) needs no inputs key.
  std::string constant = muscleEdited(14, "    inputs: 0");
  constant = constant.substr(0, constant.find("    w1_0_0")) + "bonds: [{type: m, particles: [a, c]}]\n";
  const Model c = loadModelString(constant, "constant.yaml");
  EXPECT_TRUE(c.bonds[0].inputs.empty());
  EXPECT_EQ(c.bond_types[2].network.size(), 3u);  // hidden 1, no input: b1_0, w2_0, b2
  expectError(muscleEdited(14, "    inputs: -1"), 14, "inputs", "must be in [0, 16]");
  expectError(muscleEdited(12, "    stiffness_nl: 3"), 12, "stiffness_nl", "unknown key for a muscle");
}

TEST(ModelYamlErrors, DuplicateKey) {
  expectError(edited(10, "    stiffness: 2"), 10, "stiffness", "duplicate key (first at line 9)");
}

TEST(ModelYamlErrors, Interactions) {
  // Type without max_distance.
  expectError(edited(16, "interactions: [{type: s, groups: [g, g]}]"), 16, "type",
              "must be a spring with max_distance");
  // Unknown group.
  const std::string with_range = edited(10, "    max_distance: 0.5");
  std::string doc = with_range + "interactions:\n  - {type: s, groups: [g, gas]}\n";
  expectError(doc, 17, "groups", "no particle is in group 'gas'");
  EXPECT_EQ(loadModelString(with_range + "interactions: [{type: s, groups: [g, g]}]\n", "ok.yaml")
                .interactions.size(),
            1u);
}

TEST(ModelYamlErrors, GravityBlock) {
  expectError(edited(16, "gravity: {free: false}"), 16, "gravity.value",
              "fixed gravity component x needs a value");
  expectError(edited(16, "gravity: {value: [0, 0, -9.8], free: true, min: 1, max: [2, 0, 2]}"),
              16, "gravity", "min > max for component y");
  expectError(edited(16, "gravity: [0, -9.8]"), 16, "gravity", "3 numbers");
  expectError(edited(16, "gravity: {value: [0, 0, 1], fre: true}"), 16, "gravity.fre",
              "unknown key in the gravity block");
}

TEST(ModelYamlErrors, YamlSyntaxError) {
  const std::string msg = errorOf(edited(15, "  - {type: s, particles: [a, b}"));
  EXPECT_EQ(msg.rfind("bad.yaml:15: YAML syntax error", 0), 0u) << msg;
}

TEST(ModelYamlErrors, NotAMap) {
  EXPECT_EQ(errorOf("- a\n- b\n").rfind("bad.yaml:1: the model must be a YAML map", 0), 0u);
  EXPECT_EQ(errorOf("").rfind("bad.yaml:1: the model file is empty", 0), 0u);
}

TEST(ModelYamlErrors, SourceNameAppearsInMessage) {
  const std::string msg = errorOf(edited(16, "colour: red"), "/some/dir/my_model.yaml");
  EXPECT_EQ(msg.rfind("/some/dir/my_model.yaml:16: key 'colour': ", 0), 0u) << msg;
}

// ------------------------------------------------------------------------------ files

class TempDir {
 public:
  TempDir() {
    char templ[] = "/tmp/test_model_yaml.XXXXXX";
    const char* d = ::mkdtemp(templ);
    path_ = d ? d : "";
  }
  ~TempDir() {
    if (!path_.empty()) std::system(("rm -rf '" + path_ + "'").c_str());
  }
  const std::string& path() const { return path_; }
  std::vector<std::string> entries() const {
    std::vector<std::string> out;
    if (DIR* d = ::opendir(path_.c_str())) {
      while (dirent* e = ::readdir(d)) {
        const std::string n = e->d_name;
        if (n != "." && n != "..") out.push_back(n);
      }
      ::closedir(d);
    }
    return out;
  }

 private:
  std::string path_;
};

TEST(ModelYamlFiles, MissingFile) {
  try {
    loadModelFile("/nonexistent/dir/model.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("/nonexistent/dir/model.yaml: cannot read file", 0), 0u)
        << e.what();
  }
}

TEST(ModelYamlFiles, ErrorsInAFileNameThePath) {
  TempDir dir;
  ASSERT_FALSE(dir.path().empty());
  const std::string path = dir.path() + "/broken.yaml";
  std::ofstream(path) << edited(4, "  - {name: b, mass: -2}");
  try {
    loadModelFile(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ":4: key 'mass': mass must be > 0", 0), 0u)
        << e.what();
  }
}

// A capture or a bag given where a model file is expected is recognised by its content and
// named, instead of a YAML syntax error about its bytes.
TEST(ModelYamlFiles, FilesOfAnotherKindAreNamed) {
  TempDir dir;
  ASSERT_FALSE(dir.path().empty());
  const std::string c3d = MME_TEST_DATA_DIR "/real/Sample26_Walking_Hybrid_1_1.c3d";
  const std::string trc = dir.path() + "/walk.trc";
  std::ofstream(trc) << "PathFileType\t4\t(X/Y/Z)\twalk.trc\nDataRate\tUnits\n100\tmm\n";
  const std::string bag = dir.path() + "/walk.bag";
  std::ofstream(bag) << "#ROSBAG V2.0\n" << std::string(20, '\0');
  const std::pair<std::string, std::string> cases[] = {
      {c3d, ": this is a C3D file (a capture), not a model file"},
      {trc, ": this is a TRC marker file (a capture), not a model file"},
      {bag, ": this is a rosbag, not a model file"}};
  for (const auto& [path, says] : cases) {
    try {
      loadModelFile(path);
      ADD_FAILURE() << path << ": no error";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + says, 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find("a capture goes to --trajectory"), std::string::npos) << e.what();
    }
  }
}

TEST(ModelYamlFiles, WriteAndReload) {
  TempDir dir;
  ASSERT_FALSE(dir.path().empty());
  const Model m = loadModelString(kFullModel, "full.yaml");
  const std::string path = dir.path() + "/out.yaml";
  std::ofstream(path) << "old content\n";  // replaced atomically
  IdentificationInfo info;
  info.method = "es";
  info.std_names = {"s01/stiffness"};
  info.std_values = {0.5};
  writeModelFile(path, m, &info);
  expectSameModel(m, loadModelFile(path));
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.yaml"});  // no temp file left
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), modelToYaml(m, &info));
}

TEST(ModelYamlFiles, UnwritablePathThrowsAndLeavesNothing) {
  // Directory that does not exist: the temp file cannot even be created.
  try {
    writeModelFile("/nonexistent_dir_mme/x.yaml", Model());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("/nonexistent_dir_mme/x.yaml: cannot write: ", 0), 0u)
        << e.what();
  }
  // Target is a directory: the temp file is written, the rename fails, the temp file must be
  // removed (this works even when the tests run as root, unlike a read-only directory).
  TempDir dir;
  ASSERT_FALSE(dir.path().empty());
  const std::string target = dir.path() + "/sub";
  ASSERT_EQ(::mkdir(target.c_str(), 0755), 0);
  ASSERT_EQ(::close(::creat((target + "/keep").c_str(), 0644)), 0);
  try {
    writeFileAtomically(target, "content\n");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(target + ": cannot write: ", 0), 0u) << e.what();
  }
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"sub"});
}

}  // namespace
}  // namespace mme

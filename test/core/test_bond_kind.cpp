// The bond-kind catalogue: one entry per enumerator, in enum order, with the facts the rest of
// the package reads (names the model file uses, arities, parameter lists, what each kind may do),
// complete for every kind: the simulator reaches every kind's force law, the equation error and
// structure selection read how it is linear from the entry, so adding a kind edits no switch in
// them (docs/architecture.md "Adding a bond kind").
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <string>

#include "../../src/core/engine.h"  // the simulator's engine: its generic path against the fast ones
#include "motion_model_estimation/core/bond_kind.h"
#include "motion_model_estimation/core/forces.h"
#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/simulator.h"
#include "test_helpers.h"

namespace {

using mme::BondKind;
using mme::bondKindInfo;

TEST(BondKind, TheCatalogueHasOneEntryPerKindInEnumOrder) {
  const std::vector<BondKind>& kinds = mme::allBondKinds();
  ASSERT_EQ(kinds.size(), 5u);
  std::set<std::string> names;
  for (size_t k = 0; k < kinds.size(); ++k) {
    EXPECT_EQ(static_cast<size_t>(kinds[k]), k);
    EXPECT_EQ(bondKindInfo(kinds[k]).kind, kinds[k]);
    names.insert(bondKindInfo(kinds[k]).name);
  }
  EXPECT_EQ(names.size(), kinds.size()) << "kind names must be unique";
}

TEST(BondKind, NamesRoundTripAndUnknownNamesAreNull) {
  for (BondKind k : mme::allBondKinds()) {
    const mme::BondKindInfo* info = mme::bondKindByName(bondKindInfo(k).name);
    ASSERT_NE(info, nullptr);
    EXPECT_EQ(info->kind, k);
  }
  EXPECT_EQ(mme::bondKindByName("hinge"), nullptr);
  EXPECT_EQ(mme::bondKindByName(""), nullptr);
  EXPECT_EQ(mme::bondKindNameList(), "spring, flexion, viscosity, muscle or floor");
}

TEST(BondKind, FactsOfEachKind) {
  EXPECT_STREQ(bondKindInfo(BondKind::kMuscle).name, "muscle");
  EXPECT_EQ(bondKindInfo(BondKind::kMuscle).arity, 2);
  EXPECT_EQ(bondKindInfo(BondKind::kMuscle).params,
            (std::vector<mme::ParamId>{mme::kStiffness, mme::kRestLength, mme::kDamping,
                                       mme::kGain, mme::kActivationTime}));
  EXPECT_TRUE(bondKindInfo(BondKind::kMuscle).network);
  EXPECT_TRUE(bondKindInfo(BondKind::kMuscle).has_elongation);
  EXPECT_FALSE(bondKindInfo(BondKind::kMuscle).interactions);
  EXPECT_TRUE(bondKindInfo(BondKind::kSpring).interactions);
  EXPECT_TRUE(bondKindInfo(BondKind::kSpring).has_elongation);
  EXPECT_FALSE(bondKindInfo(BondKind::kFlexion).has_elongation);
  EXPECT_FALSE(bondKindInfo(BondKind::kViscosity).has_elongation);
  EXPECT_EQ(bondKindInfo(BondKind::kFloor).arity, 1);
  EXPECT_EQ(bondKindInfo(BondKind::kFloor).params,
            (std::vector<mme::ParamId>{mme::kStiffness, mme::kDamping, mme::kFriction, mme::kHeight,
                                       mme::kContactDepth}));
  EXPECT_FALSE(bondKindInfo(BondKind::kFloor).has_elongation);
  for (BondKind k : {BondKind::kSpring, BondKind::kFlexion, BondKind::kViscosity, BondKind::kFloor})
    EXPECT_FALSE(bondKindInfo(k).network) << bondKindInfo(k).name;
  // The model's helpers read the same table.
  for (BondKind k : mme::allBondKinds()) {
    EXPECT_EQ(mme::kindArity(k), bondKindInfo(k).arity);
    EXPECT_STREQ(mme::kindName(k), bondKindInfo(k).name);
    EXPECT_EQ(&mme::paramsOfKind(k), &bondKindInfo(k).params);
  }
}

TEST(BondKind, EveryParameterHasADistinctKey) {
  std::set<std::string> keys;
  for (int id = 0; id < mme::kParamCount; ++id) {
    const std::string key = mme::paramKey(static_cast<mme::ParamId>(id));
    EXPECT_NE(key, "?") << id;
    keys.insert(key);
  }
  EXPECT_EQ(keys.size(), static_cast<size_t>(mme::kParamCount));
  EXPECT_STREQ(mme::paramKey(mme::kGain), "gain");
}

// The parameter catalogue: an entry per id, in id order, with its key; the facts the search
// space, the equation error and structure selection read agree with the physics they encode.
TEST(ParamInfo, OneEntryPerParameterWithItsFacts) {
  for (int id = 0; id < mme::kParamCount; ++id) {
    const mme::ParamInfo& info = mme::paramInfo(static_cast<mme::ParamId>(id));
    EXPECT_EQ(info.id, id);
    EXPECT_STREQ(info.key, mme::paramKey(info.id));
    EXPECT_STRNE(info.unit, "");
    // A length-like parameter is a positive magnitude searched in log space.
    if (info.length_like) {
      EXPECT_TRUE(info.log_search && info.physically_positive) << info.key;
    }
  }
  EXPECT_TRUE(mme::paramInfo(mme::kRestLength).length_like);
  EXPECT_TRUE(mme::paramInfo(mme::kMaxDistance).length_like);
  EXPECT_FALSE(mme::paramInfo(mme::kStiffness).length_like);
  // Signed parameters: a rest angle, a floor height (both searched linearly), a cubic stiffness
  // (a softening spring is physical; the search covers the stiffening side in log space).
  EXPECT_FALSE(mme::paramInfo(mme::kRestAngle).log_search);
  EXPECT_FALSE(mme::paramInfo(mme::kHeight).log_search);
  EXPECT_FALSE(mme::paramInfo(mme::kStiffnessNl).physically_positive);
  EXPECT_TRUE(mme::paramInfo(mme::kStiffnessNl).log_search);
  EXPECT_TRUE(mme::paramInfo(mme::kDamping).physically_positive);
  EXPECT_STREQ(mme::paramInfo(mme::kStiffness).unit, "N/m");
  EXPECT_STREQ(mme::paramInfo(mme::kActivationTime).unit, "s");
}

bool has(const std::vector<mme::ParamId>& params, mme::ParamId id) {
  return std::find(params.begin(), params.end(), id) != params.end();
}

// What the simulator, the equation error and structure selection read of a kind, for every
// kind: a force law (or the network kind's own path), the parameters its linear form solves for,
// and a distinct candidate prefix only where the equation error can solve the candidate.
TEST(BondKind, EveryEntryIsCompleteForTheSimulatorTheEstimatorsAndStructureSelection) {
  std::set<std::string> prefixes;
  for (BondKind k : mme::allBondKinds()) {
    const mme::BondKindInfo& info = bondKindInfo(k);
    SCOPED_TRACE(info.name);
    EXPECT_GE(info.arity, 1);
    EXPECT_LE(info.arity, 3);  // Bond::particles
    EXPECT_FALSE(info.params.empty());
    for (mme::ParamId id : info.params) EXPECT_LT(id, mme::kParamCount);
    EXPECT_EQ(std::set<mme::ParamId>(info.params.begin(), info.params.end()).size(),
              info.params.size());
    // Simulator: a kind without a generic force law is one whose force reads other bonds (the
    // network kind, on the muscle path); an energy without a force is a mistake.
    const mme::BondLaw& law = mme::bondLaw(k);
    EXPECT_EQ(law.force == nullptr, info.network);
    if (law.force == nullptr) {
      EXPECT_EQ(law.energy, nullptr);
    }
    // Equation error: the form's parameters are the kind's, on the form's particles.
    switch (info.linear_form) {
      case mme::LinearForm::kPair:
        EXPECT_EQ(info.arity, 2);
        for (mme::ParamId id : {mme::kStiffness, mme::kRestLength, mme::kDamping,
                                mme::kStiffnessNl, mme::kDampingNl})
          EXPECT_TRUE(has(info.params, id)) << mme::paramKey(id);
        break;
      case mme::LinearForm::kAngle:
        EXPECT_EQ(info.arity, 3);
        for (mme::ParamId id : {mme::kStiffness, mme::kRestAngle, mme::kDamping})
          EXPECT_TRUE(has(info.params, id)) << mme::paramKey(id);
        break;
      case mme::LinearForm::kDrag:
        EXPECT_EQ(info.arity, 1);
        EXPECT_TRUE(has(info.params, mme::kViscosity));
        break;
      case mme::LinearForm::kNone:
        break;
    }
    // Structure selection: its candidates are solved by the equation error, and its shared
    // types are named by a prefix of their own.
    if (info.candidate_prefix != nullptr) {
      EXPECT_NE(info.linear_form, mme::LinearForm::kNone);
      EXPECT_STRNE(info.candidate_prefix, "");
      EXPECT_TRUE(prefixes.insert(info.candidate_prefix).second) << "prefix used twice";
    }
  }
  EXPECT_EQ(bondKindInfo(BondKind::kSpring).linear_form, mme::LinearForm::kPair);
  EXPECT_EQ(bondKindInfo(BondKind::kFlexion).linear_form, mme::LinearForm::kAngle);
  EXPECT_EQ(bondKindInfo(BondKind::kViscosity).linear_form, mme::LinearForm::kDrag);
  EXPECT_EQ(bondKindInfo(BondKind::kMuscle).linear_form, mme::LinearForm::kNone);
  EXPECT_EQ(bondKindInfo(BondKind::kFloor).linear_form, mme::LinearForm::kNone);
  EXPECT_EQ(prefixes, (std::set<std::string>{"s", "f", "v"}));
  EXPECT_EQ(mme::paramInfo(mme::kMaxDistance).absent_value, 1e300);  // SpringLaw's "no bound"
  EXPECT_EQ(mme::paramInfo(mme::kMinDistance).absent_value, 0.0);
}

// A value for every parameter a test bond carries: a spring active over [0.1, 3] m, a floor at
// z = 0.5 m that the particles (z 0.25..0.35 m) are below.
double testValue(mme::ParamId id) {
  static const std::map<mme::ParamId, double> kValues{
      {mme::kStiffness, 40.0},    {mme::kRestLength, 0.6},   {mme::kDamping, 0.3},
      {mme::kStiffnessNl, 5.0},   {mme::kDampingNl, 0.1},    {mme::kMinDistance, 0.1},
      {mme::kMaxDistance, 3.0},   {mme::kMaxElongation, 0.5}, {mme::kRestAngle, 1.2},
      {mme::kViscosity, 0.2},     {mme::kFriction, 0.4},     {mme::kHeight, 0.5},
      {mme::kContactDepth, 0.05}};
  const auto it = kValues.find(id);
  return it == kValues.end() ? 0.5 : it->second;
}

// Three moving particles below the floor height; gravity along -z.
mme::Model threeParticles() {
  mme::Model m;
  m.frame_rate_hz = 100;
  for (int k = 0; k < 3; ++k) m.gravity_mps2[k] = mme::valueParam(k == 2 ? -9.81 : 0.0);
  mme::test::addParticle(&m, Eigen::Vector3d(0.1, 0.2, 0.3), 1.2, false, "",
                         Eigen::Vector3d(0.3, -0.2, -0.4));
  mme::test::addParticle(&m, Eigen::Vector3d(0.9, 0.4, 0.25), 0.8, false, "",
                         Eigen::Vector3d(-0.1, 0.5, 0.2));
  mme::test::addParticle(&m, Eigen::Vector3d(0.5, 1.0, 0.35), 0.6, false, "",
                         Eigen::Vector3d(0.2, 0.1, -0.3));
  return m;
}

// The simulator reaches every kind's law: one bond of the kind, every parameter of the kind
// present, and the simulator's force is gravity plus the law's force evaluated directly.
TEST(BondLaw, TheSimulatorAppliesEveryKindsLaw) {
  for (BondKind k : mme::allBondKinds()) {
    const mme::BondKindInfo& info = bondKindInfo(k);
    const mme::BondLaw& law = mme::bondLaw(k);
    if (law.force == nullptr) continue;  // the network kind: test_muscle, test_sensor_muscles
    SCOPED_TRACE(info.name);
    mme::Model m = threeParticles();
    mme::BondType type;
    type.name = "t";
    type.kind = k;
    for (mme::ParamId id : info.params) type.param(id) = mme::valueParam(testValue(id), false);
    m.bond_types.push_back(type);
    mme::addBond(&m, 0, 0, info.arity > 1 ? 1 : -1, info.arity > 2 ? 2 : -1);
    ASSERT_EQ(mme::validateModel(m), "");
    mme::Simulator sim(m);
    const mme::State s = sim.initialState();
    std::vector<Eigen::Vector3d> f_sim;
    sim.computeForces(s, &f_sim);

    double params[mme::kParamCount];
    for (int id = 0; id < mme::kParamCount; ++id)
      params[id] = mme::paramInfo(static_cast<mme::ParamId>(id)).absent_value;
    for (mme::ParamId id : info.params) params[id] = testValue(id);
    std::vector<Eigen::Vector3d> f_law(3);
    for (int i = 0; i < 3; ++i) f_law[i] = m.particles[i].mass_kg * m.gravity();
    const double* xs[3] = {s.x_m[0].data(), s.x_m[1].data(), s.x_m[2].data()};
    const double* vs[3] = {s.v_mps[0].data(), s.v_mps[1].data(), s.v_mps[2].data()};
    double* fs[3] = {f_law[0].data(), f_law[1].data(), f_law[2].data()};
    law.force(params, xs, vs, fs);
    double bond_force_n = 0.0;
    for (int i = 0; i < 3; ++i) {
      bond_force_n += (f_law[i] - m.particles[i].mass_kg * m.gravity()).norm();
      for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(f_sim[i][c], f_law[i][c]) << i << "," << c;
    }
    EXPECT_GT(bond_force_n, 1e-3) << "the test bond must exert a force";
  }
}

// The generic per-bond path (what a kind without a fast path takes) gives the fast paths'
// forces and energy for every built-in kind it can carry, also after a parameter is set.
TEST(BondLaw, TheGenericPathGivesTheFastPathsForcesAndEnergy) {
  mme::Model m = threeParticles();
  mme::test::addParticle(&m, Eigen::Vector3d(0.4, 0.5, 0.9), 0.9, false, "",
                         Eigen::Vector3d(0.0, -0.3, 0.1));
  for (BondKind k : mme::allBondKinds()) {
    const mme::BondKindInfo& info = bondKindInfo(k);
    if (mme::bondLaw(k).force == nullptr) continue;
    mme::BondType type;
    type.name = info.name;
    type.kind = k;
    for (mme::ParamId id : info.params) type.param(id) = mme::valueParam(testValue(id), true);
    m.bond_types.push_back(type);
    const int t = static_cast<int>(m.bond_types.size()) - 1;
    if (info.arity == 1) {
      for (int p = 0; p < 4; ++p) mme::addBond(&m, t, p);
    } else if (info.arity == 2) {
      mme::addBond(&m, t, 0, 1);
      mme::addBond(&m, t, 2, 3);
      mme::addBond(&m, t, 1, 3);
    } else {
      mme::addBond(&m, t, 0, 1, 2);
      mme::addBond(&m, t, 1, 2, 3);
    }
  }
  ASSERT_EQ(mme::validateModel(m), "");
  const mme::detail::Engine fast(m), generic(m, /*fast_paths=*/false);
  ASSERT_EQ(fast.numGenericBonds(), 0u);
  ASSERT_EQ(generic.numGenericBonds(), m.bonds.size());
  mme::detail::LawTable laws;
  laws.load(m);
  const mme::State s = mme::Simulator(m).initialState();
  const double* x = s.x_m[0].data();
  const double* v = s.v_mps[0].data();
  const auto compare = [&](const char* when) {
    SCOPED_TRACE(when);
    std::vector<double> f_fast(12), f_generic(12);
    fast.forces(laws, x, v, f_fast.data(), nullptr, nullptr, nullptr, 0);
    generic.forces(laws, x, v, f_generic.data(), nullptr, nullptr, nullptr, 0);
    for (size_t k = 0; k < 12; ++k)  // the same terms, summed in another order
      EXPECT_NEAR(f_generic[k], f_fast[k], 1e-12 * (1.0 + std::fabs(f_fast[k]))) << k;
    const double e_fast = fast.bondEnergy(laws, x);
    EXPECT_GT(e_fast, 0.0);
    EXPECT_NEAR(generic.bondEnergy(laws, x), e_fast, 1e-12 * e_fast);
    return f_fast;
  };
  const std::vector<double> before = compare("as loaded");
  // Every free parameter moved: both paths read the new values.
  const std::vector<mme::ParamRef> refs = mme::freeParameters(m);
  for (const mme::ParamRef& r : refs)
    if (r.bond_type >= 0) laws.set(r, 1.5 * paramOf(m, r).value);
  const std::vector<double> after = compare("after set");
  EXPECT_NE(before, after);
}

}  // namespace

// The bond-kind catalogue: one entry per enumerator, in enum order, with the facts the rest of
// the package reads (names the model file uses, arities, parameter lists, what each kind may do).
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "motion_model_estimation/core/bond_kind.h"
#include "motion_model_estimation/core/model.h"

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

}  // namespace

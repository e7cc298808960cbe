#include "motion_model_estimation/core/bond_kind.h"

namespace mme {

namespace {

// The one place where each kind's facts are written down. The switch has no default, so a new
// enumerator without an entry is a compile error (-Werror=switch on the core); its force law is
// forces.cpp's bondLaw().
BondKindInfo makeInfo(BondKind kind) {
  switch (kind) {
    case BondKind::kSpring:
      return {kind, "spring", 2,
              {kStiffness, kRestLength, kDamping, kStiffnessNl, kDampingNl, kMinDistance,
               kMaxDistance, kMaxElongation},
              /*has_elongation=*/true, /*interactions=*/true, /*network=*/false,
              /*linear_form=*/LinearForm::kPair, /*candidate_prefix=*/"s"};
    case BondKind::kFlexion:
      return {kind, "flexion", 3, {kStiffness, kRestAngle, kDamping}, false, false, false,
              LinearForm::kAngle, "f"};
    case BondKind::kViscosity:
      return {kind, "viscosity", 1, {kViscosity}, false, false, false, LinearForm::kDrag, "v"};
    case BondKind::kMuscle:  // its activation is a network of other bonds' motion
      return {kind, "muscle", 2, {kStiffness, kRestLength, kDamping, kGain, kActivationTime},
              true, false, true, LinearForm::kNone, nullptr};
    case BondKind::kFloor:  // a conditional bond to the floor plane: ground contact
      return {kind, "floor", 1, {kStiffness, kDamping, kFriction, kHeight, kContactDepth},
              false, false, false, LinearForm::kNone, nullptr};
  }
  // not reached: every enumerator is listed
  return {kind, "?", 0, {}, false, false, false, LinearForm::kNone, nullptr};
}

struct Catalogue {
  std::vector<BondKind> kinds{BondKind::kSpring, BondKind::kFlexion, BondKind::kViscosity,
                              BondKind::kMuscle, BondKind::kFloor};
  std::vector<BondKindInfo> infos;
  Catalogue() {
    for (BondKind k : kinds) infos.push_back(makeInfo(k));
  }
};

const Catalogue& catalogue() {
  static const Catalogue kCatalogue;
  return kCatalogue;
}

}  // namespace

const char* paramKey(ParamId id) {
  switch (id) {
    case kStiffness: return "stiffness";
    case kRestLength: return "rest_length";
    case kDamping: return "damping";
    case kStiffnessNl: return "stiffness_nl";
    case kDampingNl: return "damping_nl";
    case kMinDistance: return "min_distance";
    case kMaxDistance: return "max_distance";
    case kMaxElongation: return "max_elongation";
    case kRestAngle: return "rest_angle";
    case kViscosity: return "viscosity";
    case kGain: return "gain";
    case kFriction: return "friction";
    case kHeight: return "height";
    case kContactDepth: return "contact_depth";
    case kActivationTime: return "activation_time_constant";
    case kParamCount: break;
  }
  return "?";
}

namespace {

// Each parameter kind's facts, written down once; the switch has no default (-Werror=switch).
ParamInfo makeParamInfo(ParamId id) {
  constexpr double kNoBound = 1e300;  // SpringLaw::max_distance's "no upper condition"
  //                     unit           log    positive length absent
  switch (id) {
    case kStiffness: return {id, paramKey(id), "N/m", true, true, false, 0.0};
    case kRestLength: return {id, paramKey(id), "m", true, true, true, 0.0};
    case kDamping: return {id, paramKey(id), "N s/m", true, true, false, 0.0};
    case kStiffnessNl: return {id, paramKey(id), "N/m^3", true, false, false, 0.0};
    case kDampingNl: return {id, paramKey(id), "N s^2/m^2", true, true, false, 0.0};
    case kMinDistance: return {id, paramKey(id), "m", true, true, true, 0.0};
    case kMaxDistance: return {id, paramKey(id), "m", true, true, true, kNoBound};
    case kMaxElongation: return {id, paramKey(id), "1", true, true, false, 0.0};
    case kRestAngle: return {id, paramKey(id), "rad", false, false, false, 0.0};
    case kViscosity: return {id, paramKey(id), "N s/m", true, true, false, 0.0};
    case kGain: return {id, paramKey(id), "N", true, true, false, 0.0};
    case kFriction: return {id, paramKey(id), "N s/m", true, true, false, 0.0};
    case kHeight: return {id, paramKey(id), "m", false, false, false, 0.0};
    case kContactDepth: return {id, paramKey(id), "m", true, true, false, 0.0};
    case kActivationTime: return {id, paramKey(id), "s", true, true, false, 0.0};
    case kParamCount: break;
  }
  return {id, "?", "", false, false, false, 0.0};  // not reached for a valid id
}

struct ParamCatalogue {
  std::vector<ParamInfo> infos;
  ParamCatalogue() {
    for (int id = 0; id < kParamCount; ++id) infos.push_back(makeParamInfo(static_cast<ParamId>(id)));
  }
};

}  // namespace

const ParamInfo& paramInfo(ParamId id) {
  static const ParamCatalogue kCatalogue;
  return kCatalogue.infos.at(static_cast<size_t>(id));
}

const BondKindInfo& bondKindInfo(BondKind kind) {
  return catalogue().infos.at(static_cast<size_t>(kind));
}

const BondKindInfo* bondKindByName(const std::string& name) {
  for (const BondKindInfo& info : catalogue().infos)
    if (name == info.name) return &info;
  return nullptr;
}

const std::vector<BondKind>& allBondKinds() { return catalogue().kinds; }

std::string bondKindNameList() {
  std::string out;
  const std::vector<BondKindInfo>& infos = catalogue().infos;
  for (size_t k = 0; k < infos.size(); ++k) {
    if (k > 0) out += k + 1 == infos.size() ? " or " : ", ";
    out += infos[k].name;
  }
  return out;
}

}  // namespace mme

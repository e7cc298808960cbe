#include "motion_model_estimation/core/bond_kind.h"

namespace mme {

namespace {

// The one place where each kind's facts are written down. The switch has no default, so a new
// enumerator without an entry is a compile error (-Werror=switch on the core).
BondKindInfo makeInfo(BondKind kind) {
  switch (kind) {
    case BondKind::kSpring:
      return {kind, "spring", 2,
              {kStiffness, kRestLength, kDamping, kStiffnessNl, kDampingNl, kMinDistance,
               kMaxDistance, kMaxElongation},
              /*has_elongation=*/true, /*interactions=*/true, /*network=*/false};
    case BondKind::kFlexion:
      return {kind, "flexion", 3, {kStiffness, kRestAngle, kDamping}, false, false, false};
    case BondKind::kViscosity:
      return {kind, "viscosity", 1, {kViscosity}, false, false, false};
    case BondKind::kMuscle:
      return {kind, "muscle", 2, {kStiffness, kRestLength, kDamping, kGain, kActivationTime},
              true, false, true};
    case BondKind::kFloor:  // a conditional bond to the floor plane: ground contact
      return {kind, "floor", 1, {kStiffness, kDamping, kFriction, kHeight, kContactDepth},
              false, false, false};
  }
  return {kind, "?", 0, {}, false, false, false};  // not reached: every enumerator is listed
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
  //                     unit           log    positive length
  switch (id) {
    case kStiffness: return {id, paramKey(id), "N/m", true, true, false};
    case kRestLength: return {id, paramKey(id), "m", true, true, true};
    case kDamping: return {id, paramKey(id), "N s/m", true, true, false};
    case kStiffnessNl: return {id, paramKey(id), "N/m^3", true, false, false};
    case kDampingNl: return {id, paramKey(id), "N s^2/m^2", true, true, false};
    case kMinDistance: return {id, paramKey(id), "m", true, true, true};
    case kMaxDistance: return {id, paramKey(id), "m", true, true, true};
    case kMaxElongation: return {id, paramKey(id), "1", true, true, false};
    case kRestAngle: return {id, paramKey(id), "rad", false, false, false};
    case kViscosity: return {id, paramKey(id), "N s/m", true, true, false};
    case kGain: return {id, paramKey(id), "N", true, true, false};
    case kFriction: return {id, paramKey(id), "N s/m", true, true, false};
    case kHeight: return {id, paramKey(id), "m", false, false, false};
    case kContactDepth: return {id, paramKey(id), "m", true, true, false};
    case kActivationTime: return {id, paramKey(id), "s", true, true, false};
    case kParamCount: break;
  }
  return {id, "?", "", false, false, false};  // not reached for a valid id
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

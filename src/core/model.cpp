#include "motion_model_estimation/core/model.h"

#include <cmath>
#include <sstream>

#include "motion_model_estimation/core/muscle.h"

namespace mme {

const std::vector<ParamId>& paramsOfKind(BondKind kind) { return bondKindInfo(kind).params; }

const char* kindName(BondKind kind) { return bondKindInfo(kind).name; }

int kindArity(BondKind kind) { return bondKindInfo(kind).arity; }

int Model::particleIndex(const std::string& name) const {
  for (size_t i = 0; i < particles.size(); ++i)
    if (particles[i].name == name) return static_cast<int>(i);
  return -1;
}

int Model::bondTypeIndex(const std::string& name) const {
  for (size_t i = 0; i < bond_types.size(); ++i)
    if (bond_types[i].name == name) return static_cast<int>(i);
  return -1;
}

int Model::bondIndex(const std::string& name) const {
  if (name.empty()) return -1;
  for (size_t i = 0; i < bonds.size(); ++i)
    if (bonds[i].name == name) return static_cast<int>(i);
  return -1;
}

Eigen::Vector3d Model::gravity() const {
  Eigen::Vector3d g;
  for (int k = 0; k < 3; ++k) g[k] = gravity_mps2[k].present ? gravity_mps2[k].value : 0.0;
  return g;
}

namespace {
const char* kAxis[3] = {"x", "y", "z"};

std::vector<ParamRef> collect(const Model& model, bool free_only) {
  std::vector<ParamRef> refs;
  for (size_t t = 0; t < model.bond_types.size(); ++t) {
    const BondType& type = model.bond_types[t];
    for (ParamId id : paramsOfKind(type.kind)) {
      const Param& p = type.params[id];
      if (!p.present || (free_only && !p.free)) continue;
      refs.push_back({type.name + "/" + paramKey(id), static_cast<int>(t), id});
    }
    for (size_t k = 0; k < type.network.size(); ++k) {
      const Param& p = type.network[k];
      if (!p.present || (free_only && !p.free)) continue;
      refs.push_back({type.name + "/" +
                          muscleNetworkKey(type.network_inputs, type.network_hidden,
                                           static_cast<int>(k)),
                      static_cast<int>(t), kParamCount + static_cast<int>(k)});
    }
  }
  for (int k = 0; k < 3; ++k) {
    const Param& p = model.gravity_mps2[k];
    if (!p.present || (free_only && !p.free)) continue;
    refs.push_back({std::string("gravity/") + kAxis[k], -1, k});
  }
  return refs;
}
}  // namespace

std::vector<ParamRef> freeParameters(const Model& model) { return collect(model, true); }
std::vector<ParamRef> presentParameters(const Model& model) { return collect(model, false); }

Param& paramOf(Model& model, const ParamRef& ref) {
  if (ref.bond_type < 0) return model.gravity_mps2[ref.param];
  BondType& type = model.bond_types[ref.bond_type];
  return ref.isNetwork() ? type.network[ref.param - kParamCount] : type.params[ref.param];
}

const Param& paramOf(const Model& model, const ParamRef& ref) {
  if (ref.bond_type < 0) return model.gravity_mps2[ref.param];
  const BondType& type = model.bond_types[ref.bond_type];
  return ref.isNetwork() ? type.network[ref.param - kParamCount] : type.params[ref.param];
}

double getParam(const Model& model, const ParamRef& ref) { return paramOf(model, ref).value; }

void setParam(Model& model, const ParamRef& ref, double value) {
  Param& p = paramOf(model, ref);
  p.value = value;
  p.has_value = true;
  p.present = true;
}

std::vector<double> getValues(const Model& model, const std::vector<ParamRef>& refs) {
  std::vector<double> values;
  values.reserve(refs.size());
  for (const ParamRef& r : refs) values.push_back(getParam(model, r));
  return values;
}

void setValues(Model& model, const std::vector<ParamRef>& refs, const std::vector<double>& values) {
  for (size_t i = 0; i < refs.size() && i < values.size(); ++i) setParam(model, refs[i], values[i]);
}

namespace {

// validateModel's steps, one per part of the model, in the order the model is checked. Each
// returns the first problem found ("" when none).

std::string checkSettings(const Model& model) {
  if (model.substeps < 1) return "substeps must be >= 1";
  if (!(model.frame_rate_hz >= 0.0) || !std::isfinite(model.frame_rate_hz))
    return "frame_rate_hz must be >= 0";
  return "";
}

std::string checkParticles(const Model& model) {
  std::ostringstream err;
  const int n = static_cast<int>(model.particles.size());
  for (int i = 0; i < n; ++i) {
    const Particle& p = model.particles[i];
    if (!(p.mass_kg > 0.0) || !std::isfinite(p.mass_kg)) {
      err << "particle '" << p.name << "': mass must be > 0";
      return err.str();
    }
    if (!p.position_m.allFinite() || !p.velocity_mps.allFinite()) {
      err << "particle '" << p.name << "': position and velocity must be finite";
      return err.str();
    }
    for (int j = 0; j < i; ++j)
      if (model.particles[j].name == p.name) return "duplicate particle name '" + p.name + "'";
  }
  return "";
}

/// Each bond's type and particles (indices in range, no particle joined to itself).
std::string checkBondParticles(const Model& model) {
  std::ostringstream err;
  const int n = static_cast<int>(model.particles.size());
  for (size_t b = 0; b < model.bonds.size(); ++b) {
    const Bond& bond = model.bonds[b];
    if (bond.type < 0 || bond.type >= static_cast<int>(model.bond_types.size())) {
      err << "bond " << b << ": unknown bond type";
      return err.str();
    }
    const int arity = kindArity(model.bond_types[bond.type].kind);
    for (int k = 0; k < arity; ++k) {
      if (bond.particles[k] < 0 || bond.particles[k] >= n) {
        err << "bond " << b << ": particle index out of range";
        return err.str();
      }
      for (int l = 0; l < k; ++l)
        if (bond.particles[l] == bond.particles[k]) {
          err << "bond " << b << ": joins particle '" << model.particles[bond.particles[k]].name
              << "' to itself";
          return err.str();
        }
    }
  }
  return "";
}

/// A muscle bond's inputs: as many as its network reads, each another named bond with an
/// elongation.
std::string checkMuscleInputs(const Model& model, size_t b, const std::string& bond_name) {
  const Bond& bond = model.bonds[b];
  const BondType& type = model.bond_types[bond.type];
  if (static_cast<int>(bond.inputs.size()) != type.network_inputs)
    return bond_name + ": muscle type '" + type.name + "' reads " +
           std::to_string(type.network_inputs) + " input bond(s), the bond names " +
           std::to_string(bond.inputs.size());
  for (int in : bond.inputs) {
    if (in < 0 || in >= static_cast<int>(model.bonds.size()))
      return bond_name + ": input bond index out of range";
    if (in == static_cast<int>(b)) return bond_name + ": a muscle cannot read its own bond";
    const BondType& in_type = model.bond_types[model.bonds[in].type];
    if (!bondKindInfo(in_type.kind).has_elongation)
      return bond_name + ": input bond " + std::to_string(in) + " is a " +
             kindName(in_type.kind) + " (inputs must be springs or muscles: bonds with an elongation)";
    if (model.bonds[in].name.empty())
      return bond_name + ": input bond " + std::to_string(in) + " has no name";
  }
  return "";
}

/// Bond names unique; only muscles have inputs, and theirs are consistent.
std::string checkBondNamesAndInputs(const Model& model) {
  for (size_t b = 0; b < model.bonds.size(); ++b) {
    const Bond& bond = model.bonds[b];
    const std::string bond_name =
        bond.name.empty() ? "bond " + std::to_string(b) : "bond '" + bond.name + "'";
    if (!bond.name.empty())
      for (size_t c = 0; c < b; ++c)
        if (model.bonds[c].name == bond.name) return "duplicate bond name '" + bond.name + "'";
    const BondType& type = model.bond_types[bond.type];
    if (!bondKindInfo(type.kind).network) {
      if (!bond.inputs.empty())
        return bond_name + ": only muscle bonds have inputs (type '" + type.name + "' is a " +
               kindName(type.kind) + ")";
      continue;
    }
    const std::string reason = checkMuscleInputs(model, b, bond_name);
    if (!reason.empty()) return reason;
  }
  return "";
}

std::string checkInteractions(const Model& model) {
  for (size_t t = 0; t < model.interactions.size(); ++t) {
    const Interaction& in = model.interactions[t];
    if (in.type < 0 || in.type >= static_cast<int>(model.bond_types.size()))
      return "interaction: unknown bond type";
    const BondType& type = model.bond_types[in.type];
    if (!bondKindInfo(type.kind).interactions)
      return "interaction type '" + type.name + "' must be a spring";
    if (!type.param(kMaxDistance).present)
      return "interaction type '" + type.name + "' needs max_distance";
  }
  return "";
}

/// One present parameter `key` of `type`: finite value, min <= max, a value when fixed.
std::string checkParam(const BondType& type, const Param& p, const std::string& key) {
  if (!p.present) return "";
  if (p.has_value && !std::isfinite(p.value))
    return "bond type '" + type.name + "': " + key + " must be finite";
  if (p.has_min && p.has_max && p.min > p.max)
    return "bond type '" + type.name + "': " + key + " has min > max";
  if (!p.free && !p.has_value)
    return "bond type '" + type.name + "': " + key + " is fixed but has no value";
  return "";
}

/// A muscle type's network: layout in range, as many weights as it needs, each valid.
std::string checkNetwork(const BondType& type) {
  if (type.network_inputs < 0 || type.network_inputs > kMaxMuscleInputs)
    return "bond type '" + type.name + "': inputs must be in [0, " +
           std::to_string(kMaxMuscleInputs) + "]";
  if (type.network_hidden < 0 || type.network_hidden > kMaxMuscleHidden)
    return "bond type '" + type.name + "': hidden must be in [0, " +
           std::to_string(kMaxMuscleHidden) + "]";
  if (static_cast<int>(type.network.size()) !=
      muscleNetworkSize(type.network_inputs, type.network_hidden))
    return "bond type '" + type.name + "': the network has " +
           std::to_string(type.network.size()) + " parameters, its layout needs " +
           std::to_string(muscleNetworkSize(type.network_inputs, type.network_hidden));
  for (size_t k = 0; k < type.network.size(); ++k) {
    const std::string reason = checkParam(
        type, type.network[k],
        muscleNetworkKey(type.network_inputs, type.network_hidden, static_cast<int>(k)));
    if (!reason.empty()) return reason;
  }
  return "";
}

std::string checkBondType(const BondType& type) {
  for (ParamId id : paramsOfKind(type.kind)) {
    const std::string reason = checkParam(type, type.params[id], paramKey(id));
    if (!reason.empty()) return reason;
  }
  const Param& depth = type.params[kContactDepth];
  if (depth.present && depth.has_value && depth.value < 0.0)
    return "bond type '" + type.name + "': contact_depth must be >= 0 [m] (0: none)";
  const Param& tau = type.params[kActivationTime];
  if (tau.present && tau.has_value && tau.value < 0.0)
    return "bond type '" + type.name + "': activation_time_constant must be >= 0 [s] (0: none)";
  if (!bondKindInfo(type.kind).network) {
    if (!type.network.empty() || type.network_inputs != 0 || type.network_hidden != 0)
      return "bond type '" + type.name + "': only muscles have a network";
    return "";
  }
  return checkNetwork(type);
}

}  // namespace

std::string validateModel(const Model& model) {
  for (auto check : {checkSettings, checkParticles, checkBondParticles, checkBondNamesAndInputs,
                     checkInteractions}) {
    const std::string reason = check(model);
    if (!reason.empty()) return reason;
  }
  for (const BondType& type : model.bond_types) {
    const std::string reason = checkBondType(type);
    if (!reason.empty()) return reason;
  }
  return "";
}

}  // namespace mme

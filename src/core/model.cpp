#include "motion_model_estimation/core/model.h"

#include <cmath>
#include <sstream>

namespace mme {

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
    default: return "?";
  }
}

const std::vector<ParamId>& paramsOfKind(BondKind kind) {
  static const std::vector<ParamId> kSpringParams = {
      kStiffness, kRestLength, kDamping, kStiffnessNl, kDampingNl,
      kMinDistance, kMaxDistance, kMaxElongation};
  static const std::vector<ParamId> kFlexionParams = {kStiffness, kRestAngle, kDamping};
  static const std::vector<ParamId> kViscosityParams = {kViscosity};
  switch (kind) {
    case BondKind::kSpring: return kSpringParams;
    case BondKind::kFlexion: return kFlexionParams;
    default: return kViscosityParams;
  }
}

const char* kindName(BondKind kind) {
  switch (kind) {
    case BondKind::kSpring: return "spring";
    case BondKind::kFlexion: return "flexion";
    default: return "viscosity";
  }
}

int kindArity(BondKind kind) {
  switch (kind) {
    case BondKind::kSpring: return 2;
    case BondKind::kFlexion: return 3;
    default: return 1;
  }
}

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
  return ref.bond_type < 0 ? model.gravity_mps2[ref.param]
                           : model.bond_types[ref.bond_type].params[ref.param];
}

const Param& paramOf(const Model& model, const ParamRef& ref) {
  return ref.bond_type < 0 ? model.gravity_mps2[ref.param]
                           : model.bond_types[ref.bond_type].params[ref.param];
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

std::string validateModel(const Model& model) {
  std::ostringstream err;
  if (model.substeps < 1) return "substeps must be >= 1";
  if (!(model.frame_rate_hz >= 0.0) || !std::isfinite(model.frame_rate_hz))
    return "frame_rate_hz must be >= 0";
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
  for (size_t t = 0; t < model.interactions.size(); ++t) {
    const Interaction& in = model.interactions[t];
    if (in.type < 0 || in.type >= static_cast<int>(model.bond_types.size()))
      return "interaction: unknown bond type";
    const BondType& type = model.bond_types[in.type];
    if (type.kind != BondKind::kSpring)
      return "interaction type '" + type.name + "' must be a spring";
    if (!type.param(kMaxDistance).present)
      return "interaction type '" + type.name + "' needs max_distance";
  }
  for (const BondType& type : model.bond_types) {
    for (ParamId id : paramsOfKind(type.kind)) {
      const Param& p = type.params[id];
      if (!p.present) continue;
      if (p.has_value && !std::isfinite(p.value))
        return "bond type '" + type.name + "': " + paramKey(id) + " must be finite";
      if (p.has_min && p.has_max && p.min > p.max)
        return "bond type '" + type.name + "': " + paramKey(id) + " has min > max";
      if (!p.free && !p.has_value)
        return "bond type '" + type.name + "': " + paramKey(id) + " is fixed but has no value";
    }
  }
  return "";
}

}  // namespace mme

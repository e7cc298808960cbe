// modelToYaml: the YAML text of a model (SPEC section 2) and of an export (SPEC section 4),
// one section at a time in the order a model file lists them (settings and gravity, particles,
// bond types, bonds, interactions), then with identification results the `std:` of each
// listed parameter and the `identification:` block. The values themselves are written by
// model_yaml_emit.cpp so that the text loads back to the same model.

#include <algorithm>
#include <cmath>
#include <map>

#include "model_yaml_emit.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"
#include "motion_model_estimation/io/model_yaml.h"

namespace mme {

namespace model_yaml {

namespace {

/// Parameter name ("s01/stiffness") -> its std, for the finite stds of `info`.
using StdMap = std::map<std::string, double>;

StdMap stdsOf(const IdentificationInfo* info) {
  StdMap stds;
  if (info) {
    const std::size_t n = std::min(info->std_names.size(), info->std_values.size());
    for (std::size_t i = 0; i < n; ++i)
      if (std::isfinite(info->std_values[i])) stds[info->std_names[i]] = info->std_values[i];
  }
  return stds;
}

const double* stdOf(const StdMap& stds, const std::string& name) {
  auto it = stds.find(name);
  return it == stds.end() ? nullptr : &it->second;
}

/// Empty lists are written as [] on the key's line (block style would put it on the next).
void beginList(YAML::Emitter& out, const char* key, bool empty) {
  out << YAML::Key << key << YAML::Value;
  if (empty) out << YAML::Flow;
  out << YAML::BeginSeq;
}

/// frame_id, frame_rate_hz, substeps and (when present) gravity.
void writeSettings(YAML::Emitter& out, const Model& model, const StdMap& stds) {
  out << YAML::Key << "frame_id" << YAML::Value;
  emitName(out, model.frame_id);
  out << YAML::Key << "frame_rate_hz" << YAML::Value;
  emitNumber(out, model.frame_rate_hz);
  out << YAML::Key << "substeps" << YAML::Value << model.substeps;
  const auto& g = model.gravity_mps2;
  if (g[0].present || g[1].present || g[2].present) {
    out << YAML::Key << "gravity" << YAML::Value;
    emitGravity(out, g, stds);
  }
}

void writeParticles(YAML::Emitter& out, const Model& model) {
  beginList(out, "particles", model.particles.empty());
  for (const Particle& p : model.particles) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value;
    emitName(out, p.name);
    out << YAML::Key << "mass" << YAML::Value;
    emitNumber(out, p.mass_kg);
    out << YAML::Key << "position" << YAML::Value;
    emitVector(out, p.position_m);
    out << YAML::Key << "velocity" << YAML::Value;
    emitVector(out, p.velocity_mps);
    out << YAML::Key << "fixed" << YAML::Value << p.fixed;
    out << YAML::Key << "group" << YAML::Value;
    emitName(out, p.group);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

/// A muscle type's layout (inputs, hidden) and its network's present weights.
void writeNetwork(YAML::Emitter& out, const BondType& t, const StdMap& stds) {
  out << YAML::Key << "inputs" << YAML::Value << t.network_inputs;
  out << YAML::Key << "hidden" << YAML::Value << t.network_hidden;
  for (std::size_t k = 0; k < t.network.size(); ++k) {
    const Param& p = t.network[k];
    if (!p.present) continue;
    const std::string key =
        muscleNetworkKey(t.network_inputs, t.network_hidden, static_cast<int>(k));
    out << YAML::Key << key << YAML::Value;
    emitParam(out, p, stdOf(stds, t.name + "/" + key));
  }
}

void writeBondTypes(YAML::Emitter& out, const Model& model, const StdMap& stds) {
  beginList(out, "bond_types", model.bond_types.empty());
  for (const BondType& t : model.bond_types) {
    out << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value;
    emitName(out, t.name);
    out << YAML::Key << "kind" << YAML::Value << kindName(t.kind);
    for (ParamId id : paramsOfKind(t.kind)) {
      const Param& p = t.params[id];
      if (!p.present) continue;
      out << YAML::Key << paramKey(id) << YAML::Value;
      emitParam(out, p, stdOf(stds, t.name + "/" + paramKey(id)));
    }
    if (bondKindInfo(t.kind).network) writeNetwork(out, t, stds);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

void writeBonds(YAML::Emitter& out, const Model& model) {
  beginList(out, "bonds", model.bonds.empty());
  for (const Bond& b : model.bonds) {
    const BondType& t = model.bond_types[b.type];
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "type" << YAML::Value;
    emitName(out, t.name);
    out << YAML::Key << "particles" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int k = 0; k < kindArity(t.kind); ++k) emitName(out, model.particles[b.particles[k]].name);
    out << YAML::EndSeq;
    if (!b.name.empty()) {
      out << YAML::Key << "name" << YAML::Value;
      emitName(out, b.name);
    }
    if (bondKindInfo(t.kind).network) {
      out << YAML::Key << "inputs" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (int in : b.inputs) emitName(out, model.bonds[in].name);
      out << YAML::EndSeq;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

void writeInteractions(YAML::Emitter& out, const Model& model) {
  beginList(out, "interactions", model.interactions.empty());
  for (const Interaction& in : model.interactions) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "type" << YAML::Value;
    emitName(out, model.bond_types[in.type].name);
    out << YAML::Key << "groups" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    emitName(out, in.group_a);
    emitName(out, in.group_b);
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

/// The `identification:` block of an export: how the values were found, and the flags and
/// notes on what the data left undecided.
void writeIdentification(YAML::Emitter& out, const IdentificationInfo& info) {
  out << YAML::Key << "identification" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "method" << YAML::Value;
  emitName(out, info.method);
  if (!info.model_kind.empty()) {
    out << YAML::Key << "model_kind" << YAML::Value;
    emitName(out, info.model_kind);
  }
  out << YAML::Key << "global_cost" << YAML::Value;
  emitNumber(out, info.global_cost);
  out << YAML::Key << "frames" << YAML::Value << info.frames;
  out << YAML::Key << "generations" << YAML::Value << info.generations;
  out << YAML::Key << "wall_time_s" << YAML::Value;
  emitNumber(out, info.wall_time_s);
  if (!info.flags.empty()) {
    out << YAML::Key << "flags" << YAML::Value << YAML::BeginMap;
    for (const auto& [name, flag] : info.flags) {
      out << YAML::Key;
      emitName(out, name);
      out << YAML::Value;
      emitName(out, flag);
    }
    out << YAML::EndMap;
  }
  if (!info.notes.empty()) {
    out << YAML::Key << "notes" << YAML::Value << YAML::BeginSeq;
    for (const std::string& text : info.notes) out << YAML::DoubleQuoted << text;
    out << YAML::EndSeq;
  }
  out << YAML::EndMap;
}

}  // namespace

}  // namespace model_yaml

std::string modelToYaml(const Model& model, const IdentificationInfo* info) {
  using namespace model_yaml;
  // Writing an inconsistent model would produce a file that cannot be loaded back, and bad
  // indices would be read out of range below.
  const std::string reason = validateModel(model);
  if (!reason.empty()) throw InputError("cannot export an invalid model: " + reason);

  const StdMap stds = stdsOf(info);
  YAML::Emitter out;
  out << YAML::BeginMap;
  writeSettings(out, model, stds);
  writeParticles(out, model);
  writeBondTypes(out, model, stds);
  writeBonds(out, model);
  writeInteractions(out, model);
  if (info) writeIdentification(out, *info);
  out << YAML::EndMap;
  if (!out.good()) throw InputError("cannot export the model: " + out.GetLastError());
  return std::string(out.c_str()) + "\n";
}

}  // namespace mme

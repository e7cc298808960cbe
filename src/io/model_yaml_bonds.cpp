// The `bonds:` list of a model document: each bond's type, the particles it joins, its
// optional name and, for a muscle, the bonds it reads (`inputs:`). Inputs may name bonds that
// come later in the list, so they are collected here and resolved once every bond is read
// (model_yaml_muscle_inputs.cpp).

#include <map>

#include "model_yaml_values.h"

namespace mme {
namespace model_yaml {

namespace {

/// The keys of one bond entry (null when absent).
struct BondKeys {
  const Entry* type = nullptr;
  const Entry* particles = nullptr;
  const Entry* name = nullptr;
  const Entry* inputs = nullptr;
};

BondKeys findBondKeys(const ValueReader& r, const std::vector<Entry>& es,
                      const std::string& where) {
  BondKeys keys;
  for (const Entry& e : es) {
    if (e.key == "type") {
      keys.type = &e;
    } else if (e.key == "particles") {
      keys.particles = &e;
    } else if (e.key == "name") {
      keys.name = &e;
    } else if (e.key == "inputs") {
      keys.inputs = &e;
    } else {
      r.fail(lineOf(e.key_node), e.key,
             "unknown key" + where + " (allowed: type, particles, name, inputs)");
    }
  }
  return keys;
}

/// Index of the bond's type (required, must exist).
int readBondType(const ValueReader& r, const YAML::Node& item, const Entry* type_e,
                 const std::string& where, const Model& model) {
  if (!type_e) r.fail(lineOf(item), "type", "bond type missing" + where);
  const std::string type_name = r.asString(*type_e, "type", where);
  const int type = model.bondTypeIndex(type_name);
  if (type < 0)
    r.fail(type_e->valueLine(), "type", "unknown bond type '" + type_name + "'" + where);
  return type;
}

/// The particles the bond joins: as many distinct known particles as its kind's arity.
void readBondParticles(const ValueReader& r, const YAML::Node& item, const Entry* parts_e,
                       const std::string& where, const Model& model, Bond& bond) {
  const BondType& type = model.bond_types[bond.type];
  if (!parts_e) r.fail(lineOf(item), "particles", "bond particles missing" + where);
  const YAML::Node& names = parts_e->value;
  const int arity = kindArity(type.kind);
  if (!names.IsSequence())
    r.fail(parts_e->valueLine(), "particles", "expected a list of particle names" + where);
  if (static_cast<int>(names.size()) != arity)
    r.fail(parts_e->valueLine(), "particles",
           std::string("a ") + kindName(type.kind) + " bond (type '" + type.name + "') joins " +
               std::to_string(arity) + " particle" + (arity == 1 ? "" : "s") + ", got " +
               std::to_string(names.size()) + where);
  for (int k = 0; k < arity; ++k) {
    const YAML::Node n = names[k];
    if (!n.IsScalar()) r.fail(lineOf(n), "particles", "expected a particle name" + where);
    const int idx = model.particleIndex(n.Scalar());
    if (idx < 0) r.fail(lineOf(n), "particles", "unknown particle '" + n.Scalar() + "'" + where);
    for (int l = 0; l < k; ++l)
      if (bond.particles[l] == idx)
        r.fail(lineOf(n), "particles",
               "bond joins particle '" + n.Scalar() + "' to itself" + where);
    bond.particles[k] = idx;
  }
}

/// The bond's optional name (unique among bonds: muscles' inputs refer to it).
void readBondName(const ValueReader& r, const Entry* name_e, const std::string& where,
                  std::map<std::string, int>& name_line, Bond& bond) {
  if (!name_e) return;
  bond.name = r.asString(*name_e, "name", where);
  if (bond.name.empty()) r.fail(name_e->valueLine(), "name", "must not be empty" + where);
  auto [pos, inserted] = name_line.emplace(bond.name, name_e->valueLine());
  if (!inserted)
    r.fail(name_e->valueLine(), "name",
           "duplicate bond name '" + bond.name + "' (first at line " +
               std::to_string(pos->second) + ")" + where);
}

/// Checks that only muscles have `inputs:` and that a muscle reading bonds has them; a
/// muscle's entry is queued in `pending` for resolution.
void checkBondInputs(const ValueReader& r, const YAML::Node& item, const Entry* inputs_e,
                     const std::string& where, const Model& model, const Bond& bond,
                     std::vector<PendingInputs>& pending) {
  const BondType& type = model.bond_types[bond.type];
  if (bondKindInfo(type.kind).network) {
    if (inputs_e)
      pending.push_back({model.bonds.size(), inputs_e, where});
    else if (type.network_inputs > 0)  // a muscle reading nothing may leave the key out
      r.fail(lineOf(item), "inputs",
             "a muscle bond (type '" + type.name + "') names its " +
                 std::to_string(type.network_inputs) + " input bond(s): inputs: [bond names]" +
                 where);
  } else if (inputs_e) {
    r.fail(lineOf(inputs_e->key_node), "inputs",
           std::string("only muscle bonds have inputs (type '") + type.name + "' is a " +
               kindName(type.kind) + ")" + where);
  }
}

}  // namespace

void readBonds(const ValueReader& r, const Entry& list, Model& model) {
  const YAML::Node& seq = r.sequence(list);
  // Kept until the end: `pending` points into it.
  std::vector<std::vector<Entry>> all_entries(seq.size());
  std::vector<PendingInputs> pending;
  std::map<std::string, int> name_line;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const YAML::Node item = seq[i];
    const std::string where = " in bonds[" + std::to_string(i) + "]";
    if (!item.IsMap())
      r.fail(lineOf(item), "bonds", "each bond must be a map {type, particles}" + where);
    all_entries[i] = r.entries(item, "bonds", where);
    const BondKeys keys = findBondKeys(r, all_entries[i], where);
    Bond bond;
    bond.type = readBondType(r, item, keys.type, where, model);
    readBondParticles(r, item, keys.particles, where, model, bond);
    readBondName(r, keys.name, where, name_line, bond);
    checkBondInputs(r, item, keys.inputs, where, model, bond, pending);
    model.bonds.push_back(bond);
  }
  resolveMuscleInputs(r, pending, model);
}

}  // namespace model_yaml
}  // namespace mme

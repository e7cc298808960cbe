// The `bond_types:` list of a model document: each type's name, kind and the parameters its
// kind allows (stiffness, damping, ...); for a muscle also its network layout (inputs, hidden)
// and the network's weights, whose keys depend on that layout.

#include <map>

#include "model_yaml_values.h"
#include "motion_model_estimation/core/muscle.h"

namespace mme {
namespace model_yaml {

namespace {

/// The type's name entry and kind entry (either may be missing: null).
struct NameAndKind {
  const Entry* name = nullptr;
  const Entry* kind = nullptr;
};

NameAndKind findNameAndKind(const std::vector<Entry>& es) {
  NameAndKind found;
  for (const Entry& e : es) {
    if (e.key == "name") found.name = &e;
    if (e.key == "kind") found.kind = &e;
  }
  return found;
}

/// The type's name: required, unique, without '/'.
std::string readTypeName(const ValueReader& r, const YAML::Node& item, const Entry* name,
                         const std::string& where, std::map<std::string, int>& name_line) {
  if (!name) r.fail(lineOf(item), "name", "bond type has no name" + where);
  const std::string type_name = r.asString(*name, "name", where);
  if (type_name.empty()) r.fail(name->valueLine(), "name", "must not be empty" + where);
  // '/' separates type and parameter in parameter names ("s01/stiffness").
  if (type_name.find('/') != std::string::npos)
    r.fail(name->valueLine(), "name",
           "bond type names may not contain '/' (it separates type and parameter in "
           "parameter names)" + where);
  auto [pos, inserted] = name_line.emplace(type_name, name->valueLine());
  if (!inserted)
    r.fail(name->valueLine(), "name",
           "duplicate bond type name '" + type_name + "' (first at line " +
               std::to_string(pos->second) + ")" + where);
  return type_name;
}

/// The kind's facts (never null: an unknown kind is an error).
const BondKindInfo& readKind(const ValueReader& r, const YAML::Node& item, const Entry* kind,
                             const std::string& where) {
  if (!kind)
    r.fail(lineOf(item), "kind", "bond type has no kind (" + bondKindNameList() + ")" + where);
  const std::string k = r.asString(*kind, "kind", where);
  const BondKindInfo* info = bondKindByName(k);
  if (!info)
    r.fail(kind->valueLine(), "kind",
           "unknown kind '" + k + "' (expected " + bondKindNameList() + ")" + where);
  return *info;
}

/// A muscle's network layout (inputs, hidden): it decides which parameter keys exist.
void readNetworkLayout(const ValueReader& r, const std::vector<Entry>& es,
                       const std::string& where, BondType& type) {
  for (const Entry& e : es) {
    if (e.key == "inputs") type.network_inputs = r.asCount(e, kMaxMuscleInputs, where);
    if (e.key == "hidden") type.network_hidden = r.asCount(e, kMaxMuscleHidden, where);
  }
  type.network.assign(muscleNetworkSize(type.network_inputs, type.network_hidden), Param());
}

/// The reason for an unknown key: the keys the kind (and a muscle's layout) allows.
std::string unknownKeyReason(const BondKindInfo& info, const BondType& type,
                             const std::string& where) {
  std::string list_of;
  for (ParamId id : info.params)
    list_of += std::string(list_of.empty() ? "" : ", ") + paramKey(id);
  if (info.network)
    list_of += ", inputs, hidden, and the network's " +
               muscleNetworkLayout(type.network_inputs, type.network_hidden) + " (inputs " +
               std::to_string(type.network_inputs) + ", hidden " +
               std::to_string(type.network_hidden) + ")";
  return std::string("unknown key for a ") + info.name + where + " (allowed: name, kind, " +
         list_of + ")";
}

/// One parameter key of the type: a parameter of its kind or a network weight. False when
/// the key is neither.
bool readParamKey(const ValueReader& r, const Entry& e, const BondKindInfo& info,
                  const std::string& where, BondType& type) {
  bool found = false;
  for (ParamId id : info.params) {
    if (e.key != paramKey(id)) continue;
    type.params[id] = r.readParam(e, where);
    found = true;
  }
  if (!found && info.network) {
    const int index = muscleNetworkIndex(type.network_inputs, type.network_hidden, e.key);
    if (index >= 0) {
      type.network[index] = r.readParam(e, where);
      found = true;
    }
  }
  return found;
}

/// Every key but name and kind (and a muscle's inputs and hidden).
void readTypeParams(const ValueReader& r, const std::vector<Entry>& es,
                    const BondKindInfo& info, const std::string& where, BondType& type) {
  for (const Entry& e : es) {
    if (e.key == "name" || e.key == "kind") continue;
    if (info.network && (e.key == "inputs" || e.key == "hidden")) continue;
    if (!readParamKey(r, e, info, where, type))
      r.fail(lineOf(e.key_node), e.key, unknownKeyReason(info, type, where));
  }
}

}  // namespace

void readBondTypes(const ValueReader& r, const Entry& list, Model& model) {
  const YAML::Node& seq = r.sequence(list);
  std::map<std::string, int> name_line;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const YAML::Node item = seq[i];
    std::string where = " in bond_types[" + std::to_string(i) + "]";
    if (!item.IsMap())
      r.fail(lineOf(item), "bond_types", "each bond type must be a map {name, kind, ...}" + where);
    const std::vector<Entry> es = r.entries(item, "bond_types", where);
    const NameAndKind found = findNameAndKind(es);
    BondType type;
    type.name = readTypeName(r, item, found.name, where, name_line);
    where = " in bond type '" + type.name + "'";
    const BondKindInfo& info = readKind(r, item, found.kind, where);
    type.kind = info.kind;
    if (info.network) readNetworkLayout(r, es, where, type);
    readTypeParams(r, es, info, where, type);
    model.bond_types.push_back(std::move(type));
  }
}

}  // namespace model_yaml
}  // namespace mme

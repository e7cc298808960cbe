// The `interactions:` list of a model document: a spring type installed between nearby
// particles of two groups (e.g. contact between two objects). The type needs a range
// (max_distance), and each group must have at least one particle.

#include <set>

#include "model_yaml_values.h"

namespace mme {
namespace model_yaml {

namespace {

/// Index of the interaction's type: a spring with max_distance.
int readInteractionType(const ValueReader& r, const YAML::Node& item, const Entry* type_e,
                        const std::string& where, const Model& model) {
  if (!type_e) r.fail(lineOf(item), "type", "interaction type missing" + where);
  const std::string type_name = r.asString(*type_e, "type", where);
  const int index = model.bondTypeIndex(type_name);
  if (index < 0)
    r.fail(type_e->valueLine(), "type", "unknown bond type '" + type_name + "'" + where);
  const BondType& type = model.bond_types[index];
  // Interactions are installed between nearby particles, so they need a spring with a
  // range; without max_distance every pair in the groups would be bonded.
  if (!bondKindInfo(type.kind).interactions || !type.param(kMaxDistance).present)
    r.fail(type_e->valueLine(), "type",
           "interaction type '" + type.name + "' must be a spring with max_distance" + where);
  return index;
}

/// The two groups [a, b]; each must be some particle's group.
void readInteractionGroups(const ValueReader& r, const YAML::Node& item, const Entry* groups_e,
                           const std::string& where, const std::set<std::string>& groups,
                           Interaction& in) {
  if (!groups_e) r.fail(lineOf(item), "groups", "interaction groups missing" + where);
  const YAML::Node& g = groups_e->value;
  if (!g.IsSequence() || g.size() != 2)
    r.fail(groups_e->valueLine(), "groups", "expected two group names [a, b]" + where);
  for (int k = 0; k < 2; ++k) {
    if (!g[k].IsScalar()) r.fail(lineOf(g[k]), "groups", "expected a group name" + where);
    const std::string name = g[k].Scalar();
    if (!groups.count(name))
      r.fail(lineOf(g[k]), "groups", "no particle is in group '" + name + "'" + where);
    (k == 0 ? in.group_a : in.group_b) = name;
  }
}

}  // namespace

void readInteractions(const ValueReader& r, const Entry& list, Model& model) {
  const YAML::Node& seq = r.sequence(list);
  std::set<std::string> groups;
  for (const Particle& p : model.particles) groups.insert(p.group);
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const YAML::Node item = seq[i];
    const std::string where = " in interactions[" + std::to_string(i) + "]";
    if (!item.IsMap())
      r.fail(lineOf(item), "interactions", "each interaction must be a map {type, groups}" + where);
    const Entry* type_e = nullptr;
    const Entry* groups_e = nullptr;
    const std::vector<Entry> es = r.entries(item, "interactions", where);
    for (const Entry& e : es) {
      if (e.key == "type") {
        type_e = &e;
      } else if (e.key == "groups") {
        groups_e = &e;
      } else {
        r.fail(lineOf(e.key_node), e.key, "unknown key" + where + " (allowed: type, groups)");
      }
    }
    Interaction in;
    in.type = readInteractionType(r, item, type_e, where, model);
    readInteractionGroups(r, item, groups_e, where, groups, in);
    model.interactions.push_back(std::move(in));
  }
}

}  // namespace model_yaml
}  // namespace mme

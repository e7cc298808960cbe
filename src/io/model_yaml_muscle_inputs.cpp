// The `inputs:` of muscle bonds: the names of the bonds whose elongations a muscle's network
// reads. They are resolved after the whole `bonds:` list is read, since a muscle may read a
// bond defined after it; each name must be another bond with an elongation (a spring or a
// muscle), and a muscle reads exactly as many as its type's network has inputs.

#include "model_yaml_values.h"

namespace mme {
namespace model_yaml {

namespace {

/// Index of the input bond named by `n` for the muscle bond `muscle`.
int readInputBond(const ValueReader& r, const YAML::Node& n, std::size_t muscle,
                  const std::string& where, const Model& model) {
  if (!n.IsScalar()) r.fail(lineOf(n), "inputs", "expected a bond name" + where);
  const int idx = model.bondIndex(n.Scalar());
  if (idx < 0)
    r.fail(lineOf(n), "inputs",
           "unknown input bond '" + n.Scalar() + "' (no bond has that name)" + where);
  if (idx == static_cast<int>(muscle))
    r.fail(lineOf(n), "inputs", "a muscle cannot read its own bond" + where);
  const BondType& in_type = model.bond_types[model.bonds[idx].type];
  if (!bondKindInfo(in_type.kind).has_elongation)
    r.fail(lineOf(n), "inputs",
           "input bond '" + n.Scalar() + "' is a " + kindName(in_type.kind) +
               " (inputs must be springs or muscles: bonds with an elongation)" + where);
  return idx;
}

}  // namespace

void resolveMuscleInputs(const ValueReader& r, const std::vector<PendingInputs>& pending,
                         Model& model) {
  for (const PendingInputs& p : pending) {
    Bond& bond = model.bonds[p.bond];
    const BondType& type = model.bond_types[bond.type];
    const YAML::Node& names = p.entry->value;
    if (!names.IsSequence())
      r.fail(p.entry->valueLine(), "inputs", "expected a list of bond names" + p.where);
    if (static_cast<int>(names.size()) != type.network_inputs)
      r.fail(p.entry->valueLine(), "inputs",
             "muscle type '" + type.name + "' reads " + std::to_string(type.network_inputs) +
                 " input bond(s), got " + std::to_string(names.size()) + p.where);
    for (std::size_t k = 0; k < names.size(); ++k)
      bond.inputs.push_back(readInputBond(r, names[k], p.bond, p.where, model));
  }
}

}  // namespace model_yaml
}  // namespace mme

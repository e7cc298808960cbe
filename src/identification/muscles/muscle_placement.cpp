#include "motion_model_estimation/identification/muscles/muscle_placement.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"

namespace mme {

namespace {

/// A spring type whose every present parameter a muscle has too (no threshold, no cubic term),
/// not installed on the fly.
bool canBeMuscle(const Model& model, int t) {
  const BondType& type = model.bond_types[t];
  if (type.kind != BondKind::kSpring) return false;
  for (const Interaction& i : model.interactions)
    if (i.type == t) return false;
  const std::vector<ParamId>& allowed = paramsOfKind(BondKind::kMuscle);
  for (int id = 0; id < kParamCount; ++id)
    if (type.params[id].present &&
        std::find(allowed.begin(), allowed.end(), static_cast<ParamId>(id)) == allowed.end())
      return false;
  return true;
}

bool hasElongation(const Model& model, const Bond& bond) {
  return bondKindInfo(model.bond_types[bond.type].kind).has_elongation;
}

}  // namespace

Model addMuscles(const Model& passive, const Trajectory* data, const MusclePlacement& placement) {
  if (placement.inputs < 0 || placement.inputs > kMaxMuscleInputs)
    throw InputError("muscles: inputs must be 0.." + std::to_string(kMaxMuscleInputs) + ", got " +
                     std::to_string(placement.inputs));
  if (placement.hidden < 0 || placement.hidden > kMaxMuscleHidden)
    throw InputError("muscles: hidden must be 0.." + std::to_string(kMaxMuscleHidden) + ", got " +
                     std::to_string(placement.hidden));
  if (!(placement.gain_n >= 0.0) || !std::isfinite(placement.gain_n))
    throw InputError("muscles: the initial gain must be a finite number >= 0 N");
  Model model = passive;
  std::vector<int> elongation_bonds;
  for (size_t b = 0; b < model.bonds.size(); ++b)
    if (hasElongation(model, model.bonds[b])) elongation_bonds.push_back(static_cast<int>(b));
  const int inputs = std::max(0, std::min<int>(placement.inputs,
                                               static_cast<int>(elongation_bonds.size()) - 1));
  const double g = std::max(9.81, model.gravity().norm());
  std::vector<Eigen::Vector3d> place;
  for (const Particle& p : model.particles) place.push_back(p.position_m);
  if (data) {
    for (size_t k = 0; k < place.size(); ++k) {
      const auto it = std::find(data->marker_names.begin(), data->marker_names.end(),
                                model.particles[k].name);
      if (it == data->marker_names.end()) continue;
      const int i = static_cast<int>(it - data->marker_names.begin());
      for (int t = 0; t < data->numFrames(); ++t)
        if (!data->isOccluded(t, i)) {
          place[k] = data->position(t, i);
          break;
        }
    }
  }
  auto midpoint = [&](const Bond& bond) {
    return 0.5 * (place[bond.particles[0]] + place[bond.particles[1]]);
  };
  std::set<std::string> names;
  for (const Bond& bond : model.bonds)
    if (!bond.name.empty()) names.insert(bond.name);
  auto nameOf = [&](int b) {
    Bond& bond = model.bonds[b];
    if (bond.name.empty()) {
      std::string name = "bond_" + std::to_string(b);
      while (names.count(name)) name += "_";
      names.insert(name);
      bond.name = name;
    }
  };
  for (size_t t = 0; t < model.bond_types.size(); ++t) {
    if (!canBeMuscle(passive, static_cast<int>(t))) continue;
    BondType& type = model.bond_types[t];
    double weight_n = 0.0;
    int ends = 0;
    for (size_t b = 0; b < model.bonds.size(); ++b) {
      Bond& bond = model.bonds[b];
      if (bond.type != static_cast<int>(t)) continue;
      for (int k = 0; k < 2; ++k, ++ends) weight_n += model.particles[bond.particles[k]].mass_kg * g;
      // The nearest other bonds with an elongation: sharing an end first, then by midpoint.
      std::vector<std::tuple<int, double, int>> ranked;
      for (int other : elongation_bonds) {
        if (other == static_cast<int>(b)) continue;
        const Bond& o = model.bonds[other];
        const bool shares = o.particles[0] == bond.particles[0] || o.particles[0] == bond.particles[1] ||
                            o.particles[1] == bond.particles[0] || o.particles[1] == bond.particles[1];
        ranked.emplace_back(shares ? 0 : 1, (midpoint(o) - midpoint(bond)).norm(), other);
      }
      std::sort(ranked.begin(), ranked.end());
      bond.inputs.clear();
      for (int k = 0; k < inputs; ++k) {
        const int other = std::get<2>(ranked[k]);
        bond.inputs.push_back(other);
        nameOf(other);
      }
    }
    if (ends == 0) continue;  // a type no bond uses stays a spring
    type.kind = BondKind::kMuscle;
    Param& gain = type.param(kGain);
    gain.present = gain.free = gain.has_value = true;
    gain.value = placement.gain_n > 0.0 ? placement.gain_n : weight_n / ends;
    type.network_inputs = inputs;
    type.network_hidden = placement.hidden;
    type.network.assign(muscleNetworkSize(inputs, placement.hidden), Param{});
    for (Param& p : type.network) {
      p.present = p.free = p.has_value = true;
      p.value = 0.0;
    }
  }
  const std::string problem = validateModel(model);
  if (!problem.empty()) throw InputError("muscles: " + problem);
  return model;
}

Model removeMuscles(const Model& model) {
  Model out = model;
  for (BondType& type : out.bond_types) {
    if (type.kind != BondKind::kMuscle) continue;
    type.kind = BondKind::kSpring;
    type.param(kGain) = Param{};
    type.network_inputs = type.network_hidden = 0;
    type.network.clear();
  }
  for (Bond& bond : out.bonds) bond.inputs.clear();
  return out;
}

int muscleTypeCount(const Model& model) {
  int n = 0;
  for (const BondType& type : model.bond_types) n += bondKindInfo(type.kind).network ? 1 : 0;
  return n;
}

}  // namespace mme

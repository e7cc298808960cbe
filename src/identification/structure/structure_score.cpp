// Scoring a chosen structure against a known truth (structure_selection.h, scoreStructure):
// what tests and benchmarks use to say whether the selection found the bonds, their damping
// and non-linear terms, and their values. Not used by the selection itself, which never sees
// a truth.
#include "motion_model_estimation/identification/structure/structure_selection.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

namespace mme {

namespace {

/// Bonds by their particles' names: a pair sorted, a flexion as (vertex, sorted ends).
std::string bondKey(const Model& m, const Bond& b) {
  const BondType& type = m.bond_types[b.type];
  std::string a = m.particles[b.particles[0]].name;
  std::string c = kindArity(type.kind) >= 2 ? m.particles[b.particles[kindArity(type.kind) - 1]].name : "";
  if (c < a) std::swap(a, c);
  const std::string v = kindArity(type.kind) == 3 ? m.particles[b.particles[1]].name : "";
  return std::string(kindName(type.kind)) + "|" + v + "|" + a + "|" + c;
}

/// A model's springs ([0]) and flexions ([1]) by their keys, with their types.
using BondsByKey = std::map<std::string, const BondType*>;

/// The springs and flexions of `m` by key into `by_key`; returns the number of viscosity bonds.
int collectBonds(const Model& m, BondsByKey by_key[2]) {
  int viscosity_bonds = 0;
  for (const Bond& b : m.bonds) {
    const BondKind kind = m.bond_types[b.type].kind;
    if (kind == BondKind::kSpring || kind == BondKind::kFlexion)
      by_key[kind == BondKind::kFlexion ? 1 : 0][bondKey(m, b)] = &m.bond_types[b.type];
    if (kind == BondKind::kViscosity) ++viscosity_bonds;
  }
  return viscosity_bonds;
}

/// Precision, recall and F1 of the pairs and of the flexions (these stay 1 when neither model
/// has a flexion).
void scoreMatches(const BondsByKey want[2], const BondsByKey got[2], StructureScore* s) {
  double* precision[2] = {&s->precision, &s->flexion_precision};
  double* recall[2] = {&s->recall, &s->flexion_recall};
  double* f1[2] = {&s->f1, &s->flexion_f1};
  for (int k = 0; k < 2; ++k) {
    if (k == 1 && want[k].empty() && got[k].empty()) continue;  // no flexion anywhere: 1
    int hit = 0;
    for (const auto& g : got[k]) hit += want[k].count(g.first) ? 1 : 0;
    *precision[k] = got[k].empty() ? 0.0 : static_cast<double>(hit) / got[k].size();
    *recall[k] = want[k].empty() ? 0.0 : static_cast<double>(hit) / want[k].size();
    *f1[k] = *precision[k] + *recall[k] > 0.0
                 ? 2.0 * *precision[k] * *recall[k] / (*precision[k] + *recall[k]) : 0.0;
  }
}

/// Whether the chosen types are damped (and cubic, for springs) everywhere or nowhere.
void scoreTerms(const Model& chosen, StructureScore* s) {
  s->damped_everywhere = s->damped_nowhere = s->cubic_everywhere = s->cubic_nowhere = true;
  for (const BondType& t : chosen.bond_types) {
    if (t.kind == BondKind::kViscosity) continue;
    const bool damped = t.value(kDamping) != 0.0;
    s->damped_everywhere = s->damped_everywhere && damped;
    s->damped_nowhere = s->damped_nowhere && !damped;
    if (t.kind != BondKind::kSpring) continue;
    const bool cubic = t.value(kStiffnessNl) != 0.0;
    s->cubic_everywhere = s->cubic_everywhere && cubic;
    s->cubic_nowhere = s->cubic_nowhere && !cubic;
  }
}

/// The largest relative error of a found bond's values against its true type's.
double maxRelativeError(const BondsByKey want[2], const BondsByKey got[2]) {
  double max_error = 0.0;
  for (int k = 0; k < 2; ++k)
    for (const auto& w : want[k]) {
      const auto g = got[k].find(w.first);
      if (g == got[k].end()) continue;
      for (ParamId id : {kStiffness, k == 1 ? kRestAngle : kRestLength, kDamping, kStiffnessNl, kDampingNl}) {
        const double truth_value = w.second->value(id);
        if (truth_value == 0.0) continue;
        max_error = std::max(max_error, std::fabs(g->second->value(id) - truth_value) / std::fabs(truth_value));
      }
    }
  return max_error;
}

}  // namespace

StructureScore scoreStructure(const Model& truth, const Model& chosen) {
  BondsByKey want[2], got[2];  // [0] pairs, [1] flexions
  StructureScore s;
  collectBonds(truth, want);
  s.viscosity_bonds = collectBonds(chosen, got);
  scoreMatches(want, got, &s);
  s.types = static_cast<int>(chosen.bond_types.size());
  scoreTerms(chosen, &s);
  s.max_relative_error = maxRelativeError(want, got);
  return s;
}

}  // namespace mme

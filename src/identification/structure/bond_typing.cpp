// Bond typing for structure selection (bond_typing.h): the clustering of kept bonds by their
// values, the typed model's joint fit with non-physical types held, and the criterion's choice
// between shared types and one type per bond.
#include "bond_typing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <utility>
#include <vector>

#include "linearized_fit.h"

namespace mme {
namespace structure {

namespace {

constexpr ParamId kOptionalTerms[3] = {kDamping, kStiffnessNl, kDampingNl};

/// Bonds sharing a type: their inverse-variance weighted values.
struct Cluster {
  BondValues sum_w_v = BondValues::Zero(), sum_w = BondValues::Zero();
  uint8_t terms = 0;
  bool conditional = false;  ///< a spring with a threshold: a type of its own
  BondKind kind = BondKind::kSpring;
  int first_member = -1;
  BondValues mean() const { return sum_w_v.cwiseQuotient(sum_w); }
  BondValues sigma() const { return sum_w.cwiseInverse().cwiseSqrt(); }
};

bool isConditional(const BondType& type) {
  return type.param(kMinDistance).present || type.param(kMaxDistance).present;
}

/// Whether a bond (values `v`, 1-sigma `s`) joins `cluster`: one kind with the same optional
/// terms, neither conditional, and the values present agree within `sigmas`.
bool agrees(const Cluster& cluster, const BondValues& v, const BondValues& s, BondKind kind,
            uint8_t terms, bool conditional, double sigmas) {
  const BondValues mu = cluster.mean(), sc = cluster.sigma();
  bool agree = cluster.kind == kind && cluster.terms == terms && !conditional && !cluster.conditional;
  for (int d = 0; d < 5 && agree; ++d)
    if (d < 2 || (terms & (1u << (d - 2))))
      agree = std::fabs(v[d] - mu[d]) <= sigmas * std::sqrt(s[d] * s[d] + sc[d] * sc[d]);
  return agree;
}

/// The clusters of the kept bonds, greedy in order of stiffness, and each kept bond's cluster.
std::vector<Cluster> clusterBonds(const Solved& solved, int first_candidate_type, double sigmas,
                                  std::vector<int>* cluster_of) {
  const Model& m = solved.model;
  const int kept = static_cast<int>(solved.kept_types.size());
  std::vector<int> order(kept);
  for (int i = 0; i < kept; ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return solved.value[a][0] < solved.value[b][0]; });
  std::vector<Cluster> clusters;
  cluster_of->assign(kept, -1);
  for (int idx : order) {
    const BondValues& v = solved.value[idx];
    BondValues s = solved.sigma[idx];
    // Round-off of the solve: values within 1e-6 (relative) are equal.
    for (int d = 0; d < 5; ++d) s[d] = std::max(s[d], 1e-6 * std::max(std::fabs(v[d]), 1e-12));
    const BondType& member = m.bond_types[first_candidate_type + idx];
    const uint8_t terms = solved.terms[idx];
    const bool conditional = isConditional(member);
    int join = -1;
    for (size_t c = 0; c < clusters.size() && join < 0; ++c)
      if (agrees(clusters[c], v, s, member.kind, terms, conditional, sigmas)) join = static_cast<int>(c);
    if (join < 0) {
      join = static_cast<int>(clusters.size());
      clusters.emplace_back();
      clusters.back().terms = terms;
      clusters.back().conditional = conditional;
      clusters.back().kind = member.kind;
      clusters.back().first_member = idx;
    }
    const BondValues w = s.cwiseProduct(s).cwiseInverse();
    clusters[join].sum_w_v += w.cwiseProduct(v);
    clusters[join].sum_w += w;
    (*cluster_of)[idx] = join;
  }
  return clusters;
}

/// The shared type of `cluster`: its first member's layout (which parameters are free) at the
/// cluster's mean values (read back by the kind's linear form), named by the kind's candidate
/// prefix (s00.., f00.., v00..; `of_kind` counts per kind, indexed by BondKind).
BondType clusterType(const Model& m, const Cluster& cluster, int first_candidate_type,
                     std::vector<int>* of_kind) {
  BondType type = m.bond_types[first_candidate_type + cluster.first_member];
  const BondValues mu = cluster.mean();
  const BondKindInfo& info = bondKindInfo(type.kind);
  switch (info.linear_form) {
    case LinearForm::kPair:
    case LinearForm::kAngle:
      type.param(kStiffness).value = mu[0];
      type.param(info.linear_form == LinearForm::kPair ? kRestLength : kRestAngle).value = mu[1];
      for (int o = 0; o < 3; ++o)
        if (cluster.terms & (1u << o)) type.param(kOptionalTerms[o]).value = mu[2 + o];
      break;
    case LinearForm::kDrag:
      type.param(kViscosity).value = mu[0];
      break;
    case LinearForm::kNone:  // never a candidate: candidates are solved by the equation error
      break;
  }
  int& counter = (*of_kind)[static_cast<size_t>(type.kind)];
  char name[32];
  std::snprintf(name, sizeof(name), "%s%02d", info.candidate_prefix ? info.candidate_prefix : "?",
                counter++);
  type.name = name;
  return type;
}

/// The typed model's joint fit, and the values it could not use.
struct TypedFit {
  EquationErrorResult fit;
  std::vector<std::pair<int, ParamId>> held;  ///< parameters held at typing's values
};

/// Holds the free parameters of the candidate types whose values came out non-physical (NaN)
/// in `result` at their values in `typed_start` (the weighted mean of their bonds' own, physical
/// values); returns how many types were held.
size_t holdNonPhysicalTypes(const EquationErrorResult& result, const Model& typed_start,
                            int first_candidate_type, Model* typed,
                            std::vector<std::pair<int, ParamId>>* held) {
  const std::vector<ParamRef> refs = freeParameters(*typed);
  std::set<int> bad;
  for (size_t k = 0; k < refs.size(); ++k)
    if (!std::isfinite(result.values[k]) && refs[k].bond_type >= first_candidate_type)
      bad.insert(refs[k].bond_type);
  for (int t : bad)
    for (ParamId id : paramsOfKind(typed->bond_types[t].kind))
      if (typed->bond_types[t].param(id).free) {
        typed->bond_types[t].param(id) = typed_start.bond_types[t].param(id);
        typed->bond_types[t].param(id).free = false;
        held->push_back({t, id});
      }
  return bad.size();
}

/// The typed model's joint fit (none unless `try_typing`). The joint fit can come out
/// non-physical where each bond's own did not (merged columns, worse conditioned): such a type
/// is held at the values typing gave it, the others solved again, in rounds.
TypedFit fitTyped(const SelectionContext& ctx, const std::string& name, Model* typed, bool try_typing,
                  bool nonlinear, const EquationErrorOptions& level_ee) {
  TypedFit out;
  const Model typed_start = *typed;  // typing's values, before any fit moved them
  for (int round = 0;; ++round) {
    if (!try_typing) break;  // no typing: one type per bond
    if (nonlinear) convergeLinearized(typed, ctx.fit, level_ee);
    out.fit = solveEquationError(*typed, ctx.fit, level_ee);
    if (!out.fit.applicable || round == kMaxPasses) break;
    const size_t bad = holdNonPhysicalTypes(out.fit, typed_start, ctx.first_candidate_type, typed, &out.held);
    if (bad == 0) break;
    ctx.say("structure: " + name + ": " + std::to_string(bad) +
            " type(s) non-physical in the typed fit: held at their bonds' mean values");
  }
  return out;
}

/// Whether the typed fit can be used: applicable, every value determined and every held value
/// physical. When it can, its values go into `typed`; the held parameters count as free again.
bool settleTyped(const TypedFit& typed_fit, Model* typed) {
  bool usable = typed_fit.fit.applicable;
  for (double v : typed_fit.fit.values) usable = usable && std::isfinite(v);
  for (const auto& h : typed_fit.held)
    if (physicalOnlyPositive(h.second))
      usable = usable && typed->bond_types[h.first].param(h.second).value > 0.0;
  if (usable) setValues(*typed, freeParameters(*typed), typed_fit.fit.values);
  for (const auto& h : typed_fit.held) typed->bond_types[h.first].param(h.second).free = true;
  return usable;
}

}  // namespace

Model typeBonds(const Solved& solved, int first_candidate_type, double sigmas, int* types_out) {
  const Model& m = solved.model;
  std::vector<int> cluster_of;
  const std::vector<Cluster> clusters = clusterBonds(solved, first_candidate_type, sigmas, &cluster_of);
  // The typed model: base types, then one type per cluster.
  Model typed = m;
  typed.bond_types.resize(first_candidate_type);
  std::vector<int> of_kind(allBondKinds().size(), 0);  // numbering per kind: s00.., f00.., v00..
  for (const Cluster& cluster : clusters)
    typed.bond_types.push_back(clusterType(m, cluster, first_candidate_type, &of_kind));
  // The kept candidate types of `m` follow the base types in kept order.
  for (Bond& b : typed.bonds)
    if (b.type >= first_candidate_type)
      b.type = first_candidate_type + cluster_of[b.type - first_candidate_type];
  *types_out = static_cast<int>(clusters.size());
  return typed;
}

TypingChoice chooseTyping(const SelectionContext& ctx, const std::string& name, const Solved& solved,
                          const Selection& sel, size_t rows, double floor2, bool try_typing,
                          bool nonlinear, const EquationErrorOptions& level_ee) {
  TypingChoice chosen{solved.model, sel.rss_m2, sel.parameters, bic(sel.rss_m2, rows, sel.parameters, floor2)};
  const double untyped_bic = chosen.bic;
  int types = 0;
  // Types with no bond left (non-physical drops) do not exist in `solved.model`; typed too.
  Model typed = typeBonds(solved, ctx.first_candidate_type, ctx.options.type_sigmas, &types);
  const TypedFit typed_fit = fitTyped(ctx, name, &typed, try_typing, nonlinear, level_ee);
  const bool typed_usable = settleTyped(typed_fit, &typed);
  const int typed_params = static_cast<int>(freeParameters(typed).size());
  if (!typed_fit.fit.applicable) return chosen;
  const EquationErrorResult& fit = typed_fit.fit;
  const double typed_rss = fit.residual_rms_m * fit.residual_rms_m * fit.rows;
  const double typed_bic = bic(typed_rss, fit.rows, typed_params, floor2);
  char line[240];
  std::snprintf(line, sizeof(line), "structure: %s: %d bonds in %d types: residual RMS %.3g m "
                "(one type per bond: %.3g m), BIC %.6g against %.6g", name.c_str(),
                static_cast<int>(typed.bonds.size()), types,
                fit.residual_rms_m, std::sqrt(sel.rss_m2 / std::max<size_t>(rows, 1)),
                typed_bic, untyped_bic);
  ctx.say(line);
  if (!(typed_bic <= untyped_bic)) return chosen;
  if (typed_usable) return TypingChoice{typed, typed_rss, typed_params, typed_bic};
  const std::string why = "the criterion preferred shared types, but the typed fit "
                          "stayed non-physical or undetermined: one type per bond kept";
  ctx.say("structure: " + name + ": " + why);
  ctx.result->notes.push_back(name + ": " + why);
  return chosen;
}

}  // namespace structure
}  // namespace mme

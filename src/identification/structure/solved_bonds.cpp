// From an elimination's solve to bonds (solved_bonds.h): the solved values and their
// uncertainty per kept bond, the physical checks, the pruning of removed candidates, and the
// signature that tells two levels' structures apart.
#include "solved_bonds.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace mme {
namespace structure {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr ParamId kOptionalTerms[3] = {kDamping, kStiffnessNl, kDampingNl};

/// Which column holds which parameter of which type: (type, ParamId) -> column; a spring's or
/// flexion's product column (k L, k theta0) under (type, -kRestLength - 1).
std::map<std::pair<int, int>, int> columnsByParam(const std::vector<ParamRef>& refs,
                                                  const EquationErrorSystem& sys) {
  std::map<std::pair<int, int>, int> column_of;
  for (size_t j = 0; j < sys.column_param.size(); ++j) {
    const ParamRef& r = refs[sys.column_param[j]];
    const bool product = sys.column_partner[j] >= 0;
    column_of[{r.bond_type, product ? -kRestLength - 1 : r.param}] = static_cast<int>(j);
  }
  return column_of;
}

/// The final solve's covariance of the active columns: sigma2 times the unscaled inverse.
class SolveCovariance {
 public:
  SolveCovariance(const Selection& sel, double sigma2)
      : inv_(sel.inverse_scaled), scale_(sel.scale), sigma2_(sigma2) {
    for (size_t i = 0; i < sel.active_columns.size(); ++i)
      position_[sel.active_columns[i]] = static_cast<int>(i);
  }
  bool active(int column) const { return position_.count(column) > 0; }
  double cov(int ci, int cj) const {
    const int pi = position_.at(ci), pj = position_.at(cj);
    return sigma2_ * inv_(pi, pj) * scale_[pi] * scale_[pj];
  }
  double sigma(int c) const { return std::sqrt(std::max(0.0, cov(c, c))); }

 private:
  const Eigen::MatrixXd& inv_;
  const Eigen::VectorXd& scale_;
  double sigma2_;
  std::map<int, int> position_;
};

/// One kept bond as read from the solve.
struct KeptBond {
  BondValues value = BondValues::Zero(), sigma = BondValues::Zero();
  uint8_t terms = 0;
};

/// Every solved value (base types, candidates, gravity) into `model`.
void applySolvedValues(Model* model, const std::vector<ParamRef>& refs,
                       const EquationErrorSystem& sys, const Selection& sel) {
  for (int j : sel.active_columns) {
    const int partner = sys.column_partner[j];
    const double value = partner >= 0 ? sel.theta[j] / sel.theta[partner] : sel.theta[j] + sys.column_offset[j];
    if (std::isfinite(value)) setParam(*model, refs[sys.column_param[j]], value);
  }
}

/// Gravity held at zero (its unit was removed).
void clearGravity(Model* model) {
  for (int c = 0; c < 3; ++c) {
    Param& p = model->gravity_mps2[c];
    p = Param();
    p.present = true;
    p.has_value = true;
  }
}

/// A kept drag's value c_v (non-physical unless > 0: then listed in `out->bad_bonds`).
KeptBond readViscosity(BondType* type, int t, const std::map<std::pair<int, int>, int>& column_of,
                       const SolveCovariance& cov, const Eigen::VectorXd& theta, Solved* out) {
  KeptBond kept;
  const int cv = column_of.at({t, kViscosity});
  kept.value[0] = theta[cv];
  kept.sigma[0] = cov.sigma(cv);
  if (!(kept.value[0] > 0.0)) out->bad_bonds.push_back(t);
  else type->param(kViscosity).value = kept.value[0];
  return kept;
}

/// A kept spring's (k, L = kL / k, c, ...) or flexion's (k, theta0 = k theta0 / k, c) values:
/// the same algebra; a rest length that is not free (the non-linear level) is known.
/// Non-physical bonds and terms are listed in `out`.
KeptBond readSpringOrFlexion(BondType* type, int t, const std::map<std::pair<int, int>, int>& column_of,
                             const SolveCovariance& cov, const Eigen::VectorXd& theta, bool dampers,
                             Solved* out) {
  KeptBond kept;
  BondValues& v = kept.value;
  BondValues& s = kept.sigma;
  const bool spring = type->kind == BondKind::kSpring;
  const ParamId rest_id = spring ? kRestLength : kRestAngle;
  const int ck = column_of.at({t, kStiffness});
  const double k = theta[ck];
  s[0] = cov.sigma(ck);
  double rest = type->param(rest_id).value;  // known, or set before (a linearised column)
  const auto linearized = column_of.find({t, rest_id});
  if (linearized != column_of.end() && cov.active(linearized->second)) s[1] = cov.sigma(linearized->second);
  const auto product = column_of.find({t, -kRestLength - 1});
  if (product != column_of.end()) {
    const int ckl = product->second;
    const double kl = theta[ckl];
    rest = kl / k;
    const double dl_dkl = 1.0 / k, dl_dk = -kl / (k * k);
    s[1] = std::sqrt(std::max(0.0, dl_dkl * dl_dkl * cov.cov(ckl, ckl) + dl_dk * dl_dk * cov.cov(ck, ck) +
                                       2.0 * dl_dkl * dl_dk * cov.cov(ck, ckl)));
  }
  v[0] = k;
  v[1] = rest;
  // The optional terms still active.
  for (int o = 0; o < 3; ++o) {
    const auto column = column_of.find({t, kOptionalTerms[o]});
    if (column == column_of.end() || !cov.active(column->second)) continue;
    if (kOptionalTerms[o] == kDamping && !dampers) continue;
    kept.terms |= static_cast<uint8_t>(1u << o);
    v[2 + o] = theta[column->second];
    s[2 + o] = cov.sigma(column->second);
    type->param(kOptionalTerms[o]).value = v[2 + o];
    if (kOptionalTerms[o] != kStiffnessNl && !(v[2 + o] > 0.0)) out->bad_terms.push_back({t, kOptionalTerms[o]});
  }
  const bool rest_ok = spring ? rest > 0.0 : (rest > 0.0 && rest <= kPi);
  if (!(k > 0.0) || !rest_ok) out->bad_bonds.push_back(t);
  type->param(kStiffness).value = k;
  type->param(rest_id).value = rest;
  return kept;
}

/// `model` without the candidate types not kept and their bonds (base types stay, indices kept
/// in order).
Model pruneTypes(const Model& model, const std::vector<uint8_t>& keep_type, int first_candidate_type) {
  Model pruned = model;
  pruned.bond_types.clear();
  pruned.bonds.clear();
  std::vector<int> new_index(model.bond_types.size(), -1);
  for (size_t t = 0; t < model.bond_types.size(); ++t)
    if (static_cast<int>(t) < first_candidate_type || keep_type[t]) {
      new_index[t] = static_cast<int>(pruned.bond_types.size());
      pruned.bond_types.push_back(model.bond_types[t]);
    }
  for (const Bond& b : model.bonds)
    if (new_index[b.type] >= 0) {
      Bond nb = b;
      nb.type = new_index[b.type];
      pruned.bonds.push_back(nb);
    }
  return pruned;
}

/// `type` without the optional terms of `candidate_type` listed in `bad_terms` (their bits
/// cleared in `terms`, their values zeroed in `value`).
void dropBadTerms(const std::vector<std::pair<int, int>>& bad_terms, int candidate_type,
                  BondType* type, BondValues* value, uint8_t* terms) {
  for (const auto& term : bad_terms) {
    if (term.first != candidate_type) continue;
    for (int o = 0; o < 3; ++o)
      if (kOptionalTerms[o] == term.second) {
        type->param(kOptionalTerms[o]) = Param();
        *terms &= static_cast<uint8_t>(~(1u << o));
        (*value)[2 + o] = 0.0;
      }
  }
}

}  // namespace

Solved describe(const Model& candidate, const EquationErrorSystem& sys, const Selection& sel,
                double sigma2, int first_candidate_type, bool dampers) {
  Solved out;
  const std::vector<ParamRef> refs = freeParameters(candidate);
  const std::map<std::pair<int, int>, int> column_of = columnsByParam(refs, sys);
  const SolveCovariance cov(sel, sigma2);  // the elimination's final solve
  Model model = candidate;
  applySolvedValues(&model, refs, sys, sel);
  // Base types stay; a candidate type stays when its spring does.
  std::vector<uint8_t> keep_type(candidate.bond_types.size(), 0);
  for (int t = 0; t < first_candidate_type; ++t) keep_type[t] = 1;
  for (const Group& g : sel.groups) {
    if (g.bond_type < 0) {
      if (!g.active) clearGravity(&model);
      continue;
    }
    if (g.term >= 0) {
      if (!g.active) model.bond_types[g.bond_type].param(static_cast<ParamId>(g.term)) = Param();
      continue;
    }
    if (!g.active) continue;
    const int t = g.bond_type;
    keep_type[t] = 1;
    BondType& type = model.bond_types[t];
    const KeptBond kept = type.kind == BondKind::kViscosity
                              ? readViscosity(&type, t, column_of, cov, sel.theta, &out)
                              : readSpringOrFlexion(&type, t, column_of, cov, sel.theta, dampers, &out);
    out.kept_types.push_back(t);
    out.value.push_back(kept.value);
    out.sigma.push_back(kept.sigma);
    out.terms.push_back(kept.terms);
  }
  out.model = pruneTypes(model, keep_type, first_candidate_type);
  return out;
}

bool dropNonPhysical(Solved* solved, int first_candidate_type) {
  if (solved->bad_bonds.empty() && solved->bad_terms.empty()) return false;
  const std::set<int> bad(solved->bad_bonds.begin(), solved->bad_bonds.end());
  Model& m = solved->model;
  Solved kept;
  kept.model = m;
  kept.model.bond_types.resize(first_candidate_type);
  kept.model.bonds.clear();
  std::vector<int> new_type(m.bond_types.size(), -1);
  for (int t = 0; t < first_candidate_type; ++t) new_type[t] = t;
  for (size_t i = 0; i < solved->kept_types.size(); ++i) {
    const int candidate_type = solved->kept_types[i];
    if (bad.count(candidate_type)) continue;
    BondType type = m.bond_types[first_candidate_type + i];
    BondValues value = solved->value[i];
    uint8_t terms = solved->terms[i];
    dropBadTerms(solved->bad_terms, candidate_type, &type, &value, &terms);
    new_type[first_candidate_type + i] = static_cast<int>(kept.model.bond_types.size());
    kept.model.bond_types.push_back(type);
    kept.kept_types.push_back(candidate_type);
    kept.value.push_back(value);
    kept.sigma.push_back(solved->sigma[i]);
    kept.terms.push_back(terms);
  }
  for (const Bond& b : m.bonds)
    if (new_type[b.type] >= 0) {
      Bond nb = b;
      nb.type = new_type[b.type];
      kept.model.bonds.push_back(nb);
    }
  *solved = std::move(kept);
  return true;
}

std::string structureSignature(const Model& model, int first_candidate_type) {
  std::vector<std::string> items;
  for (const Bond& b : model.bonds) {
    if (b.type < first_candidate_type) continue;
    const BondType& type = model.bond_types[b.type];
    std::string item = kindName(type.kind);
    for (int k = 0; k < kindArity(type.kind); ++k) item += " " + model.particles[b.particles[k]].name;
    for (ParamId id : paramsOfKind(type.kind))
      if (type.param(id).present) item += std::string(" ") + paramKey(id);
    items.push_back(item);
  }
  std::sort(items.begin(), items.end());
  std::string out;
  for (const std::string& item : items) out += item + ";";
  const bool gravity = model.gravity_mps2[0].free || model.gravity_mps2[1].free || model.gravity_mps2[2].free;
  return out + (gravity ? "gravity" : "");
}

}  // namespace structure
}  // namespace mme

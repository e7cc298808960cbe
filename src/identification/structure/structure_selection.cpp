#include "motion_model_estimation/identification/structure/structure_selection.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/forces.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"
#include "motion_model_estimation/identification/estimators/normal_equations.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"

namespace mme {

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;
constexpr double kRoundOffFloorM = 1e-10;  ///< an equation-error residual below this is exact
constexpr int kHorizons[3] = {1, 5, 10};
constexpr int kMaxPasses = 12;  ///< solves per level (non-physical drops, screening rounds)

/// The selection's wall-time limit (StructureOptions::max_wall_time_s; 0 = none), read between
/// steps: a step under way (one solve, one refit bounded by what is left) still ends.
class Deadline {
 public:
  explicit Deadline(double max_s) : max_s_(max_s), start_(std::chrono::steady_clock::now()) {}
  double elapsedS() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  bool limited() const { return max_s_ > 0.0; }
  bool passed() const { return limited() && elapsedS() >= max_s_; }
  /// [s] left; infinite without a limit.
  double remainingS() const {
    return limited() ? std::max(0.0, max_s_ - elapsedS()) : std::numeric_limits<double>::infinity();
  }
  double maxS() const { return max_s_; }

 private:
  double max_s_;
  std::chrono::steady_clock::time_point start_;
};

/// Mean and relative spread of a pair's distance over the frames where both are seen.
struct PairStats {
  double mean_m = 0.0;
  double relative_std = 0.0;
  bool seen = false;
};

std::vector<std::pair<int, int>> candidatePairs(const Model& model, const Trajectory& data,
                                                const StructureOptions& options) {
  const int n = static_cast<int>(model.particles.size());
  std::set<std::pair<int, int>> bonded;
  for (const Bond& b : model.bonds)
    if (kindArity(model.bond_types[b.type].kind) == 2)
      bonded.insert(std::minmax(b.particles[0], b.particles[1]));
  std::vector<std::vector<PairStats>> stats(n, std::vector<PairStats>(n));
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      const MarkerDistance d = markerDistance(data, a, b);
      if (d.seen_frames < 3) continue;
      PairStats& s = stats[a][b];
      s.seen = true;
      s.mean_m = d.mean_m;
      s.relative_std = s.mean_m > 0.0 ? d.std_m / s.mean_m : 0.0;
      stats[b][a] = s;
    }
  const auto usable = [&](int a, int b) {
    return a != b && stats[a][b].seen && stats[a][b].mean_m > 0.0 &&
           !(model.particles[a].fixed && model.particles[b].fixed) &&
           !bonded.count(std::minmax(a, b));
  };
  std::set<std::pair<int, int>> chosen;
  for (int a = 0; a < n; ++a) {
    std::vector<std::pair<double, int>> near;
    for (int b = 0; b < n; ++b)
      if (usable(a, b)) near.push_back({stats[a][b].mean_m, b});
    std::sort(near.begin(), near.end());
    for (int k = 0; k < options.neighbours && k < static_cast<int>(near.size()); ++k)
      chosen.insert(std::minmax(a, near[k].second));
  }
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      if (usable(a, b) && stats[a][b].relative_std < options.rigid_relative_std) chosen.insert({a, b});
  std::vector<std::pair<double, std::pair<int, int>>> by_length;
  for (const auto& p : chosen) by_length.push_back({stats[p.first][p.second].mean_m, p});
  std::sort(by_length.begin(), by_length.end());
  if (static_cast<int>(by_length.size()) > options.max_candidates) by_length.resize(options.max_candidates);
  std::vector<std::pair<int, int>> pairs;
  for (const auto& e : by_length) pairs.push_back(e.second);
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

Param freeParam(double value) {
  Param p;
  p.value = value;
  p.present = true;
  p.has_value = true;
  p.free = true;
  return p;
}

/// A spring bond of its own type per pair, appended to `base`; returns the first new type.
int addCandidateBonds(Model* model, const std::vector<std::pair<int, int>>& pairs,
                      const Trajectory& data, bool dampers) {
  const int first = static_cast<int>(model->bond_types.size());
  for (const auto& p : pairs) {
    BondType type;
    type.name = "b_" + model->particles[p.first].name + "_" + model->particles[p.second].name;
    type.kind = BondKind::kSpring;
    double length = 0.0;
    int count = 0;
    for (int t = 0; t < data.numFrames(); ++t)
      if (!data.isOccluded(t, p.first) && !data.isOccluded(t, p.second)) {
        length += (data.position(t, p.first) - data.position(t, p.second)).norm();
        ++count;
      }
    type.param(kStiffness) = freeParam(1.0);
    type.param(kRestLength) = freeParam(count > 0 ? length / count : 0.1);
    if (dampers) type.param(kDamping) = freeParam(0.1);
    Bond bond;
    bond.type = static_cast<int>(model->bond_types.size());
    bond.particles = {{p.first, p.second, -1}};
    model->bond_types.push_back(type);
    model->bonds.push_back(bond);
  }
  return first;
}

/// Near-collinear triples (a, v, c) for flexion: a and c among the `nearest` candidate partners
/// of the vertex v, with a mean angle at v of at least `min_angle_rad` (a chain's bend: springs
/// alone resist it only at second order, unlike a triangle's), the straightest first, at most
/// `most`.
std::vector<std::array<int, 3>> candidateTriples(const Model& model, const Trajectory& data,
                                                 const std::vector<std::pair<int, int>>& pairs,
                                                 int nearest, double min_angle_rad, int most) {
  const int n = static_cast<int>(model.particles.size());
  // Each vertex's nearest candidate partners (mean distance): a chain's neighbours.
  const auto meanDistance = [&](int a, int b) {
    double sum = 0.0;
    int count = 0;
    for (int t = 0; t < data.numFrames(); ++t)
      if (!data.isOccluded(t, a) && !data.isOccluded(t, b)) {
        sum += (data.position(t, a) - data.position(t, b)).norm();
        ++count;
      }
    return count > 0 ? sum / count : std::numeric_limits<double>::infinity();
  };
  std::vector<std::vector<std::pair<double, int>>> by_distance(n);
  for (const auto& p : pairs) {
    const double d = meanDistance(p.first, p.second);
    by_distance[p.first].push_back({d, p.second});
    by_distance[p.second].push_back({d, p.first});
  }
  std::vector<std::vector<int>> partners(n);
  for (int v = 0; v < n; ++v) {
    std::sort(by_distance[v].begin(), by_distance[v].end());
    for (int k = 0; k < nearest && k < static_cast<int>(by_distance[v].size()); ++k)
      partners[v].push_back(by_distance[v][k].second);
  }
  std::vector<std::pair<double, std::array<int, 3>>> found;
  for (int v = 0; v < n; ++v) {
    if (model.particles[v].fixed) continue;
    const std::vector<int>& near = partners[v];
    for (size_t i = 0; i < near.size(); ++i)
      for (size_t j = i + 1; j < near.size(); ++j) {
        const int a = std::min(near[i], near[j]), c = std::max(near[i], near[j]);
        double sum = 0.0;
        int count = 0;
        for (int t = 0; t < data.numFrames(); ++t) {
          if (data.isOccluded(t, a) || data.isOccluded(t, v) || data.isOccluded(t, c)) continue;
          sum += flexionAngle(data.position(t, a), data.position(t, v), data.position(t, c));
          ++count;
        }
        if (count < 3 || sum / count < min_angle_rad) continue;
        found.push_back({-sum / count, {{a, v, c}}});
      }
  }
  std::sort(found.begin(), found.end());
  if (static_cast<int>(found.size()) > most) found.resize(most);
  std::vector<std::array<int, 3>> triples;
  for (const auto& f : found) triples.push_back(f.second);
  std::sort(triples.begin(), triples.end());
  return triples;
}

/// A flexion bond of its own type per triple (stiffness, rest angle at the mean angle, and a
/// damping when `dampers`).
void addCandidateFlexions(Model* model, const std::vector<std::array<int, 3>>& triples,
                          const Trajectory& data, bool dampers) {
  for (const auto& tr : triples) {
    BondType type;
    type.name = "f_" + model->particles[tr[0]].name + "_" + model->particles[tr[1]].name + "_" +
                model->particles[tr[2]].name;
    type.kind = BondKind::kFlexion;
    double angle = 0.0;
    int count = 0;
    for (int t = 0; t < data.numFrames(); ++t)
      if (!data.isOccluded(t, tr[0]) && !data.isOccluded(t, tr[1]) && !data.isOccluded(t, tr[2])) {
        angle += flexionAngle(data.position(t, tr[0]), data.position(t, tr[1]), data.position(t, tr[2]));
        ++count;
      }
    type.param(kStiffness) = freeParam(1e-3);
    type.param(kRestAngle) = freeParam(count > 0 ? angle / count : 3.0);
    if (dampers) type.param(kDamping) = freeParam(1e-4);
    Bond bond;
    bond.type = static_cast<int>(model->bond_types.size());
    bond.particles = {{tr[0], tr[1], tr[2]}};
    model->bond_types.push_back(type);
    model->bonds.push_back(bond);
  }
}

/// A viscosity (drag on the particle's velocity) of its own type per free particle.
void addCandidateViscosities(Model* model) {
  for (size_t i = 0; i < model->particles.size(); ++i) {
    if (model->particles[i].fixed) continue;
    BondType type;
    type.name = "v_" + model->particles[i].name;
    type.kind = BondKind::kViscosity;
    type.param(kViscosity) = freeParam(0.01);
    Bond bond;
    bond.type = static_cast<int>(model->bond_types.size());
    bond.particles = {{static_cast<int>(i), -1, -1}};
    model->bond_types.push_back(type);
    model->bonds.push_back(bond);
  }
}

/// Solves the columns in `active` of the normal equations (normal_equations.h); the others 0.
/// Throws InputError naming `who` when the system is not finite or no solve can be trusted.
NormalEquationsSolution solveActive(const EquationErrorSystem& sys, const std::vector<int>& active,
                                    bool want_inverse, const std::string& who) {
  if (!sys.ata.allFinite() || !sys.atb.allFinite() || !std::isfinite(sys.btb))
    throw InputError("structure selection: " + who + ": the equation error's normal equations are not finite");
  NormalEquationsSolution s = solveNormalEquations(sys.ata, sys.atb, sys.btb, active, want_inverse);
  if (!s.trusted)
    throw InputError("structure selection: " + who + ": the equation error's " +
                     std::to_string(active.size()) + " unknowns could not be solved reliably (the "
                     "residual stayed above the right-hand side at every ridge); the window's "
                     "markers may be too few or too still for this many candidates");
  return s;
}

double rss(const EquationErrorSystem& sys, const Eigen::VectorXd& theta) {
  return std::max(0.0, sys.btb - 2.0 * theta.dot(sys.atb) + theta.dot(sys.ata * theta));
}

/// A removable unit: a bond (its spring, flexion or drag, with its children), one of a bond's
/// optional terms alone (damping, cubic stiffness, quadratic damping), or gravity.
struct Group {
  std::vector<int> columns;
  int bond_type = -1;     ///< -1: gravity
  int term = -1;          ///< an optional term's ParamId (kDamping, ...); -1: the bond itself
  std::vector<int> children;  ///< the optional terms' groups, which go with the bond
  bool active = true;
};

struct Selection {
  std::vector<Group> groups;
  Eigen::VectorXd theta;
  double rss_m2 = 0.0;
  int parameters = 0;
  std::vector<int> active_columns;
  Eigen::MatrixXd inverse_scaled;  ///< the final solve's scaled (pseudo-)inverse
  Eigen::VectorXd scale;           ///< its column scaling
  bool cut = false;                ///< the time limit stopped the elimination early
};

std::vector<int> activeColumns(const std::vector<Group>& groups, const std::vector<int>& always) {
  std::vector<int> cols = always;
  for (const Group& g : groups)
    if (g.active) cols.insert(cols.end(), g.columns.begin(), g.columns.end());
  std::sort(cols.begin(), cols.end());
  return cols;
}

/// Grouped backward elimination with the BIC's price per parameter, sigma2 * ln(N). The solve
/// is kept as the (scaled) inverse of the active normal equations and downdated when a unit
/// goes (theta_K -= inv_KR inv_RR^-1 theta_R, inv_KK -= inv_KR inv_RR^-1 inv_RK); it is
/// recomputed from scratch every 25 removals against drift. The time limit stops the removals;
/// the selection so far is then solved again unless `finish_when_cut` is false (the caller gives
/// the level up and reads only `cut`).
Selection eliminate(const EquationErrorSystem& sys, std::vector<Group> groups,
                    const std::vector<int>& always, double sigma2, const std::string& who,
                    const Deadline& deadline, bool finish_when_cut,
                    const std::function<void(const std::string&)>& progress) {
  const double price_per_param = sigma2 * std::log(static_cast<double>(std::max<size_t>(sys.rows, 2)));
  int removed = 0, since_solve = 0;
  std::vector<int> cols;
  Eigen::MatrixXd inv;
  Eigen::VectorXd scale, theta_s;  // theta = scale .* theta_s
  std::map<int, int> position;
  const auto resolve = [&]() {
    cols = activeColumns(groups, always);
    NormalEquationsSolution solved = solveActive(sys, cols, true, who);
    const Eigen::VectorXd& full = solved.theta;
    inv = std::move(solved.inverse_scaled);
    scale = std::move(solved.scale);
    theta_s.resize(cols.size());
    position.clear();
    for (size_t i = 0; i < cols.size(); ++i) {
      position[cols[i]] = static_cast<int>(i);
      theta_s[i] = scale[i] > 0.0 ? full[cols[i]] / scale[i] : 0.0;
    }
    since_solve = 0;
  };
  // The positions of a unit's columns (a spring with its active damper).
  const auto unitOf = [&](int g) {
    std::vector<int> unit;
    for (int c : groups[g].columns) unit.push_back(position.at(c));
    for (int child : groups[g].children)
      if (groups[child].active)
        for (int c : groups[child].columns) unit.push_back(position.at(c));
    return unit;
  };
  // The residual's rise when the columns at `r` go: theta_R^T inv_RR^-1 theta_R.
  const auto rise = [&](const std::vector<int>& r) {
    const int u = static_cast<int>(r.size());
    Eigen::MatrixXd block(u, u);
    Eigen::VectorXd t(u);
    for (int i = 0; i < u; ++i) {
      t[i] = theta_s[r[i]];
      for (int j = 0; j < u; ++j) block(i, j) = inv(r[i], r[j]);
    }
    // The block of a positive-definite inverse is positive definite: a Cholesky (LDLT) solves
    // it ten times faster than an orthogonal decomposition, which matters for the joint rise of
    // a thousand cheap units; the decomposition stays the fallback when round-off breaks it.
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(block);
    if (ldlt.info() == Eigen::Success && ldlt.isPositive() && (ldlt.vectorD().array() > 0.0).all())
      return t.dot(ldlt.solve(t));
    return t.dot(block.completeOrthogonalDecomposition().solve(t));
  };
  // Removes the columns at positions `r` from the solve (downdate).
  const auto drop = [&](std::vector<int> r) {
    std::sort(r.begin(), r.end());
    const int m = static_cast<int>(cols.size()), u = static_cast<int>(r.size());
    std::vector<int> k;
    for (int i = 0, j = 0; i < m; ++i) {
      if (j < u && r[j] == i) { ++j; continue; }
      k.push_back(i);
    }
    const int n = static_cast<int>(k.size());
    Eigen::MatrixXd rr(u, u), kr(n, u), kk(n, n);
    Eigen::VectorXd tr(u), tk(n), sk(n);
    for (int i = 0; i < u; ++i) {
      tr[i] = theta_s[r[i]];
      for (int j = 0; j < u; ++j) rr(i, j) = inv(r[i], r[j]);
    }
    for (int i = 0; i < n; ++i) {
      tk[i] = theta_s[k[i]];
      sk[i] = scale[k[i]];
      for (int j = 0; j < u; ++j) kr(i, j) = inv(k[i], r[j]);
      for (int j = 0; j < n; ++j) kk(i, j) = inv(k[i], k[j]);
    }
    if (n > 0) {  // (every column going leaves nothing to downdate: Eigen has no empty solve)
      const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> rr_cod(rr);
      const Eigen::MatrixXd w = rr_cod.solve(kr.transpose());  // inv_RR^-1 inv_RK
      theta_s = tk - kr * rr_cod.solve(tr);
      inv = kk - kr * w;
    } else {
      theta_s.resize(0);
      inv.resize(0, 0);
    }
    scale = sk;
    std::vector<int> kept_cols;
    position.clear();
    for (int i = 0; i < n; ++i) {
      kept_cols.push_back(cols[k[i]]);
      position[cols[k[i]]] = i;
    }
    cols = kept_cols;
    ++since_solve;
  };
  if (deadline.passed() && !finish_when_cut) {  // given up before the first solve
    Selection s;
    s.cut = true;
    return s;
  }
  resolve();
  bool cut = false;
  for (;;) {
    if (deadline.passed()) {
      cut = true;
      break;
    }
    if (since_solve >= 25) resolve();
    // The cheapest unit to remove, and every unit far below its price.
    double best_ratio = std::numeric_limits<double>::infinity();
    int best = -1;
    std::vector<int> cheap;
    for (size_t g = 0; g < groups.size() && !cut; ++g) {
      if (g % 64 == 63 && deadline.passed()) cut = true;  // a scan of a large level takes seconds
      if (!groups[g].active || groups[g].columns.empty()) continue;
      const std::vector<int> unit = unitOf(static_cast<int>(g));
      const double ratio = rise(unit) / (unit.size() * price_per_param);
      if (ratio < 1e-3) cheap.push_back(static_cast<int>(g));
      if (ratio < best_ratio) {
        best_ratio = ratio;
        best = static_cast<int>(g);
      }
    }
    if (cut || best < 0 || !(best_ratio < 1.0)) break;
    // The cheap ones together when their joint rise is cheap too (collinear units can each look
    // free while together they are not); else the cheapest alone.
    std::vector<int> batch = {best};
    // A bond's unit holds its active optional terms, which are units of their own too: each
    // column once (a repeated one made the block singular and was not removed by the downdate).
    const auto columnsOf = [&](const std::vector<int>& units) {
      std::vector<int> r;
      for (int g : units) {
        const std::vector<int> unit = unitOf(g);
        r.insert(r.end(), unit.begin(), unit.end());
      }
      std::sort(r.begin(), r.end());
      r.erase(std::unique(r.begin(), r.end()), r.end());
      return r;
    };
    if (cheap.size() > 1) {
      const std::vector<int> r = columnsOf(cheap);
      if (rise(r) < 1e-2 * r.size() * price_per_param) batch = cheap;
    }
    if (deadline.passed()) {  // before the downdate, which costs as much as a solve
      cut = true;
      break;
    }
    const std::vector<int> r = columnsOf(batch);
    for (int g : batch) {
      groups[g].active = false;
      for (int child : groups[g].children) groups[child].active = false;
    }
    drop(r);
    removed += static_cast<int>(batch.size());
  }
  Selection s;
  if (cut && !finish_when_cut) {  // the caller gives the level up: no final solve
    s.cut = true;
    return s;
  }
  resolve();  // the final solve from scratch
  s.groups = std::move(groups);
  s.theta = Eigen::VectorXd::Zero(sys.atb.size());
  for (size_t i = 0; i < cols.size(); ++i) s.theta[cols[i]] = scale[i] * theta_s[i];
  s.rss_m2 = rss(sys, s.theta);
  s.parameters = static_cast<int>(cols.size());
  s.active_columns = cols;
  s.inverse_scaled = inv;
  s.scale = scale;
  s.cut = cut;
  if (progress) progress("  elimination: " + std::to_string(removed) + " unit(s) removed, " +
                         std::to_string(cols.size()) + " unknowns left" +
                         (cut ? " (cut by the time limit)" : ""));
  return s;
}

/// BIC of a least-squares fit: N ln(RSS / N) + P ln N, RSS floored at N sigma_floor^2.
double bic(double rss_m2, size_t rows, int parameters, double sigma2_floor) {
  const double n = static_cast<double>(std::max<size_t>(rows, 1));
  const double r = std::max(rss_m2, n * sigma2_floor);
  return n * std::log(r / n) + parameters * std::log(n);
}

/// A kept bond's values: spring (k, L, c, k_nl, c_nl); flexion (k, theta0, c, 0, 0); viscosity
/// (c_v, 0, 0, 0, 0).
using BondValues = Eigen::Matrix<double, 5, 1>;
/// Which optional terms a kept bond has (bits): damping, cubic stiffness, quadratic damping.
enum TermBits : uint8_t { kHasDamping = 1, kHasStiffnessNl = 2, kHasDampingNl = 4 };

/// The model a selection describes: the base model's own bonds, then one type per kept bond
/// with its solved values; gravity off when its unit was removed.
struct Solved {
  Model model;
  std::vector<int> kept_types;      ///< the candidate types kept (indices into the candidate model)
  std::vector<BondValues> value, sigma;  ///< per kept type: its values and their 1-sigma
  std::vector<uint8_t> terms;       ///< per kept type: its optional terms (TermBits)
  std::vector<int> bad_bonds;       ///< kept types with k <= 0, L <= 0, theta0 outside (0, pi] or c_v <= 0
  /// Optional terms that came out non-physical (a damping <= 0): (type, ParamId).
  std::vector<std::pair<int, int>> bad_terms;
};

Solved describe(const Model& candidate, const EquationErrorSystem& sys, const Selection& sel,
                double sigma2, int first_candidate_type, bool dampers) {
  Solved out;
  const std::vector<ParamRef> refs = freeParameters(candidate);
  // Which column holds which parameter of which type.
  std::map<std::pair<int, int>, int> column_of;  // (type, param) -> column
  for (size_t j = 0; j < sys.column_param.size(); ++j) {
    const ParamRef& r = refs[sys.column_param[j]];
    const bool product = sys.column_partner[j] >= 0;
    column_of[{r.bond_type, product ? -kRestLength - 1 : r.param}] = static_cast<int>(j);
  }
  const Eigen::MatrixXd& inv = sel.inverse_scaled;  // the elimination's final solve
  const Eigen::VectorXd& scale = sel.scale;
  std::map<int, int> position;
  for (size_t i = 0; i < sel.active_columns.size(); ++i) position[sel.active_columns[i]] = static_cast<int>(i);
  const auto cov = [&](int ci, int cj) {
    const int pi = position.at(ci), pj = position.at(cj);
    return sigma2 * inv(pi, pj) * scale[pi] * scale[pj];
  };
  Model model = candidate;
  // Every solved value (base types, candidates, gravity) into the model.
  for (int j : sel.active_columns) {
    const int partner = sys.column_partner[j];
    const double value = partner >= 0 ? sel.theta[j] / sel.theta[partner] : sel.theta[j] + sys.column_offset[j];
    if (std::isfinite(value)) setParam(model, refs[sys.column_param[j]], value);
  }
  // Base types stay; a candidate type stays when its spring does.
  std::vector<uint8_t> keep_type(candidate.bond_types.size(), 0);
  for (int t = 0; t < first_candidate_type; ++t) keep_type[t] = 1;
  for (const Group& g : sel.groups) {
    if (g.bond_type < 0) {
      if (!g.active)
        for (int c = 0; c < 3; ++c) {
          Param& p = model.gravity_mps2[c];
          p = Param();
          p.present = true;
          p.has_value = true;
        }
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
    BondValues v = BondValues::Zero(), s = BondValues::Zero();
    uint8_t terms = 0;
    if (type.kind == BondKind::kViscosity) {
      const int cv = column_of.at({t, kViscosity});
      v[0] = sel.theta[cv];
      s[0] = std::sqrt(std::max(0.0, cov(cv, cv)));
      if (!(v[0] > 0.0)) out.bad_bonds.push_back(t);
      else type.param(kViscosity).value = v[0];
    } else {
      // A spring (k, L = kL / k, c) or a flexion (k, theta0 = k theta0 / k, c): the same algebra;
      // a rest length that is not free (the non-linear level) is known.
      const bool spring = type.kind == BondKind::kSpring;
      const ParamId rest_id = spring ? kRestLength : kRestAngle;
      const int ck = column_of.at({t, kStiffness});
      const double k = sel.theta[ck];
      s[0] = std::sqrt(std::max(0.0, cov(ck, ck)));
      double rest = type.param(rest_id).value;  // known, or set above (a linearised column)
      const auto linearized = column_of.find({t, rest_id});
      if (linearized != column_of.end() && position.count(linearized->second))
        s[1] = std::sqrt(std::max(0.0, cov(linearized->second, linearized->second)));
      const auto product = column_of.find({t, -kRestLength - 1});
      if (product != column_of.end()) {
        const int ckl = product->second;
        const double kl = sel.theta[ckl];
        rest = kl / k;
        const double dl_dkl = 1.0 / k, dl_dk = -kl / (k * k);
        s[1] = std::sqrt(std::max(0.0, dl_dkl * dl_dkl * cov(ckl, ckl) + dl_dk * dl_dk * cov(ck, ck) +
                                           2.0 * dl_dkl * dl_dk * cov(ck, ckl)));
      }
      v[0] = k;
      v[1] = rest;
      // The optional terms still active.
      const ParamId optional[3] = {kDamping, kStiffnessNl, kDampingNl};
      for (int o = 0; o < 3; ++o) {
        const auto column = column_of.find({t, optional[o]});
        if (column == column_of.end() || !position.count(column->second)) continue;
        if (optional[o] == kDamping && !dampers) continue;
        terms |= static_cast<uint8_t>(1u << o);
        v[2 + o] = sel.theta[column->second];
        s[2 + o] = std::sqrt(std::max(0.0, cov(column->second, column->second)));
        type.param(optional[o]).value = v[2 + o];
        if (optional[o] != kStiffnessNl && !(v[2 + o] > 0.0)) out.bad_terms.push_back({t, optional[o]});
      }
      const bool rest_ok = spring ? rest > 0.0 : (rest > 0.0 && rest <= kPi);
      if (!(k > 0.0) || !rest_ok) out.bad_bonds.push_back(t);
      type.param(kStiffness).value = k;
      type.param(rest_id).value = rest;
    }
    out.kept_types.push_back(t);
    out.value.push_back(v);
    out.sigma.push_back(s);
    out.terms.push_back(terms);
  }
  // Drop the removed candidate types and their bonds (base types stay, indices kept in order).
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
  out.model = std::move(pruned);
  return out;
}

/// Drops the kept bonds whose values came out non-physical and the non-physical optional terms
/// from `solved`, without solving again: the last pass, or one cut by the time limit, must not
/// hand on a negative stiffness. Returns whether anything was dropped.
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
    const ParamId optional[3] = {kDamping, kStiffnessNl, kDampingNl};
    for (const auto& term : solved->bad_terms) {
      if (term.first != candidate_type) continue;
      for (int o = 0; o < 3; ++o)
        if (optional[o] == term.second) {
          type.param(optional[o]) = Param();
          terms &= static_cast<uint8_t>(~(1u << o));
          value[2 + o] = 0.0;
        }
    }
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

/// Bonds of one kind whose values (k, L, c; k, theta0, c; c_v) agree within `sigmas` standard
/// deviations share a type (greedy, in order of stiffness). Returns the typed model (candidate
/// types renamed s00, s01, ... for springs, f00, ... for flexion, v00, ... for viscosity).
Model typeBonds(const Solved& solved, int first_candidate_type, double sigmas, int* types_out) {
  const Model& m = solved.model;
  const int kept = static_cast<int>(solved.kept_types.size());
  std::vector<int> order(kept);
  for (int i = 0; i < kept; ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return solved.value[a][0] < solved.value[b][0]; });
  struct Cluster {
    BondValues sum_w_v = BondValues::Zero(), sum_w = BondValues::Zero();
    uint8_t terms = 0;
    bool conditional = false;  ///< a spring with a threshold: a type of its own
    BondKind kind = BondKind::kSpring;
    int first_member = -1;
    BondValues mean() const { return sum_w_v.cwiseQuotient(sum_w); }
    BondValues sigma() const { return sum_w.cwiseInverse().cwiseSqrt(); }
  };
  std::vector<Cluster> clusters;
  std::vector<int> cluster_of(kept, -1);
  for (int idx : order) {
    const BondValues& v = solved.value[idx];
    BondValues s = solved.sigma[idx];
    // Round-off of the solve: values within 1e-6 (relative) are equal.
    for (int d = 0; d < 5; ++d) s[d] = std::max(s[d], 1e-6 * std::max(std::fabs(v[d]), 1e-12));
    int join = -1;
    for (size_t c = 0; c < clusters.size() && join < 0; ++c) {
      const BondValues mu = clusters[c].mean(), sc = clusters[c].sigma();
      const BondKind kind = m.bond_types[first_candidate_type + idx].kind;
      // One kind with the same optional terms; the values present agree.
      const uint8_t terms = solved.terms[idx];
      const BondType& member = m.bond_types[first_candidate_type + idx];
      const bool conditional = member.param(kMinDistance).present || member.param(kMaxDistance).present;
      bool agree = clusters[c].kind == kind && clusters[c].terms == terms && !conditional &&
                   !clusters[c].conditional;
      for (int d = 0; d < 5 && agree; ++d)
        if (d < 2 || (terms & (1u << (d - 2))))
          agree = std::fabs(v[d] - mu[d]) <= sigmas * std::sqrt(s[d] * s[d] + sc[d] * sc[d]);
      if (agree) join = static_cast<int>(c);
    }
    if (join < 0) {
      join = static_cast<int>(clusters.size());
      clusters.emplace_back();
      clusters.back().terms = solved.terms[idx];
      clusters.back().conditional = m.bond_types[first_candidate_type + idx].param(kMinDistance).present ||
                                    m.bond_types[first_candidate_type + idx].param(kMaxDistance).present;
      clusters.back().kind = m.bond_types[first_candidate_type + idx].kind;
      clusters.back().first_member = idx;
    }
    const BondValues w = s.cwiseProduct(s).cwiseInverse();
    clusters[join].sum_w_v += w.cwiseProduct(v);
    clusters[join].sum_w += w;
    cluster_of[idx] = join;
  }
  // The typed model: base types, then one type per cluster.
  Model typed = m;
  typed.bond_types.resize(first_candidate_type);
  char name[32];
  int of_kind[3] = {0, 0, 0};  // numbering per kind: s00.., f00.., v00..
  for (size_t c = 0; c < clusters.size(); ++c) {
    // The layout (which parameters are free) of the cluster's first member.
    BondType type = m.bond_types[first_candidate_type + clusters[c].first_member];
    const BondValues mu = clusters[c].mean();
    const char* prefix = "s";
    int* counter = &of_kind[0];
    switch (type.kind) {
      case BondKind::kSpring:
      case BondKind::kFlexion: {
        const bool spring = type.kind == BondKind::kSpring;
        if (!spring) {
          prefix = "f";
          counter = &of_kind[1];
        }
        type.param(kStiffness).value = mu[0];
        type.param(spring ? kRestLength : kRestAngle).value = mu[1];
        const ParamId optional[3] = {kDamping, kStiffnessNl, kDampingNl};
        for (int o = 0; o < 3; ++o)
          if (clusters[c].terms & (1u << o)) type.param(optional[o]).value = mu[2 + o];
        break;
      }
      case BondKind::kViscosity:
        prefix = "v";
        counter = &of_kind[2];
        type.param(kViscosity).value = mu[0];
        break;
      case BondKind::kMuscle:  // never a candidate: candidates are springs, flexions, drags
      case BondKind::kFloor:
        break;
    }
    std::snprintf(name, sizeof(name), "%s%02d", prefix, (*counter)++);
    type.name = name;
    typed.bond_types.push_back(type);
  }
  // The kept candidate types of `m` follow the base types in kept order.
  for (Bond& b : typed.bonds)
    if (b.type >= first_candidate_type)
      b.type = first_candidate_type + cluster_of[b.type - first_candidate_type];
  *types_out = static_cast<int>(clusters.size());
  return typed;
}

/// What a level kept, before typing: per candidate bond its kind, particles and which of its
/// parameters are present (equal strings: the same structure).
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

void heldOutErrors(const Model& model, const Trajectory& held, int held_start,
                   StructureCandidate* c) {
  try {
    const PredictionReport r = evaluatePredictions(model, held, {1, 5, 10}, 10.0, held_start);
    for (const PredictionError& row : r.rows)
      if (row.predictor == Predictor::kModel)
        for (int k = 0; k < 3; ++k)
          if (row.horizon == kHorizons[k]) c->held_out_rms_m[k] = row.rms_m;
    c->rollout_bounded = r.rollout_bounded;
  } catch (const InputError&) {
    for (double& e : c->held_out_rms_m) e = kNan;
  }
}

/// Pairs outside `have` that the residual of `model` (every value set) asks for: for each pair,
/// the part of the one-step residual a spring between them (tension k l - k L along the pair)
/// would explain, c^T G^-1 c over the frames where both are seen. Returns the pairs explaining
/// more than 20 ln(N) times the residual's mean square (a pair of parameters' BIC price with a
/// wide margin, so that noise adds nothing), the most first, at most `most`; none when the
/// residual's RMS is below `floor_rms_m` (nothing is missing).
/// Per frame, the weighted one-step residual (m a - F) h^2 / m of every free particle seen at
/// t-1, t and t+1 under `model` (every value set; raw differences); NaN elsewhere, and frames
/// 0 and T-1 empty.
std::vector<std::vector<Eigen::Vector3d>> oneStepResiduals(const Model& model, const Trajectory& data) {
  const int n = static_cast<int>(model.particles.size()), frames = data.numFrames();
  const double h = 1.0 / model.frame_rate_hz;
  Simulator simulator(model);
  State state;
  state.x_m.resize(n);
  state.v_mps.resize(n);
  std::vector<Eigen::Vector3d> force;
  std::vector<std::vector<Eigen::Vector3d>> residual(frames);
  for (int t = 1; t + 1 < frames; ++t) {
    std::vector<uint8_t> seen(n);
    for (int i = 0; i < n; ++i) {
      seen[i] = !data.isOccluded(t - 1, i) && !data.isOccluded(t, i) && !data.isOccluded(t + 1, i);
      state.x_m[i] = seen[i] ? data.position(t, i) : model.particles[i].position_m;
      state.v_mps[i] = seen[i] ? Eigen::Vector3d((data.position(t, i) - data.position(t - 1, i)) / h)
                               : Eigen::Vector3d::Zero();
      if (model.particles[i].fixed) state.v_mps[i] = model.particles[i].velocity_mps;
    }
    simulator.computeForces(state, &force);
    residual[t].assign(n, Eigen::Vector3d::Constant(kNan));
    for (int i = 0; i < n; ++i) {
      if (!seen[i] || model.particles[i].fixed) continue;
      const double m = model.particles[i].mass_kg;
      const Eigen::Vector3d a = (data.position(t + 1, i) - 2.0 * data.position(t, i) + data.position(t - 1, i)) / (h * h);
      residual[t][i] = h * h / m * (m * a - force[i]);
    }
  }
  return residual;
}

std::vector<std::pair<int, int>> missingPairs(const Model& model, const Trajectory& data,
                                              const std::set<std::pair<int, int>>& have,
                                              double floor_rms_m, int most) {
  const int n = static_cast<int>(model.particles.size()), frames = data.numFrames();
  const double h = 1.0 / model.frame_rate_hz;
  const std::vector<std::vector<Eigen::Vector3d>> residual = oneStepResiduals(model, data);
  double sum2 = 0.0;
  long rows = 0;
  for (const auto& frame : residual)
    for (const Eigen::Vector3d& r : frame)
      if (r.allFinite()) {
        sum2 += r.squaredNorm();
        rows += 3;
      }
  if (rows == 0 || std::sqrt(sum2 / rows) < floor_rms_m) return {};
  const double threshold_m2 = 20.0 * std::log(static_cast<double>(rows)) * sum2 / rows;
  std::vector<std::pair<double, std::pair<int, int>>> scored;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      if (have.count({a, b}) || (model.particles[a].fixed && model.particles[b].fixed)) continue;
      Eigen::Matrix2d g = Eigen::Matrix2d::Zero();
      Eigen::Vector2d c = Eigen::Vector2d::Zero();
      for (int t = 1; t + 1 < frames; ++t) {
        if (residual[t].empty()) continue;
        const Eigen::Vector3d d = data.position(t, b) - data.position(t, a);
        const double l = d.norm();
        if (!(l > 0.0) || data.isOccluded(t, a) || data.isOccluded(t, b)) continue;
        const Eigen::Vector3d u = d / l;
        // Tension f = k l - (k L): on a, +f u; on b, -f u (rows weighted h^2 / m).
        for (int side = 0; side < 2; ++side) {
          const int i = side == 0 ? a : b;
          if (model.particles[i].fixed || !residual[t][i].allFinite()) continue;
          const double w = (side == 0 ? 1.0 : -1.0) * h * h / model.particles[i].mass_kg;
          const double r = residual[t][i].dot(u);
          const Eigen::Vector2d f(w * l, -w);
          g += f * f.transpose();
          c += f * r;
        }
      }
      if (!(g.determinant() > 0.0)) continue;
      const double explained = c.dot(g.ldlt().solve(c));
      if (explained > threshold_m2) scored.push_back({-explained, {a, b}});
    }
  std::sort(scored.begin(), scored.end());
  std::vector<std::pair<int, int>> out;
  for (size_t k = 0; k < scored.size() && static_cast<int>(out.size()) < most; ++k)
    out.push_back(scored[k].second);
  return out;
}

}  // namespace

/// A kept spring made conditional: active only when its length is at least (`lower`) or at
/// most the threshold.
struct ConditionalChoice {
  int type = -1;
  bool lower = true;
  double threshold_m = 0.0;
  double gain_m2 = 0.0;  ///< the residual's fall when the bond is off beyond the threshold
};

/// For each candidate spring of `model` (types from `first_candidate_type`, one bond each, every
/// value set), the threshold whose switching the one-step residual asks for most: the bond's
/// force removed on the frames where it is shorter (or longer) than the threshold, the residual's
/// fall is a prefix (suffix) sum over the frames sorted by length. Returns those falling by more
/// than `min_gain_m2`, the most first.
std::vector<ConditionalChoice> conditionalCandidates(const Model& model, const Trajectory& data,
                                                     int first_candidate_type, double min_gain_m2) {
  const std::vector<std::vector<Eigen::Vector3d>> residual = oneStepResiduals(model, data);
  const double h = 1.0 / model.frame_rate_hz;
  std::vector<ConditionalChoice> out;
  for (const Bond& bond : model.bonds) {
    if (bond.type < first_candidate_type) continue;
    const BondType& type = model.bond_types[bond.type];
    if (type.kind != BondKind::kSpring || type.param(kMinDistance).present ||
        type.param(kMaxDistance).present)
      continue;
    SpringLaw law;  // unconditional (checked above)
    law.stiffness = type.value(kStiffness);
    law.rest_length = type.value(kRestLength);
    law.damping = type.value(kDamping);
    law.stiffness_nl = type.value(kStiffnessNl);
    law.damping_nl = type.value(kDampingNl);
    const int a = bond.particles[0], c = bond.particles[1];
    std::vector<std::pair<double, double>> rows;  // (length, residual change when off)
    for (int t = 1; t + 1 < data.numFrames(); ++t) {
      if (residual[t].empty() || data.isOccluded(t, a) || data.isOccluded(t, c) ||
          data.isOccluded(t - 1, a) || data.isOccluded(t - 1, c))
        continue;
      const Eigen::Vector3d xa = data.position(t, a), xc = data.position(t, c);
      const Eigen::Vector3d va = (xa - data.position(t - 1, a)) / h, vc = (xc - data.position(t - 1, c)) / h;
      Eigen::Vector3d fa = Eigen::Vector3d::Zero(), fc = Eigen::Vector3d::Zero();
      addSpringForce(law, xa, xc, va, vc, &fa, &fc);
      double change = 0.0;
      bool usable = false;
      for (int side = 0; side < 2; ++side) {
        const int i = side == 0 ? a : c;
        const Eigen::Vector3d& r = residual[t][i];
        if (!r.allFinite()) continue;
        usable = true;
        // r = (m a - F) h^2 / m: without the bond's force f on i, r + f h^2 / m.
        const Eigen::Vector3d off = r + (h * h / model.particles[i].mass_kg) * (side == 0 ? fa : fc);
        change += off.squaredNorm() - r.squaredNorm();
      }
      if (usable) rows.push_back({(xc - xa).norm(), change});
    }
    if (rows.size() < 4) continue;
    std::sort(rows.begin(), rows.end());
    ConditionalChoice best;
    best.type = bond.type;
    double prefix = 0.0, total = 0.0;
    for (const auto& row : rows) total += row.second;
    for (size_t k = 1; k < rows.size(); ++k) {
      prefix += rows[k - 1].second;  // frames [0, k) off: the bond shorter than the threshold
      const double threshold = 0.5 * (rows[k - 1].first + rows[k].first);
      if (-prefix > best.gain_m2) best = {bond.type, true, threshold, -prefix};
      const double suffix = total - prefix;  // frames [k, end) off: longer than the threshold
      if (-suffix > best.gain_m2) best = {bond.type, false, threshold, -suffix};
    }
    if (best.gain_m2 > min_gain_m2) out.push_back(best);
  }
  std::sort(out.begin(), out.end(),
            [](const ConditionalChoice& x, const ConditionalChoice& y) { return x.gain_m2 > y.gain_m2; });
  return out;
}

/// The held-out 10-frame error decides; within 2 % of the best, the criterion (then fewer
/// parameters) does.
int bestCandidate(const std::vector<StructureCandidate>& candidates) {
  double best_err = std::numeric_limits<double>::infinity();
  for (const StructureCandidate& c : candidates)
    if (std::isfinite(c.held_out_rms_m[2])) best_err = std::min(best_err, c.held_out_rms_m[2]);
  int chosen = -1;
  for (size_t i = 0; i < candidates.size(); ++i) {
    const StructureCandidate& c = candidates[i];
    const bool near = !std::isfinite(best_err) || (std::isfinite(c.held_out_rms_m[2]) &&
                                                   c.held_out_rms_m[2] <= 1.02 * best_err);
    if (!near) continue;
    if (chosen < 0 || c.parameters < candidates[chosen].parameters ||
        (c.parameters == candidates[chosen].parameters && c.bic < candidates[chosen].bic))
      chosen = static_cast<int>(i);
  }
  return chosen;
}

/// The non-linear level's candidate model: `linear` (the best linear level's kept bonds, one type
/// each) with the values of its least-squares equation-error fit, and a free cubic stiffness on
/// every candidate spring (a quadratic damping too where it has a damper), at 0.
Model nonlinearCandidates(Model linear, const Trajectory& fit, const EquationErrorOptions& ee,
                          int first_candidate_type) {
  const EquationErrorResult start = solveEquationError(linear, fit, ee);
  const std::vector<ParamRef> refs = freeParameters(linear);
  if (start.applicable)
    for (size_t k = 0; k < refs.size(); ++k)
      if (std::isfinite(start.values[k])) setParam(linear, refs[k], start.values[k]);
  for (size_t t = first_candidate_type; t < linear.bond_types.size(); ++t) {
    BondType& type = linear.bond_types[t];
    if (type.kind != BondKind::kSpring || !type.param(kStiffness).free) continue;
    type.param(kStiffnessNl) = freeParam(0.0);
    if (type.param(kDamping).free) type.param(kDampingNl) = freeParam(0.0);
  }
  return linear;
}

/// The least-squares solution of every column of `model`'s linearised equation error (rest
/// lengths beside cubic terms, equation_error.h), iterated from the model's values while the
/// linearised residual falls (Gauss-Newton; a step that raises it is undone); the values are
/// written into the model.
void convergeLinearized(Model* model, const Trajectory& fit, const EquationErrorOptions& ee) {
  const std::vector<ParamRef> refs = freeParameters(*model);
  double best_rss = std::numeric_limits<double>::infinity();
  Model before_step = *model;
  for (int iteration = 0; iteration < 30; ++iteration) {
    const EquationErrorSystem sys = buildEquationErrorSystem(*model, fit, ee);
    const bool finite = sys.reason.empty() && sys.ata.allFinite() && sys.atb.allFinite() &&
                        std::isfinite(sys.btb);
    std::vector<int> all;
    for (size_t j = 0; finite && j < sys.column_param.size(); ++j)
      if (sys.ata(j, j) > 0.0) all.push_back(static_cast<int>(j));
    NormalEquationsSolution solved;
    if (finite) solved = solveNormalEquations(sys.ata, sys.atb, sys.btb, all);
    const Eigen::VectorXd& theta = solved.theta;
    const double r = solved.trusted ? solved.rss : kNan;
    if (!solved.trusted || !(r < best_rss * (1.0 - 1e-6))) {
      // No progress from this point: back to the one it was reached from (iteration 0: the start).
      if (iteration > 0) *model = before_step;
      return;
    }
    best_rss = r;
    before_step = *model;
    for (int j : all) {
      const int partner = sys.column_partner[j];
      double value = partner >= 0 ? theta[j] / theta[partner] : theta[j] + sys.column_offset[j];
      if (!std::isfinite(value)) continue;
      const ParamRef& r_ref = refs[sys.column_param[j]];
      if (r_ref.bond_type >= 0 && r_ref.param == kRestLength && sys.column_offset[j] != 0.0) {
        // A step of at most 20 % of the rest length: a bond with next to no stiffness (a
        // candidate the data do not want) has next to no say on its length.
        const double before = sys.column_offset[j];
        value = std::min(std::max(value, 0.8 * before), 1.2 * before);
      }
      setParam(*model, r_ref, value);
    }
    if (r <= 1e-30 * std::max(sys.btb, 1e-300)) return;  // exact
  }
}

HeldOutSplit splitHeldOut(const Trajectory& data, double held_out_share, const std::string& who) {
  const int frames = data.numFrames();
  HeldOutSplit split;
  split.held_frames = std::max(15, static_cast<int>(std::lround(held_out_share * frames)));
  split.fit_frames = frames - split.held_frames;
  if (split.fit_frames < 20)
    throw InputError(who + ": " + std::to_string(frames) + " frames are too few (need at least " +
                     std::to_string(20 + split.held_frames) + ": 20 to fit, " +
                     std::to_string(split.held_frames) + " held out)");
  split.fit = sliceFrames(data, 0, split.fit_frames);
  split.held = data;
  split.held_start = split.fit_frames;
  return split;
}

StructureResult selectStructure(const Model& given, const Trajectory& data,
                                const StructureOptions& options) {
  // The data's rate when the model states none (a live window, a model of particles alone).
  Model model = given;
  if (!(model.frame_rate_hz > 0.0)) model.frame_rate_hz = data.frame_rate_hz;
  if (!(model.frame_rate_hz > 0.0))
    throw InputError("structure selection: no frame rate (neither the model nor the data state one)");
  const auto say = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  const Deadline deadline(options.max_wall_time_s);
  if (!model.interactions.empty())
    throw InputError("structure selection: the model has interactions (bonds found on the fly); "
                     "give the particles and fixed bonds only");
  // Pruning renumbers bonds, which a muscle's input list would not follow; and a muscle's
  // network is not linear, so the equation error this selection rests on cannot weigh it.
  for (const BondType& type : model.bond_types)
    if (bondKindInfo(type.kind).network)
      throw InputError("structure selection: the model has muscles (type '" + type.name +
                       "'); select the passive structure first, then add the muscles");
  const HeldOutSplit split = splitHeldOut(data, options.held_out_share, "structure selection");
  const int fit_frames = split.fit_frames, held_frames = split.held_frames;
  StructureResult result;
  result.fitted_frames = fit_frames;
  result.held_out_frames = held_frames;
  const Trajectory& fit = split.fit;
  const Trajectory& held = split.held;

  const std::vector<std::pair<int, int>> pairs = candidatePairs(model, fit, options);
  result.candidate_bonds = static_cast<int>(pairs.size());
  std::set<std::pair<int, int>> all_candidates(pairs.begin(), pairs.end());
  if (pairs.empty()) throw InputError("structure selection: no candidate pair of particles");
  say("structure: " + std::to_string(pairs.size()) + " candidate bonds among " +
      std::to_string(model.particles.size()) + " particles; " + std::to_string(fit_frames) +
      " frames fitted, " + std::to_string(held_frames) + " held out");

  // Model-free guesses on the held-out frames (NaN when no start there has every particle placed).
  for (auto& row : result.guess_rms_m)
    for (double& e : row) e = kNan;
  try {
    const PredictionReport r = evaluatePredictions(model, held, {1, 5, 10}, 0.0, split.held_start);
    for (const PredictionError& row : r.rows)
      for (int k = 0; k < 3; ++k)
        if (row.horizon == kHorizons[k] && row.predictor != Predictor::kModel)
          result.guess_rms_m[static_cast<int>(row.predictor) - 1][k] = row.rms_m;
  } catch (const InputError& e) {
    result.notes.push_back(std::string("no held-out prediction: ") + e.what());
  }

  // Raw differences (exact on noiseless data with one step per frame) unless the markers' noise
  // is estimated at 1 um or more (real captures: 10 um to 1 mm): then smoothed kinematics. (Not
  // the identifier's test of an exact one-step fit: with bonds still missing from the candidates
  // no fit is exact.)
  EquationErrorOptions ee;
  {
    const double noise_m = estimateMarkerNoise(fit);
    if (noise_m >= 1e-6) ee.smoothing_half_width = 4;
    char line[160];
    std::snprintf(line, sizeof(line), "structure: marker noise estimated %.3g m; equation error on %s kinematics",
                  noise_m, ee.smoothing_half_width > 0 ? "smoothed" : "raw");
    say(line);
  }

  const int first_candidate_type = static_cast<int>(model.bond_types.size());
  // Flexion candidates on near-collinear triples of the candidate pairs.
  std::vector<std::array<int, 3>> triples;
  if (options.try_flexion)
    triples = candidateTriples(model, fit, pairs, 4, options.flexion_min_angle_rad,
                               4 * static_cast<int>(model.particles.size()));
  // The levels, in rising complexity; each holds every candidate component of the ones before.
  struct Level {
    std::string name;
    bool dampers, flexion, viscosity;
    int nonlinear_on = -1;  ///< >= 0: the non-linear terms on that level's kept bonds
    int conditional_on = -1;  ///< >= 0: conditions on that level's kept springs
  };
  std::vector<Level> levels = {{"springs", false, false, false}};
  if (options.try_dampers) levels.push_back({"springs+dampers", true, false, false});
  if (!triples.empty()) levels.push_back({levels.back().name + "+flexion", options.try_dampers, true, false});
  if (options.try_viscosity)
    levels.push_back({levels.back().name + "+viscosity", options.try_dampers, !triples.empty(), true});
  say("structure: " + std::to_string(triples.size()) + " flexion candidate(s) on near-collinear triples; " +
      std::to_string(levels.size()) + " level(s) to try");
  std::vector<StructureCandidate> candidates;
  // A level's typed model refitted by the full identification on the fitted frames (rest
  // lengths of the non-linear level free again: the seeds are Gauss-Newton steps of the
  // linearised equation error from the values) and judged on the held-out frames.
  const auto refitAndJudge = [&](StructureCandidate* cand, bool nonlinear, bool conditional, int first_type) {
    for (size_t t = first_type; t < cand->model.bond_types.size(); ++t) {
      BondType& type = cand->model.bond_types[t];
      if (type.kind != BondKind::kSpring || !type.param(kStiffness).free) continue;
      if (nonlinear) type.param(kRestLength).free = true;
      // The thresholds held for the equation error are refined by the threshold search.
      for (ParamId id : {kMinDistance, kMaxDistance})
        if (conditional && type.param(id).present) type.param(id).free = true;
    }
    if (options.refit && freeParameters(cand->model).empty()) {
      say("structure: " + cand->name + ": no bond and no gravity kept: nothing to refit");
    } else if (options.refit && deadline.passed()) {
      say("structure: " + cand->name + ": not refitted (the time limit is spent); judged with the "
          "equation error's values");
    } else if (options.refit) {
      IdentifyOptions io = options.identify;
      io.cost = CostChoice::kShortTerm;  // ranking only: the final fit is the caller's
      io.generations = std::min(io.generations, options.refit_generations);
      io.estimate_std = false;
      if (deadline.limited())  // what is left of the selection's limit bounds the refit too
        io.max_wall_time_s = io.max_wall_time_s > 0.0 ? std::min(io.max_wall_time_s, deadline.remainingS())
                                                      : std::max(deadline.remainingS(), 1e-3);
      const IdentifyResult r = identifyModel(cand->model, fit, io);
      cand->model = r.model;
      cand->refit_cost_m2 = r.global_cost;
      char line[160];
      std::snprintf(line, sizeof(line), "structure: %s: refit %d generations (%s), %.1f s",
                    cand->name.c_str(), r.generations, identifyStopName(r.stop), r.wall_time_s);
      say(line);
    }
    cand->parameters = static_cast<int>(freeParameters(cand->model).size());
    heldOutErrors(cand->model, held, split.held_start, cand);
    char line[256];
    std::snprintf(line, sizeof(line),
                  "structure: %s: %d bonds, %d types, %d parameters; held-out RMS 1/5/10 frames "
                  "ahead %.3g / %.3g / %.3g mm",
                  cand->name.c_str(), cand->bonds, cand->bond_types, cand->parameters,
                  1e3 * cand->held_out_rms_m[0], 1e3 * cand->held_out_rms_m[1],
                  1e3 * cand->held_out_rms_m[2]);
    say(line);
  };
  std::vector<std::string> signatures;  // per level: the kept structure before typing
  std::vector<Model> untyped;           // per level: the kept bonds, one type each, values set
  std::vector<ConditionalChoice> conditional_choices;  // the conditional level's thresholds
  int conditional_rounds = 0;
  std::vector<double> base_sigma2;      // per level: its noise level (the criterion's sigma^2)
  std::vector<size_t> base_rows;        // ... and its equations
  const size_t cumulative_levels = levels.size();
  // Once the time limit is spent, no further level starts; a level under way is given up
  // unless it is the first (which ends on its elimination so far: something to choose).
  const auto stopByTime = [&](const std::string& where) {
    result.stopped_by_time = true;
    char line[200];
    std::snprintf(line, sizeof(line), "the time limit (%.3g s) stopped the selection %s after %zu "
                  "level(s) (%.1f s): the best level judged so far is chosen",
                  deadline.maxS(), where.c_str(), candidates.size(), deadline.elapsedS());
    say(std::string("structure: ") + line);
    result.notes.push_back(line);
  };
  for (size_t level_index = 0; level_index < levels.size(); ++level_index) {
    const Level level = levels[level_index];
    if (!candidates.empty() && deadline.passed()) {
      stopByTime("before " + level.name);
      break;
    }
    const bool dampers = level.dampers;
    const bool nonlinear = level.nonlinear_on >= 0;
    const bool conditional = level.conditional_on >= 0;
    StructureCandidate cand;
    cand.name = level.name;
    Model full = model;
    if (nonlinear) {
      // The non-linear level: the base level's kept bonds, values set.
      full = untyped[level.nonlinear_on];
    } else if (conditional) {
      // The conditional level: the base level's kept bonds, the chosen springs with a threshold
      // held at the scan's value (the masks are then known: linear unknowns again).
      full = untyped[level.conditional_on];
      for (const ConditionalChoice& choice : conditional_choices) {
        Param threshold;
        threshold.value = choice.threshold_m;
        threshold.present = threshold.has_value = true;
        full.bond_types[choice.type].param(choice.lower ? kMinDistance : kMaxDistance) = threshold;
      }
    } else {
      // Pairs the screening of an earlier level found start as candidates here.
      addCandidateBonds(&full, std::vector<std::pair<int, int>>(all_candidates.begin(), all_candidates.end()),
                        fit, dampers);
      if (level.flexion) addCandidateFlexions(&full, triples, fit, dampers);
      if (level.viscosity) addCandidateViscosities(&full);
    }
    // The non-linear level: rest lengths beside cubic terms enter linearised about the values.
    EquationErrorOptions level_ee = ee;
    level_ee.linearize_rest_length = nonlinear;
    if (nonlinear) full = nonlinearCandidates(full, fit, ee, first_candidate_type);
    Model kept_untyped;
    double level_sigma2 = 0.0;
    size_t level_rows = 0;
    std::string signature;
    std::vector<Group> groups;
    int screening_rounds = 0;
    bool given_up = false;  // the time limit ran out during this level (not the first)
    const auto giveUp = [&]() { return given_up = !candidates.empty() && deadline.passed(); };
    for (int pass = 0; pass < kMaxPasses; ++pass) {
      if (giveUp()) break;
      if (nonlinear) convergeLinearized(&full, fit, level_ee);
      const EquationErrorSystem sys = buildEquationErrorSystem(full, fit, level_ee);
      if (!sys.reason.empty())
        throw InputError("structure selection: the equation error does not apply: " + sys.reason);
      if (!sys.ata.allFinite() || !sys.atb.allFinite() || !std::isfinite(sys.btb))
        throw InputError("structure selection: " + cand.name + ": the equation error is not finite "
                         "(positions or values too large?)");
      const std::vector<ParamRef> refs = freeParameters(full);
      groups.clear();
      std::map<int, int> spring_group_of_type;
      std::vector<int> always;
      Group gravity;
      for (size_t j = 0; j < sys.column_param.size(); ++j) {
        const ParamRef& r = refs[sys.column_param[j]];
        if (r.bond_type < 0) {
          gravity.columns.push_back(static_cast<int>(j));
          continue;
        }
        if (r.bond_type < first_candidate_type) {
          always.push_back(static_cast<int>(j));
          continue;
        }
        if (r.param == kDamping || r.param == kStiffnessNl || r.param == kDampingNl) {
          Group g;
          g.columns = {static_cast<int>(j)};
          g.bond_type = r.bond_type;
          g.term = r.param;
          groups.push_back(g);
          continue;
        }
        auto it = spring_group_of_type.find(r.bond_type);
        if (it == spring_group_of_type.end()) {
          Group g;
          g.bond_type = r.bond_type;
          spring_group_of_type[r.bond_type] = static_cast<int>(groups.size());
          groups.push_back(g);
          it = spring_group_of_type.find(r.bond_type);
        }
        groups[it->second].columns.push_back(static_cast<int>(j));
      }
      for (size_t g = 0; g < groups.size(); ++g)
        if (groups[g].term >= 0)
          groups[spring_group_of_type.at(groups[g].bond_type)].children.push_back(static_cast<int>(g));
      if (!gravity.columns.empty()) groups.push_back(gravity);
      // Columns no row touches (a pair never seen) start inactive.
      for (Group& g : groups)
        for (int c : g.columns)
          if (!(sys.ata(c, c) > 0.0)) g.active = false;
      // The noise level of the full candidate model's residual, floored at round-off.
      std::vector<int> all = activeColumns(groups, always);
      const NormalEquationsSolution solved_all = solveActive(sys, all, false, cand.name);
      if (giveUp()) break;
      const Eigen::VectorXd& theta_all = solved_all.theta;
      const double rms_b = std::sqrt(sys.btb / std::max<size_t>(sys.rows, 1));
      // Round-off of the equation error (conditioning included) on exact data: 1e-6 of the rows' RMS,
      // 1e-10 m at least: no capture resolves a tenth of a nanometre, and a small motion's
      // rhs (micrometres) would otherwise put the floor below the solves' own round-off.
      const double floor2 = std::pow(std::max(1e-6 * rms_b, kRoundOffFloorM), 2);
      const double dof = std::max(1.0, static_cast<double>(sys.rows) - static_cast<double>(all.size()));
      const double sigma2 = std::max(rss(sys, theta_all) / dof, floor2);
      {
        char line[200];
        std::snprintf(line, sizeof(line), "structure: %s: %zu unknowns over %zu equations (residual "
                      "RMS %.3g m, rhs RMS %.3g m); eliminating", cand.name.c_str(), all.size(),
                      sys.rows, std::sqrt(rss(sys, theta_all) / std::max<size_t>(sys.rows, 1)), rms_b);
        say(line);
      }
      Selection sel = eliminate(sys, groups, always, sigma2, cand.name, deadline, candidates.empty(),
                                options.progress);
      if (giveUp()) break;
      Solved solved = describe(full, sys, sel, sigma2, first_candidate_type, dampers);
      const bool out_of_time = deadline.passed();  // the first level ends on what it has
      // Bonds the neighbourhoods missed (long ones): pairs the residual asks for become
      // candidates too, and the selection runs again (at most 4 rounds of 20). Before the
      // non-physical drops: a missing bond makes true ones come out wrong.
      if (!nonlinear && !conditional && screening_rounds < 4 && pass + 1 < kMaxPasses && !out_of_time) {
        std::set<std::pair<int, int>> have;
        for (const Bond& b : full.bonds)
          if (kindArity(full.bond_types[b.type].kind) == 2) have.insert(std::minmax(b.particles[0], b.particles[1]));
        const std::vector<std::pair<int, int>> more =
            missingPairs(solved.model, fit, have, 10.0 * std::sqrt(floor2), 20);
        ++screening_rounds;
        if (!more.empty()) {
          addCandidateBonds(&full, more, fit, dampers);
          all_candidates.insert(more.begin(), more.end());
          result.candidate_bonds = static_cast<int>(all_candidates.size());
          say("structure: " + cand.name + ": " + std::to_string(more.size()) +
              " pair(s) outside the neighbourhoods explain the residual: candidates too");
          continue;
        }
      }
      if ((!solved.bad_bonds.empty() || !solved.bad_terms.empty()) && pass + 1 < kMaxPasses && !out_of_time) {
        // Kept bonds that came out non-physical lose their spring (the bond goes) or their
        // damper; then the system is solved again. A type without a bond keeps no free value.
        std::set<int> bad(solved.bad_bonds.begin(), solved.bad_bonds.end());
        std::vector<Bond> bonds;
        for (const Bond& b : full.bonds)
          if (!bad.count(b.type)) bonds.push_back(b);
        full.bonds = bonds;
        for (int t : solved.bad_bonds) {
          BondType& type = full.bond_types[t];
          for (ParamId id : paramsOfKind(type.kind)) type.param(id) = Param();
        }
        for (const auto& bad : solved.bad_terms)
          full.bond_types[bad.first].param(static_cast<ParamId>(bad.second)) = Param();
        say("structure: " + cand.name + ": " + std::to_string(solved.bad_bonds.size()) +
            " non-physical bond(s) and " + std::to_string(solved.bad_terms.size()) +
            " damping term(s) dropped; solving again");
        continue;
      }
      if (!solved.bad_bonds.empty() || !solved.bad_terms.empty()) {
        const std::string why = out_of_time ? "the time limit cut this level" :
                                              "they remained after " + std::to_string(kMaxPasses) + " passes";
        const std::string line = cand.name + ": " + std::to_string(solved.bad_bonds.size()) +
                                 " non-physical bond(s) and " + std::to_string(solved.bad_terms.size()) +
                                 " damping term(s) dropped without solving again (" + why + ")";
        say("structure: " + line);
        result.notes.push_back(line);
        dropNonPhysical(&solved, first_candidate_type);
        sel.parameters = static_cast<int>(freeParameters(solved.model).size());  // rss: as solved
      }
      // Types: one per bond, or shared where the values agree; the criterion decides.
      const double untyped_bic = bic(sel.rss_m2, sys.rows, sel.parameters, floor2);
      int types = 0;
      Model typed = typeBonds(solved, first_candidate_type, options.type_sigmas, &types);
      // Types with no bond left (non-physical drops) do not exist in `solved.model`; typed too.
      // The typed model's joint fit can come out non-physical where each bond's own did not
      // (merged columns, worse conditioned): such a type is held at the values typing gave it
      // (the weighted mean of its bonds' own, physical values), the others solved again, and
      // it counts as free in the criterion (before: one such type dropped the whole typing,
      // silently, whatever the criterion said).
      std::vector<std::pair<int, ParamId>> held;
      const Model typed_start = typed;  // typing's values, before any fit moved them
      EquationErrorResult typed_fit;
      for (int round = 0;; ++round) {
        if (out_of_time) break;  // no typing: one type per bond
        if (nonlinear) convergeLinearized(&typed, fit, level_ee);
        typed_fit = solveEquationError(typed, fit, level_ee);
        if (!typed_fit.applicable || round == kMaxPasses) break;
        const std::vector<ParamRef> refs = freeParameters(typed);
        std::set<int> bad;
        for (size_t k = 0; k < refs.size(); ++k)
          if (!std::isfinite(typed_fit.values[k]) && refs[k].bond_type >= first_candidate_type)
            bad.insert(refs[k].bond_type);
        if (bad.empty()) break;
        for (int t : bad)
          for (ParamId id : paramsOfKind(typed.bond_types[t].kind))
            if (typed.bond_types[t].param(id).free) {
              typed.bond_types[t].param(id) = typed_start.bond_types[t].param(id);
              typed.bond_types[t].param(id).free = false;
              held.push_back({t, id});
            }
        say("structure: " + cand.name + ": " + std::to_string(bad.size()) +
            " type(s) non-physical in the typed fit: held at their bonds' mean values");
      }
      bool typed_usable = typed_fit.applicable;
      for (double v : typed_fit.values) typed_usable = typed_usable && std::isfinite(v);
      for (const auto& h : held)
        if (physicalOnlyPositive(h.second))
          typed_usable = typed_usable && typed.bond_types[h.first].param(h.second).value > 0.0;
      if (typed_usable) setValues(typed, freeParameters(typed), typed_fit.values);
      for (const auto& h : held) typed.bond_types[h.first].param(h.second).free = true;
      const int typed_params = static_cast<int>(freeParameters(typed).size());
      Model chosen = solved.model;
      double fit_rss = sel.rss_m2;
      int params = sel.parameters;
      double chosen_bic = untyped_bic;
      if (typed_fit.applicable) {
        const double typed_rss = typed_fit.residual_rms_m * typed_fit.residual_rms_m * typed_fit.rows;
        const double typed_bic = bic(typed_rss, typed_fit.rows, typed_params, floor2);
        {
          char line[240];
          std::snprintf(line, sizeof(line), "structure: %s: %d bonds in %d types: residual RMS %.3g m "
                        "(one type per bond: %.3g m), BIC %.6g against %.6g", cand.name.c_str(),
                        static_cast<int>(typed.bonds.size()), types,
                        typed_fit.residual_rms_m, std::sqrt(sel.rss_m2 / std::max<size_t>(sys.rows, 1)),
                        typed_bic, untyped_bic);
          say(line);
        }
        if (typed_bic <= untyped_bic) {
          if (typed_usable) {
            chosen = typed;
            fit_rss = typed_rss;
            params = typed_params;
            chosen_bic = typed_bic;
          } else {
            const std::string why = "the criterion preferred shared types, but the typed fit "
                                    "stayed non-physical or undetermined: one type per bond kept";
            say("structure: " + cand.name + ": " + why);
            result.notes.push_back(cand.name + ": " + why);
          }
        }
      }
      cand.model = chosen;
      cand.bonds = static_cast<int>(chosen.bonds.size());
      cand.bond_types = static_cast<int>(chosen.bond_types.size());
      cand.parameters = params;
      cand.fit_rms_m = std::sqrt(fit_rss / std::max<size_t>(sys.rows, 1));
      cand.bic = chosen_bic;
      signature = structureSignature(solved.model, first_candidate_type);
      kept_untyped = solved.model;
      level_sigma2 = sigma2;
      level_rows = sys.rows;
      break;
    }
    if (given_up) {
      stopByTime("during " + cand.name);
      break;
    }
    untyped.push_back(kept_untyped);
    base_sigma2.push_back(level_sigma2);
    base_rows.push_back(level_rows);
    // A level that kept none of its new components has an earlier level's structure: not
    // refitted nor judged again (its figures are that level's).
    const size_t same = std::find(signatures.begin(), signatures.end(), signature) - signatures.begin();
    signatures.push_back(signature);
    if (same + 1 < signatures.size()) {
      const StructureCandidate& earlier = candidates[same];
      const std::string name = cand.name;
      cand = earlier;
      cand.name = name;
      cand.same_as = earlier.same_as.empty() ? earlier.name : earlier.same_as;
      say("structure: " + name + ": none of its new components kept; the structure of " + cand.same_as);
      candidates.push_back(std::move(cand));
      untyped.back() = untyped[same];
    } else {
      refitAndJudge(&cand, nonlinear, conditional, first_candidate_type);
      candidates.push_back(std::move(cand));
    }
    // After the cumulative levels and the non-linear one: conditions on the best cumulative
    // level's springs, where the one-step residual asks for a switch; then again on that
    // conditional level's result while the residual asks for more (at most 4 rounds: a wrong
    // condition on one bond biases its neighbours' fits, hiding theirs at first).
    const bool first_round = level_index + 1 == cumulative_levels + (options.try_nonlinear ? 1 : 0);
    const bool next_round = conditional && ++conditional_rounds < 4 &&
                            candidates.back().same_as.empty();
    if ((first_round || next_round) && options.try_conditional) {
      int base = static_cast<int>(level_index);
      if (first_round) {
        std::vector<StructureCandidate> linear(candidates.begin(), candidates.begin() + cumulative_levels);
        base = bestCandidate(linear);
        if (!candidates[base].same_as.empty())
          base = static_cast<int>(std::find_if(candidates.begin(), candidates.end(),
                                               [&](const StructureCandidate& c) { return c.name == candidates[base].same_as; }) -
                                  candidates.begin());
      }
      const double price_m2 = base_sigma2[base] * std::log(static_cast<double>(std::max<size_t>(base_rows[base], 2)));
      conditional_choices = conditionalCandidates(untyped[base], fit, first_candidate_type, 20.0 * price_m2);
      say("structure: " + std::to_string(conditional_choices.size()) + " spring(s) of " + candidates[base].name +
          " whose residual asks for a switching condition");
      if (!conditional_choices.empty()) {
        Level next{first_round ? candidates[base].name + "+conditional" : candidates[base].name,
                   levels[base].dampers, levels[base].flexion, levels[base].viscosity};
        if (!first_round) next.name += "+";
        next.conditional_on = base;
        levels.push_back(next);
      }
    }
    // After the cumulative levels: the non-linear terms on the best of them.
    if (level_index + 1 == cumulative_levels && options.try_nonlinear) {
      const int best = bestCandidate(candidates);
      const int base = candidates[best].same_as.empty()
                           ? best : static_cast<int>(std::find_if(candidates.begin(), candidates.end(),
                               [&](const StructureCandidate& c) { return c.name == candidates[best].same_as; }) -
                                                     candidates.begin());
      levels.push_back({candidates[base].name + "+nonlinear", levels[base].dampers, levels[base].flexion,
                        levels[base].viscosity, base});
    }
  }
  const int chosen = bestCandidate(candidates);
  candidates[chosen].chosen = true;
  for (StructureCandidate& c : candidates) c.model.frame_rate_hz = given.frame_rate_hz;
  result.model = candidates[chosen].model;
  result.candidates = std::move(candidates);
  return result;
}

StructureScore scoreStructure(const Model& truth, const Model& chosen) {
  // Bonds by their particles' names: a pair sorted, a flexion as (vertex, sorted ends).
  const auto key = [](const Model& m, const Bond& b) {
    const BondType& type = m.bond_types[b.type];
    std::string a = m.particles[b.particles[0]].name;
    std::string c = kindArity(type.kind) >= 2 ? m.particles[b.particles[kindArity(type.kind) - 1]].name : "";
    if (c < a) std::swap(a, c);
    const std::string v = kindArity(type.kind) == 3 ? m.particles[b.particles[1]].name : "";
    return std::string(kindName(type.kind)) + "|" + v + "|" + a + "|" + c;
  };
  std::map<std::string, const BondType*> want[2], got[2];  // [0] pairs, [1] flexions
  StructureScore s;
  for (const Bond& b : truth.bonds) {
    const BondKind kind = truth.bond_types[b.type].kind;
    if (kind == BondKind::kSpring || kind == BondKind::kFlexion)
      want[kind == BondKind::kFlexion ? 1 : 0][key(truth, b)] = &truth.bond_types[b.type];
  }
  for (const Bond& b : chosen.bonds) {
    const BondKind kind = chosen.bond_types[b.type].kind;
    if (kind == BondKind::kSpring || kind == BondKind::kFlexion)
      got[kind == BondKind::kFlexion ? 1 : 0][key(chosen, b)] = &chosen.bond_types[b.type];
    if (kind == BondKind::kViscosity) ++s.viscosity_bonds;
  }
  double* precision[2] = {&s.precision, &s.flexion_precision};
  double* recall[2] = {&s.recall, &s.flexion_recall};
  double* f1[2] = {&s.f1, &s.flexion_f1};
  for (int k = 0; k < 2; ++k) {
    if (k == 1 && want[k].empty() && got[k].empty()) continue;  // no flexion anywhere: 1
    int hit = 0;
    for (const auto& g : got[k]) hit += want[k].count(g.first) ? 1 : 0;
    *precision[k] = got[k].empty() ? 0.0 : static_cast<double>(hit) / got[k].size();
    *recall[k] = want[k].empty() ? 0.0 : static_cast<double>(hit) / want[k].size();
    *f1[k] = *precision[k] + *recall[k] > 0.0
                 ? 2.0 * *precision[k] * *recall[k] / (*precision[k] + *recall[k]) : 0.0;
  }
  s.types = static_cast<int>(chosen.bond_types.size());
  s.damped_everywhere = s.damped_nowhere = s.cubic_everywhere = s.cubic_nowhere = true;
  for (const BondType& t : chosen.bond_types) {
    if (t.kind == BondKind::kViscosity) continue;
    const bool damped = t.value(kDamping) != 0.0;
    s.damped_everywhere = s.damped_everywhere && damped;
    s.damped_nowhere = s.damped_nowhere && !damped;
    if (t.kind != BondKind::kSpring) continue;
    const bool cubic = t.value(kStiffnessNl) != 0.0;
    s.cubic_everywhere = s.cubic_everywhere && cubic;
    s.cubic_nowhere = s.cubic_nowhere && !cubic;
  }
  for (int k = 0; k < 2; ++k)
    for (const auto& w : want[k]) {
      const auto g = got[k].find(w.first);
      if (g == got[k].end()) continue;
      for (ParamId id : {kStiffness, k == 1 ? kRestAngle : kRestLength, kDamping, kStiffnessNl, kDampingNl}) {
        const double truth_value = w.second->value(id);
        if (truth_value == 0.0) continue;
        s.max_relative_error = std::max(
            s.max_relative_error, std::fabs(g->second->value(id) - truth_value) / std::fabs(truth_value));
      }
    }
  return s;
}

std::string formatStructureReport(const StructureResult& r) {
  std::ostringstream out;
  char line[320];
  std::snprintf(line, sizeof(line),
                "structure selection: %d candidate bonds; %d frames fitted, %d held out\n",
                r.candidate_bonds, r.fitted_frames, r.held_out_frames);
  out << line;
  std::snprintf(line, sizeof(line), "%-34s %6s %6s %6s %12s %12s %12s %10s %10s %10s %8s %s\n",
                "candidate", "bonds", "types", "params", "fit_rms_m", "bic", "refit_m2",
                "held1_mm", "held5_mm", "held10_mm", "bounded", "");
  out << line;
  for (const StructureCandidate& c : r.candidates) {
    std::snprintf(line, sizeof(line),
                  "%-34s %6d %6d %6d %12.4g %12.6g %12.4g %10.4g %10.4g %10.4g %8s %s%s\n",
                  c.name.c_str(), c.bonds, c.bond_types, c.parameters, c.fit_rms_m, c.bic,
                  c.refit_cost_m2, 1e3 * c.held_out_rms_m[0], 1e3 * c.held_out_rms_m[1],
                  1e3 * c.held_out_rms_m[2], c.rollout_bounded ? "yes" : "no",
                  c.chosen ? "<- chosen" : "",
                  c.same_as.empty() ? "" : ("(= " + c.same_as + ")").c_str());
    out << line;
  }
  const char* guesses[3] = {"constant_velocity", "constant_acceleration", "gravity_only"};
  for (int g = 0; g < 3; ++g) {
    std::snprintf(line, sizeof(line), "%-34s %6s %6s %6s %12s %12s %12s %10.4g %10.4g %10.4g\n",
                  guesses[g], "-", "-", "0", "-", "-", "-", 1e3 * r.guess_rms_m[g][0],
                  1e3 * r.guess_rms_m[g][1], 1e3 * r.guess_rms_m[g][2]);
    out << line;
  }
  for (const std::string& n : r.notes) out << "note: " << n << "\n";
  return out.str();
}

std::string structureReportCsv(const StructureResult& r) {
  std::ostringstream out;
  out << "name,bonds,bond_types,parameters,fit_rms_m,bic,refit_cost_m2,held_out_rms_1_m,"
         "held_out_rms_5_m,held_out_rms_10_m,rollout_bounded,chosen,same_as\n";
  char line[400];
  for (const StructureCandidate& c : r.candidates) {
    std::snprintf(line, sizeof(line), "%s,%d,%d,%d,%.6g,%.9g,%.6g,%.6g,%.6g,%.6g,%d,%d,%s\n",
                  c.name.c_str(), c.bonds, c.bond_types, c.parameters, c.fit_rms_m, c.bic,
                  c.refit_cost_m2, c.held_out_rms_m[0], c.held_out_rms_m[1], c.held_out_rms_m[2],
                  c.rollout_bounded ? 1 : 0, c.chosen ? 1 : 0, c.same_as.c_str());
    out << line;
  }
  const char* guesses[3] = {"constant_velocity", "constant_acceleration", "gravity_only"};
  for (int g = 0; g < 3; ++g) {
    std::snprintf(line, sizeof(line), "%s,,,0,,,,%.6g,%.6g,%.6g,,0,\n", guesses[g],
                  r.guess_rms_m[g][0], r.guess_rms_m[g][1], r.guess_rms_m[g][2]);
    out << line;
  }
  return out.str();
}

}  // namespace mme

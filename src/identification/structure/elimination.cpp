// Grouped backward elimination on the equation error's normal equations (elimination.h): the
// grouping of a level's columns into removable units, the incremental solve the elimination
// downdates, and the elimination loop itself.
#include "elimination.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <utility>

#include "motion_model_estimation/core/error.h"

namespace mme {
namespace structure {

namespace {

/// The active columns' solve during the elimination: the scaled inverse of their normal
/// equations and the scaled solution (theta = scale .* theta_s), solved from scratch or
/// downdated when columns go. The inverse keeps the size of its last solve from scratch: a
/// removed column's row and column are zeroed in place (the downdate leaves them zero up to
/// round-off) instead of the kept block being copied out on every removal, which on a level of a
/// thousand unknowns cost more than the downdate itself.
class ActiveSolve {
 public:
  ActiveSolve(const EquationErrorSystem& sys, const std::vector<int>& always, const std::string& who)
      : sys_(sys), always_(always), who_(who), position_(sys.atb.size(), -1) {}

  /// Solves the active groups' columns from scratch.
  void resolve(const std::vector<Group>& groups) {
    const std::vector<int> cols = activeColumns(groups, always_);
    adopt(cols, solveActive(sys_, cols, true, who_));
  }

  /// Takes `solved` (solveActive's of the columns `cols`, with its inverse) as the solve from
  /// scratch.
  void adopt(const std::vector<int>& cols, NormalEquationsSolution solved) {
    cols_ = cols;
    const Eigen::VectorXd& full = solved.theta;
    inv_ = std::move(solved.inverse_scaled);
    scale_ = std::move(solved.scale);
    theta_s_.resize(cols_.size());
    std::fill(position_.begin(), position_.end(), -1);
    for (size_t i = 0; i < cols_.size(); ++i) {
      position_[cols_[i]] = static_cast<int>(i);
      theta_s_[i] = scale_[i] > 0.0 ? full[cols_[i]] / scale_[i] : 0.0;
    }
    live_ = cols_.size();
    since_solve_ = 0;
  }

  /// Downdates since the last solve from scratch.
  int downdatesSinceSolve() const { return since_solve_; }

  /// The positions of a unit's columns (a spring with its active damper).
  std::vector<int> unitOf(const std::vector<Group>& groups, int g) const {
    std::vector<int> unit;
    for (int c : groups[g].columns) unit.push_back(positionOf(c));
    for (int child : groups[g].children)
      if (groups[child].active)
        for (int c : groups[child].columns) unit.push_back(positionOf(c));
    return unit;
  }

  /// The positions of several units' columns, each once: a bond's unit holds its active
  /// optional terms, which are units of their own too (a repeated column made the block
  /// singular and was not removed by the downdate).
  std::vector<int> columnsOf(const std::vector<Group>& groups, const std::vector<int>& units) const {
    std::vector<int> r;
    for (int g : units) {
      const std::vector<int> unit = unitOf(groups, g);
      r.insert(r.end(), unit.begin(), unit.end());
    }
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
    return r;
  }

  /// The residual's rise when the columns at `r` go: theta_R^T inv_RR^-1 theta_R.
  double rise(const std::vector<int>& r) const {
    const int u = static_cast<int>(r.size());
    Eigen::MatrixXd block(u, u);
    Eigen::VectorXd t(u);
    for (int i = 0; i < u; ++i) {
      t[i] = theta_s_[r[i]];
      for (int j = 0; j < u; ++j) block(i, j) = inv_(r[i], r[j]);
    }
    // The block of a positive-definite inverse is positive definite: a Cholesky (LDLT) solves
    // it much faster than an orthogonal decomposition, which matters for the joint rise of
    // a thousand cheap units; the decomposition stays the fallback when round-off breaks it.
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(block);
    if (ldlt.info() == Eigen::Success && ldlt.isPositive() && (ldlt.vectorD().array() > 0.0).all())
      return t.dot(ldlt.solve(t));
    return t.dot(block.completeOrthogonalDecomposition().solve(t));
  }

  /// Removes the columns at positions `r` from the solve (downdate): theta_K -= inv_KR
  /// inv_RR^-1 theta_R, inv_KK -= inv_KR inv_RR^-1 inv_RK, in place; R's rows and columns are
  /// then zeroed and no longer live.
  void drop(const std::vector<int>& r) {
    const int u = static_cast<int>(r.size()), m = static_cast<int>(inv_.rows());
    if (u == 0) return;
    Eigen::MatrixXd rr(u, u), kr(m, u);
    Eigen::VectorXd tr(u);
    for (int j = 0; j < u; ++j) {
      tr[j] = theta_s_[r[j]];
      kr.col(j) = inv_.col(r[j]);
      for (int i = 0; i < u; ++i) rr(i, j) = inv_(r[i], r[j]);
    }
    if (static_cast<size_t>(u) < live_) {  // (every column going leaves nothing to downdate)
      const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> rr_cod(rr);
      const Eigen::MatrixXd w = rr_cod.solve(kr.transpose());  // inv_RR^-1 inv_RK
      theta_s_.noalias() -= kr * rr_cod.solve(tr);
      inv_.noalias() -= kr * w;
    }
    for (int p : r) {
      inv_.row(p).setZero();
      inv_.col(p).setZero();
      theta_s_[p] = 0.0;
      position_[cols_[p]] = -1;
    }
    live_ -= static_cast<size_t>(u);
    ++since_solve_;
  }

  /// The selection this solve describes (`groups` as they stand), `cut` as given. Called right
  /// after a solve from scratch (every position live).
  Selection selection(std::vector<Group> groups, bool cut) const {
    Selection s;
    s.groups = std::move(groups);
    s.theta = Eigen::VectorXd::Zero(sys_.atb.size());
    for (size_t i = 0; i < cols_.size(); ++i) s.theta[cols_[i]] = scale_[i] * theta_s_[i];
    s.rss_m2 = rss(sys_, s.theta);
    s.parameters = static_cast<int>(cols_.size());
    s.active_columns = cols_;
    s.inverse_scaled = inv_;
    s.scale = scale_;
    s.cut = cut;
    return s;
  }

  size_t unknowns() const { return live_; }

 private:
  int positionOf(int column) const {
    const int p = position_[column];
    if (p < 0) throw std::logic_error("structure selection: a removed column was asked for");
    return p;
  }

  const EquationErrorSystem& sys_;
  const std::vector<int>& always_;
  const std::string& who_;
  std::vector<int> cols_;        ///< the columns of the last solve from scratch
  Eigen::MatrixXd inv_;          ///< over cols_; removed columns' rows and columns zero
  Eigen::VectorXd scale_, theta_s_;
  std::vector<int> position_;    ///< per column of the system: its position in cols_, -1 if not live
  size_t live_ = 0;
  int since_solve_ = 0;
};

/// The scan of one elimination step: the cheapest unit to remove (its rise over its price) and
/// every unit far below its price.
struct Cheapest {
  double best_ratio = std::numeric_limits<double>::infinity();
  int best = -1;
  std::vector<int> cheap;
};

/// Scans the active units; sets `*cut` when the time limit passes during the scan (read every
/// 64 groups: a scan of a large level takes seconds).
Cheapest scanUnits(const ActiveSolve& solve, const std::vector<Group>& groups,
                   double price_per_param, const Deadline& deadline, bool* cut) {
  Cheapest found;
  for (size_t g = 0; g < groups.size() && !*cut; ++g) {
    if (g % 64 == 63 && deadline.passed()) *cut = true;
    if (!groups[g].active || groups[g].columns.empty()) continue;
    const std::vector<int> unit = solve.unitOf(groups, static_cast<int>(g));
    const double ratio = solve.rise(unit) / (unit.size() * price_per_param);
    if (ratio < 1e-3) found.cheap.push_back(static_cast<int>(g));
    if (ratio < found.best_ratio) {
      found.best_ratio = ratio;
      found.best = static_cast<int>(g);
    }
  }
  return found;
}

/// The units to remove in this step: the cheap ones together when their joint rise is cheap
/// too (collinear units can each look free while together they are not); else the cheapest
/// alone.
std::vector<int> removalBatch(const ActiveSolve& solve, const std::vector<Group>& groups,
                              const Cheapest& found, double price_per_param) {
  std::vector<int> batch = {found.best};
  if (found.cheap.size() > 1) {
    const std::vector<int> r = solve.columnsOf(groups, found.cheap);
    if (solve.rise(r) < 1e-2 * r.size() * price_per_param) batch = found.cheap;
  }
  return batch;
}

/// Marks the units of `batch` and their optional terms inactive.
void deactivate(std::vector<Group>* groups, const std::vector<int>& batch) {
  for (int g : batch) {
    (*groups)[g].active = false;
    for (int child : (*groups)[g].children) (*groups)[child].active = false;
  }
}

Selection cutSelection() {
  Selection s;
  s.cut = true;
  return s;
}

}  // namespace

std::vector<Group> groupColumns(const EquationErrorSystem& sys, const std::vector<ParamRef>& refs,
                                int first_candidate_type, std::vector<int>* always) {
  std::vector<Group> groups;
  std::map<int, int> spring_group_of_type;
  Group gravity;
  for (size_t j = 0; j < sys.column_param.size(); ++j) {
    const ParamRef& r = refs[sys.column_param[j]];
    if (r.bond_type < 0) {
      gravity.columns.push_back(static_cast<int>(j));
      continue;
    }
    if (r.bond_type < first_candidate_type) {
      always->push_back(static_cast<int>(j));
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
  return groups;
}

std::vector<int> activeColumns(const std::vector<Group>& groups, const std::vector<int>& always) {
  std::vector<int> cols = always;
  for (const Group& g : groups)
    if (g.active) cols.insert(cols.end(), g.columns.begin(), g.columns.end());
  std::sort(cols.begin(), cols.end());
  return cols;
}

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

double bic(double rss_m2, size_t rows, int parameters, double sigma2_floor) {
  const double n = static_cast<double>(std::max<size_t>(rows, 1));
  const double r = std::max(rss_m2, n * sigma2_floor);
  return n * std::log(r / n) + parameters * std::log(n);
}

Selection eliminate(const EquationErrorSystem& sys, std::vector<Group> groups,
                    const std::vector<int>& always, double sigma2, const std::string& who,
                    const Deadline& deadline, bool finish_when_cut,
                    const std::function<void(const std::string&)>& progress,
                    NormalEquationsSolution* first_solve) {
  const double price_per_param = sigma2 * std::log(static_cast<double>(std::max<size_t>(sys.rows, 2)));
  if (deadline.passed() && !finish_when_cut) return cutSelection();  // before the first solve
  ActiveSolve solve(sys, always, who);
  if (first_solve) solve.adopt(activeColumns(groups, always), std::move(*first_solve));
  else solve.resolve(groups);
  int removed = 0;
  bool cut = false;
  for (;;) {
    if (deadline.passed()) {
      cut = true;
      break;
    }
    if (solve.downdatesSinceSolve() >= 25) solve.resolve(groups);
    const Cheapest found = scanUnits(solve, groups, price_per_param, deadline, &cut);
    if (cut || found.best < 0 || !(found.best_ratio < 1.0)) break;
    const std::vector<int> batch = removalBatch(solve, groups, found, price_per_param);
    if (deadline.passed()) {  // before the downdate, which costs as much as a solve
      cut = true;
      break;
    }
    const std::vector<int> r = solve.columnsOf(groups, batch);
    deactivate(&groups, batch);
    solve.drop(r);
    removed += static_cast<int>(batch.size());
  }
  if (cut && !finish_when_cut) return cutSelection();  // the caller gives the level up
  // The final solve from scratch (none needed when nothing was downdated since the last one:
  // it would give the same numbers).
  if (solve.downdatesSinceSolve() > 0) solve.resolve(groups);
  const size_t unknowns = solve.unknowns();
  Selection s = solve.selection(std::move(groups), cut);
  if (progress) progress("  elimination: " + std::to_string(removed) + " unit(s) removed, " +
                         std::to_string(unknowns) + " unknowns left" +
                         (cut ? " (cut by the time limit)" : ""));
  return s;
}

}  // namespace structure
}  // namespace mme

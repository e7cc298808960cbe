// The linear system of structure selection and its thinning. A level's equation error is
// linear in its candidates' parameters (k, k L, c, k theta0, c_v, gravity), so choosing which
// candidates stay is a subset selection on normal equations: grouped backward elimination
// priced by the Bayesian information criterion, with the solve kept as an inverse and
// downdated per removal because a level may hold hundreds of units. The groups say what
// goes together (a bond with its optional terms), the criterion says when to stop.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"
#include "motion_model_estimation/identification/estimators/normal_equations.h"
#include "deadline.h"

namespace mme {
namespace structure {

/// A removable unit: a bond (its spring, flexion or drag, with its children), one of a bond's
/// optional terms alone (damping, cubic stiffness, quadratic damping), or gravity.
struct Group {
  std::vector<int> columns;
  int bond_type = -1;     ///< -1: gravity
  int term = -1;          ///< an optional term's ParamId (kDamping, ...); -1: the bond itself
  std::vector<int> children;  ///< the optional terms' groups, which go with the bond
  bool active = true;
};

/// What the elimination kept, and its final solve.
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

/// The groups of `sys`'s columns (`refs`: freeParameters of the model it was built from): one
/// per candidate bond (types from `first_candidate_type`), one per optional term (a child of its
/// bond's), gravity last; the given model's columns go to `always` (never removed). Columns no
/// row touches start inactive.
std::vector<Group> groupColumns(const EquationErrorSystem& sys, const std::vector<ParamRef>& refs,
                                int first_candidate_type, std::vector<int>* always);

/// The columns of the active groups and `always`, sorted.
std::vector<int> activeColumns(const std::vector<Group>& groups, const std::vector<int>& always);

/// Solves the columns in `active` of the normal equations (normal_equations.h); the others 0.
/// Throws InputError naming `who` when the system is not finite or no solve can be trusted.
NormalEquationsSolution solveActive(const EquationErrorSystem& sys, const std::vector<int>& active,
                                    bool want_inverse, const std::string& who);

/// The residual sum of squares of `theta` on `sys` (floored at 0 against round-off).
double rss(const EquationErrorSystem& sys, const Eigen::VectorXd& theta);

/// BIC of a least-squares fit: N ln(RSS / N) + P ln N, RSS floored at N sigma_floor^2.
double bic(double rss_m2, size_t rows, int parameters, double sigma2_floor);

/// Grouped backward elimination with the BIC's price per parameter, sigma2 * ln(N). The solve
/// is kept as the (scaled) inverse of the active normal equations and downdated when a unit
/// goes (theta_K -= inv_KR inv_RR^-1 theta_R, inv_KK -= inv_KR inv_RR^-1 inv_RK, in place:
/// O(n^2) per removal, no copy); it is recomputed from scratch every 25 removals against drift
/// and once at the end (unless nothing was downdated since). The time limit stops the removals;
/// the selection so far is then solved again unless `finish_when_cut` is false (the caller gives
/// the level up and reads only `cut`). `first_solve`, when given, is solveActive's solve of the
/// active groups' columns with its inverse (the caller's, taken over: not solved twice).
Selection eliminate(const EquationErrorSystem& sys, std::vector<Group> groups,
                    const std::vector<int>& always, double sigma2, const std::string& who,
                    const Deadline& deadline, bool finish_when_cut,
                    const std::function<void(const std::string&)>& progress,
                    NormalEquationsSolution* first_solve = nullptr);

}  // namespace structure
}  // namespace mme

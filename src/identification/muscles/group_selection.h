// Grouped sparsity for the sensor muscles: which muscles and sensors the data support. A muscle
// is the group of its unknowns, a sensor the group of every unknown that reads it (its
// elongation's and its speed's weight in every muscle). Groups are removed by backward
// elimination on the normal equations, priced as structure selection prices its units
// (docs/structure_selection.md): a removal is taken while the residual's rise stays below the
// Bayesian information criterion's price of the parameters it removes.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "muscle_least_squares.h"

namespace mme::sensor_muscles {

/// The muscles and sensors a fit drops (empty vectors: none).
struct GroupSelection {
  std::vector<char> muscle_dropped, sensor_dropped;
  int parameters = 0;  ///< unknowns left free (not dropped, not held at 0 by the layout)
  int groups_dropped() const;
  bool dropsMuscle(int m) const { return !muscle_dropped.empty() && muscle_dropped[m]; }
  bool dropsSensor(int s) const { return !sensor_dropped.empty() && sensor_dropped[s]; }
};

/// The columns `selection` holds at 0 (a dropped muscle's block, a dropped sensor's two columns
/// in every muscle), sorted.
std::vector<int> droppedColumns(const GroupSelection& selection, int sensors, int per_muscle);

/// What the elimination did, for the progress line.
struct EliminationReport {
  int solves = 0;                ///< ridge solves it ran
  double rss_before = 0.0;       ///< residual sum of squares of the full fit
  double rss_after = 0.0;        ///< and of the selected one
  double price_per_param = 0.0;  ///< the criterion's price of one parameter (residual units)
};

/// Backward elimination by group on `sys` at the relative `ridge` under `constraints` (its
/// held_at_zero columns stay held), from `theta`, the full fit at that ridge. Each step ranks
/// the groups by the residual's rise if each alone were removed with the others held (one block
/// product each; it overstates the rise after the refit where groups overlap, so it ranks and
/// the refit decides) over the price of its parameters, removes the cheapest batch, refits,
/// and keeps the removal when the refit's rise stays below the summed price of the parameters
/// removed. The batch doubles after a kept removal and halves after a refused one; a refused
/// single group ends it. The price: sigma^2 ln(rows) per parameter, sigma^2 the full fit's
/// residual mean square. `theta` is replaced by the selected fit. At most `max_solves` solves.
GroupSelection eliminateGroups(const System& sys, double ridge, const SignConstraints& constraints,
                               int sensors, int max_solves, Eigen::VectorXd* theta, EliminationReport* report);

}  // namespace mme::sensor_muscles

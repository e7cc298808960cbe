// What identification minimises: a cost over the free parameters of a model, as a sum of squared
// residuals that also splits into per-particle local costs (the paper's crossover needs those).
// The evolution strategy, the refinements, the identifier, the online estimator and the
// benchmarks take any implementation (as ceres' CostFunction: one abstract interface, the terms
// elsewhere). ShortTermCost (short_term_cost.h) is the paper's one-step prediction cost.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"

namespace mme {

class Cost {
 public:
  virtual ~Cost() = default;

  /// The free parameters, in the order evaluate() and residuals() expect their values.
  virtual const std::vector<ParamRef>& freeParameters() const = 0;
  /// Global cost [m^2] at physical parameter values; fills local_costs (one per particle, their
  /// sum is the global cost) when not null. Const and thread-safe.
  virtual double evaluate(const std::vector<double>& values,
                          std::vector<double>* local_costs) const = 0;
  /// The same cost as a sum of squares: fills residuals (residualCount() entries, in a fixed
  /// order) [m] and returns their squared sum (equal to evaluate()'s value up to summation
  /// order). Const and thread-safe.
  virtual double residuals(const std::vector<double>& values,
                           std::vector<double>* residuals) const = 0;
  virtual size_t residualCount() const = 0;
  /// Observed samples (particle, frame) that enter the cost.
  virtual uint64_t termCount() const = 0;
  virtual int numParticles() const = 0;
  /// Short name for reports ("short_term", ...).
  virtual const char* name() const = 0;
};

}  // namespace mme

// The paper's short-term prediction cost: per-particle local costs and their sum (SPEC section 3).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "motion_model_estimation/core/cost.h"
#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// Evaluates local/global costs of parameter vectors against one trajectory. Structure
/// (particles, bonds, masses, fixed flags, occlusion masks, interaction candidate pairs) is
/// precomputed once; evaluate() only changes parameter values. evaluate() is const and
/// thread-safe (any number of threads may call it concurrently).
///
/// From observed x(t-1), x(t): v(t) = (x(t) - x(t-1))/h, one frame (substeps) of the motion law,
/// compared with observed x(t+1): local_cost(i) = sum_t |xhat_i(t+1) - x_i(t+1)|^2 [m^2].
/// A trajectory of a single frame is a static equilibrium: x(t-1) = x(t) = x(t+1) = that frame.
/// Occlusion: term (i, t) is dropped when x_i(t+1) is occluded or any free particle within
/// `substeps` bond hops of i (i included) lacks x(t) or x(t-1) (a fixed particle is where it
/// always is: its last seen position, else the model's, as for an anchor without a marker);
/// interaction groups: when a
/// particle of a group is occluded at t or t-1, every particle of groups interacting with it is
/// dropped for that frame (its neighbours are unknown).
class ShortTermCost final : public Cost {
 public:
  /// `trajectory` must have the model's particles as markers in the same order (see
  /// remapMarkers). frame_rate_hz: the model's if > 0, else the trajectory's.
  ShortTermCost(const Model& model, const Trajectory& trajectory);
  ~ShortTermCost() override;

  /// The free parameters, in the order evaluate() expects.
  const std::vector<ParamRef>& freeParameters() const override;
  /// Global cost [m^2]; fills local_costs (size = particles) when not null.
  double evaluate(const std::vector<double>& free_values,
                  std::vector<double>* local_costs) const override;
  /// The cost as a sum of squares: residuals (size residualCount()) = predicted minus observed
  /// position [m] of every term, x y z, terms in a fixed order (frame, then particle). Returns
  /// the global cost, the same value evaluate() gives (summed per particle first).
  double residuals(const std::vector<double>& free_values,
                   std::vector<double>* residuals) const override;
  /// 3 x termCount().
  size_t residualCount() const override;
  /// Same as evaluate(), splitting frames over `threads` threads (deterministic result for a thread count).
  double evaluateParallel(const std::vector<double>& free_values, std::vector<double>* local_costs,
                          int threads) const;
  /// Bond (spring/flexion/interaction candidate) evaluations one evaluate() call performs at
  /// most (every interaction candidate within the search radius).
  uint64_t bondEvaluationsPerCall() const;
  /// Bond evaluations evaluate(free_values) performs: interaction candidates beyond the current
  /// max_distance are skipped (they are inactive), so this depends on the values.
  uint64_t bondEvaluationsFor(const std::vector<double>& free_values) const;
  /// Number of (particle, frame) terms that enter the cost.
  uint64_t termCount() const override;
  int numParticles() const override;
  const char* name() const override { return "short_term"; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mme

// Offline identification pipeline shared by `identify` and the benchmarks: builds the cost and
// the search space for a model and a trajectory, runs the evolution strategy for a budget and
// estimates a 1-sigma uncertainty per parameter.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/evolution_strategy.h"

namespace mme {

struct IdentifyOptions {
  EsOptions es;
  int generations = 1000;        ///< generation budget
  double target_cost = 0.0;      ///< stop once the global cost [m^2] is <= it (0 = never)
  double max_wall_time_s = 0.0;  ///< stop after this wall time (0 = no limit)
  bool estimate_std = true;      ///< finite-difference Hessian at the optimum
  /// Stop once converged: after a refinement has run, this many generations in a row without
  /// the best cost falling by a relative 1e-9 (a cost at the round-off floor, 1e-26 m^2 per
  /// residual, counts as no fall). 0 = run the whole generation budget (the paper).
  int patience_generations = 30;
};

std::string validateOptions(const IdentifyOptions& options);
/// The options of a preset (preset.h): kDefault = the defaults above, kPaper = the paper's
/// schedule and the whole generation budget.
IdentifyOptions identifyOptionsFor(Preset preset);

/// Why identifyModel stopped.
enum class IdentifyStop { kGenerations, kTargetCost, kWallTime, kConverged };
const char* identifyStopName(IdentifyStop stop);

struct Progress {
  int generation = 0;
  uint64_t evaluations = 0;
  double best_cost = 0.0;
  double wall_time_s = 0.0;
  std::vector<double> best_values;  ///< physical, in free-parameter order
};

struct IdentifyResult {
  std::vector<ParamRef> parameters;  ///< free parameters, in order
  std::vector<double> values;        ///< identified physical values
  std::vector<double> std_devs;      ///< 1-sigma (NaN when the Hessian is not usable)
  double global_cost = 0.0;
  int generations = 0;
  uint64_t evaluations = 0;
  double wall_time_s = 0.0;
  int frames = 0;
  IdentifyStop stop = IdentifyStop::kGenerations;
  RefineStatus last_refine_status = RefineStatus::kNotRun;  ///< how the last refinement ended
  Model model;  ///< the input model with every free value filled in
};

/// `trajectory` must already hold the model's particles as markers (remapMarkers). Calls
/// `progress` (if set) after every generation. Throws InputError on unusable input.
IdentifyResult identifyModel(const Model& model, const Trajectory& trajectory,
                             const IdentifyOptions& options,
                             const std::function<void(const Progress&)>& progress = nullptr);

/// 1-sigma uncertainty of each gene-mapped parameter from the global cost's curvature at
/// `values`: Cov = 2 s^2 H^-1 with s^2 = cost / (3 terms - n). NaN where not defined.
std::vector<double> estimateStdDevs(const Cost& cost, const ParameterSpace& space,
                                    const std::vector<double>& genes);

}  // namespace mme

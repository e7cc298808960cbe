// Offline identification pipeline shared by `identify` and the benchmarks: builds the cost and
// the search space for a model and a trajectory, runs the evolution strategy for a budget and
// estimates a 1-sigma uncertainty per parameter.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/search/evolution_strategy.h"
#include "motion_model_estimation/identification/search/island_model.h"
#include "motion_model_estimation/identification/estimators/covariance.h"
#include "motion_model_estimation/identification/estimators/estimator_kind.h"
#include "motion_model_estimation/identification/estimators/output_error.h"

namespace mme {

/// Which cost gives the final answer.
enum class CostChoice {
  kAuto,         ///< output error when the markers' estimated noise reaches auto_noise_threshold_m
  kShortTerm,    ///< the paper's one-step prediction (exact on noiseless data, biased by noise)
  kOutputError,  ///< multiple shooting (output_error.h), started from the search's answer
};
/// "auto" | "short_term" | "output_error" -> the enum; false when unknown.
bool parseCostChoice(const std::string& name, CostChoice* choice);
const char* costChoiceName(CostChoice choice);

struct IdentifyOptions {
  EsOptions es;
  /// Islands (island_model.h): islands = 1 is the single evolution strategy; with more, each
  /// island runs `es` (population, offspring) with its own seed, and `es.threads` is shared out
  /// among them. The generation budget and the stop rules count lock-step generations.
  IslandOptions islands;
  CostChoice cost = CostChoice::kAuto;
  /// kAuto: the output-error estimator runs when estimateMarkerNoise() is at least this [m]
  /// (below it the one-step cost is exact to within what matters, and faster).
  double auto_noise_threshold_m = 1e-7;
  OutputErrorOptions output_error;
  /// When the identified model's stiffest mode has omega h / substeps above this, the
  /// prediction integrates with more substeps per frame (and the search resumes): semi-implicit
  /// Euler's drift grows as (omega h)^2. 0: never.
  double max_omega_h_per_substep = 0.2;
  int generations = 1000;        ///< generation budget
  double target_cost = 0.0;      ///< stop once the global cost [m^2] is <= it (0 = never)
  double max_wall_time_s = 0.0;  ///< stop after this wall time (0 = no limit)
  /// Raised by another thread or a signal handler (e.g. Ctrl-C): the search stops after the
  /// generation or refinement under way with its best so far (IdentifyStop::kCancelled) and the
  /// output error is not started (one under way stops after its iteration). May be null.
  const std::atomic<bool>* cancel = nullptr;
  bool estimate_std = true;      ///< 1-sigma std and unidentifiable flags at the answer (covariance.h)
  /// Stop once converged: after a refinement has run, when the best cost fell by less than a
  /// relative 1e-4 over this many generations, or sits at the round-off floor (1e-26 m^2 per
  /// residual); twice this when a threshold (min/max_distance) is free. 0 = run the whole
  /// generation budget (the paper).
  int patience_generations = 50;
  /// Seed the population with the equation-error solution (equation_error.h) where it applies,
  /// widening default bounds that exclude it.
  bool equation_error_start = true;
  /// When every free parameter has a value in the model (a complete guess, e.g. an earlier
  /// fit), one individual of the first population is exactly that guess: the search never ends
  /// worse than it (the rest of the population is drawn around it as before; a value outside a
  /// default bound widens the bound, as the equation-error start does).
  bool values_start = true;
  /// A smooth parameter that ends within 1 % of a default (not user-given) bound: the bound is
  /// widened tenfold and the search resumed from the answer, at most this many times.
  int max_bound_widenings = 3;
  /// kAuto only: when the search's answer leaves one-step residuals over 2x what the markers'
  /// noise gives (the passive model does not explain the motion, as on a walk), the output
  /// error is not run but left to the caller (IdentifyResult::output_error_deferred;
  /// runDeferredOutputError), which runs it only when a later step (the sensor muscles) does
  /// not replace the passive model: there it costs minutes and is rarely adopted. Where the
  /// residuals are at the noise (a passive scene, where the output error reaches the
  /// Cramer-Rao bound) or the one-step cost is starved by occlusion, it runs as always.
  bool defer_output_error_on_misfit = false;
};

std::string validateOptions(const IdentifyOptions& options);
/// The options of a preset (preset.h): kDefault = the defaults above, kPaper = the paper's
/// method (its schedule, random starts, its bounds, its one-step cost, the whole budget).
IdentifyOptions identifyOptionsFor(Preset preset);

/// Why identifyModel stopped. kWallTime also when the time limit cut the output-error fit after
/// the search had converged: a cut fit is never reported as converged.
enum class IdentifyStop { kGenerations, kTargetCost, kWallTime, kConverged, kCancelled };
const char* identifyStopName(IdentifyStop stop);

struct Progress {
  /// Non-empty: a notice rather than a generation's figures (e.g. a widened bound).
  std::string message;
  int generation = 0;
  uint64_t evaluations = 0;
  double best_cost = 0.0;
  double wall_time_s = 0.0;
  std::vector<double> best_values;  ///< physical, in free-parameter order
};

struct IdentifyResult {
  std::vector<ParamRef> parameters;  ///< free parameters, in order
  std::vector<double> values;        ///< identified physical values
  std::vector<double> std_devs;      ///< 1-sigma (NaN where not defined)
  /// Why every std is NaN when the reason is the run's, not the parameter's (e.g. the time limit
  /// cut the fit before its uncertainty was computed); empty otherwise.
  std::string std_missing_reason;
  std::vector<ParameterFlag> flags;  ///< per parameter
  double global_cost = 0.0;
  int generations = 0;
  uint64_t evaluations = 0;
  double wall_time_s = 0.0;
  int frames = 0;
  IdentifyStop stop = IdentifyStop::kGenerations;
  RefineStatus last_refine_status = RefineStatus::kNotRun;  ///< how the last refinement ended
  int bound_widenings = 0;           ///< searches resumed after widening default bounds
  /// Per island (one entry per island; one for the single evolution strategy): its cost
  /// evaluations (immigrants' re-evaluations included) and the immigrants it let in.
  std::vector<uint64_t> island_evaluations;
  std::vector<uint64_t> island_immigrants_accepted;
  int migrations = 0;                ///< migrations done (every island sending once)
  int best_island = 0;               ///< the island whose best is the search's answer
  std::vector<std::string> notes;    ///< what happened on the way (widened bounds, ...)
  Estimator estimator = Estimator::kShortTerm;  ///< the cost of the final answer
  double noise_estimate_m = 0.0;     ///< estimateMarkerNoise() of the data
  double noise_std_m = 0.0;          ///< output error: from its residuals (else 0)
  int substeps = 1;                  ///< integration steps per frame the answer was fitted with
  double stiffest_omega_h = 0.0;     ///< the answer's stiffest mode x frame period
  /// IdentifyOptions::defer_output_error_on_misfit left the output error to the caller (the
  /// answer is the search's; runDeferredOutputError runs it).
  bool output_error_deferred = false;
  double one_step_rms_m = 0.0;       ///< the search's answer's one-step residual per coordinate
  Model model;  ///< the input model with every free value filled in
};

/// `trajectory` must already hold the model's particles as markers (remapMarkers). Calls
/// `progress` (if set) after every generation. Throws InputError on unusable input.
IdentifyResult identifyModel(const Model& model, const Trajectory& trajectory,
                             const IdentifyOptions& options,
                             const std::function<void(const Progress&)>& progress = nullptr);

/// The output error identifyModel deferred (`passive.output_error_deferred`), from the passive
/// answer's values without a new search: `passive` with the output error's answer where it is
/// adopted (the same judge as identifyModel's), else `passive` unchanged; the notes of both
/// runs either way. `options` are identifyModel's; `trajectory` the one it fitted.
IdentifyResult runDeferredOutputError(const IdentifyResult& passive, const Trajectory& trajectory,
                                      const IdentifyOptions& options,
                                      const std::function<void(const Progress&)>& progress = nullptr);

/// Per parameter at `genes`: within 1 % of a search bound, or else (where `unidentifiable` is
/// given and says so) undetermined by the data. The offline result's and the live estimate's
/// flags.
std::vector<ParameterFlag> parameterFlags(const ParameterSpace& space, const std::vector<double>& genes,
                                          const std::vector<uint8_t>* unidentifiable = nullptr);

/// 1-sigma uncertainty of each parameter at `genes` and whether the data determine it
/// (covariance.h: Cov = s^2 (J^T J)^+ with J the residuals' forward-difference Jacobian over the
/// smooth genes, s^2 = cost / (residuals - genes)). NaN where not defined (the thresholds of
/// conditional bonds, undetermined parameters). `pool` may be null.
GeneUncertainty estimateStdDevs(const Cost& cost, const ParameterSpace& space,
                                const std::vector<double>& genes, ThreadPool* pool = nullptr);

}  // namespace mme

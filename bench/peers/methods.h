// The methods compared by the peer benchmark, all on the same Problem (cost function, search
// space, random starts) and judged the same way: the best-cost point found so far is the
// method's answer; its parameter errors against the truth are recorded along the run. The one
// exception is `default`, judged on the final answer it returns.
//   default    the package's default engine exactly as `identify` runs it (mme::identifyModel
//              with identifyOptionsFor(kDefault): ES + LM on the one-step cost, equation-error
//              seeds, threshold search, bound widening, convergence stop, automatic substeps,
//              the output-error estimator when the markers' noise reaches 1e-7 m); it stops by
//              itself, takes its own starts and is judged on its final answer (no oracle stop)
//   islands    `default` with `--islands 3` (identify's island defaults: broadcast, 2 migrants
//              every 10 generations), the same total evaluations (a third of the generations);
//              judged like `default` on its final answer; run in the stability map only
//   es_local   the paper's ES with local costs (mme::EvolutionStrategy, default options)
//   es_early   the same engine with its refinement from generation 10, every 10 (the paper:
//              from 400, every 100); run in the speed-accuracy part only
//   es_lm      the same engine with the Levenberg-Marquardt refinement (refine_algorithm
//              levenberg_marquardt) from generation kLmRefineGeneration, every as many
//   es_global  the same engine with the local-cost operators switched off through its options
//              (share_partial_replica = share_crossover = 0, their share given to share_replica)
//   cmaes      pagmo2 CMA-ES (restarts from the next starts when it stops or stalls)
//   sade       pagmo2 self-adaptive differential evolution (jDE), same restarts
//   sade_final sade without the oracle stop, judged on its best point at the budget's end (the
//              stability map's conditional axis only: the final-answer comparison with default)
//   bobyqa     NLopt BOBYQA, multi-start from the same random starts until the budget
//   lm         Ceres Levenberg-Marquardt on the cost's residuals, forward numeric
//              differences, multi-start until the budget
//   lls        linear least squares on the equation error (one solve; linear springs only)
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "motion_model_estimation/identification/estimators/estimator_kind.h"
#include "problem.h"

namespace bench {

/// es_early's refinement schedule: first refinement and period [generations].
constexpr int kEarlyRefineGeneration = 10;
/// `islands`' island count.
constexpr int kIslands = 3;
/// es_lm's: first refinement and period [generations].
constexpr int kLmRefineGeneration = 5;

struct Budget {
  uint64_t max_evaluations = 100000;  ///< cost evaluations (full-cost equivalents)
  double max_wall_s = 60.0;           ///< wall-time limit of one run
  /// Oracle stop: the run ends once the best point's max parameter error is below this [%]
  /// (0 = never). Only used to save time: it cannot change when a threshold is first reached.
  double stop_max_error_pct = 0.0;
};

struct TracePoint {
  uint64_t evaluations = 0;
  double wall_s = 0.0;
  double cost = 0.0;
  double median_error_pct = 0.0;
  double max_error_pct = 0.0;
};

/// First time the best point's max error went below a threshold.
struct Milestone {
  bool reached = false;
  uint64_t evaluations = 0;
  double wall_s = 0.0;
  int generations = -1;  ///< generations of population methods at that moment (-1 otherwise)
};

struct RunResult {
  std::string method;
  bool applicable = true;  ///< false: "n/a" (LLS on conditional/non-linear bonds)
  std::string note;        ///< n/a reason or how the run ended
  std::vector<double> values;  ///< physical, free-parameter order
  double cost = 0.0;
  Errors errors;
  uint64_t evaluations = 0;
  double wall_s = 0.0;
  int generations = -1;
  int restarts = 0;
  Milestone to_1pct, to_001pct;  ///< max error < 1 % and < 0.01 %
  bool bounded = false;           ///< long rollout of the answer stays bounded
  // `default` only (the identify pipeline's result; others keep these defaults):
  std::optional<mme::Estimator> estimator;  ///< the pipeline's final cost (none: not the pipeline)
  int substeps = 0;               ///< integration steps per frame of the answer (0 = the problem's)
  double noise_estimate_m = -1.0; ///< the pipeline's marker-noise estimate (< 0 = not run)
  double residual_std_m = -1.0;   ///< output error: RMS residual per coordinate at its answer
  int flagged = 0;                ///< parameters it flagged (at a bound, unidentifiable)
  std::vector<TracePoint> trace;  ///< best-so-far curve (thinned)
};

/// Methods compiled in (peers missing at build time are left out).
std::vector<std::string> availableMethods();
/// Every method the benchmark knows, available or not.
std::vector<std::string> allMethods();
bool methodAvailable(const std::string& method);

/// Runs one method on one problem from the random starts of `seed` (`default`: its own starts
/// for that seed; budget.stop_max_error_pct does not apply to it).
RunResult runMethod(const std::string& method, const Problem& problem, uint64_t seed,
                    const Budget& budget, bool keep_trace);

/// Equation-error least squares (also used standalone): fills values; false when n/a.
bool solveEquationError(const Problem& problem, std::vector<double>* values, std::string* why);

}  // namespace bench

// A local refinement of one point of the search space: the evolution strategy hands its best
// individual to it every few generations. Chosen by an enum through a factory, reporting how it
// ended (as ceres' TrustRegionStrategy::Create and TinySolver::Status): the Powell family
// (NLopt: BOBYQA, NEWUOA, PRAXIS; derivative-free) or Levenberg-Marquardt on the cost's residuals.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "motion_model_estimation/core/cost.h"
#include "motion_model_estimation/core/thread_pool.h"
#include "motion_model_estimation/identification/search/parameter_space.h"

namespace mme {

enum class RefineAlgorithm { kBobyqa, kNewuoa, kPraxis, kLevenbergMarquardt };

/// "bobyqa" | "newuoa" | "praxis" | "levenberg_marquardt" -> the enum; false when unknown.
bool parseRefineAlgorithm(const std::string& name, RefineAlgorithm* algorithm);
const char* refineAlgorithmName(RefineAlgorithm algorithm);
/// The accepted names, for messages ("bobyqa, newuoa, praxis or levenberg_marquardt").
const char* refineAlgorithmNames();

/// How a refinement ended.
enum class RefineStatus {
  kConverged,         ///< the next step is below the step tolerance (LM) / NLopt's tolerances met
  kStalled,           ///< progress stopped paying (the stall rule), e.g. a noisy optimum
  kNoProgress,        ///< no step lowered the cost (round-off floor or a flat cost)
  kEvaluationLimit,   ///< the evaluation budget is spent
  kDeadline,          ///< the caller's deadline came (or the next Jacobian would pass it)
  kJacobianTooLarge,  ///< LM: the Jacobian outgrew its memory cap (the caller may fall back)
  kNotRun,            ///< the budget did not allow a single iteration
  kCancelled,         ///< the caller's cancel flag was raised
};
const char* refineStatusName(RefineStatus status);

struct RefineSettings {
  uint64_t max_evaluations = 0;     ///< cost evaluations allowed (caps already applied)
  /// Stall rule: NLopt stops when a window of this many evaluations did not divide the best cost
  /// by stall_factor; LM when 3 Jacobians in a row did not. stall_factor 0: one window / 3
  /// Jacobians, whatever the progress.
  uint64_t window_evaluations = 0;
  double stall_factor = 1.01;
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
  /// Raised by another thread: the refinement stops at its next check (between evaluations, or
  /// between Jacobians for LM), keeping its best point. Null: never.
  const std::atomic<bool>* cancel = nullptr;
  /// The deadline has passed or the cancel flag is raised.
  bool mustStop() const {
    return (cancel && cancel->load(std::memory_order_relaxed)) ||
           (deadline != std::chrono::steady_clock::time_point::max() &&
            std::chrono::steady_clock::now() > deadline);
  }
  /// Genes the refinement may move (empty = all). Genes without a useful slope (the thresholds
  /// of conditional bonds: the cost is flat between switching events) stay where they are.
  std::vector<uint8_t> movable;
};

struct RefineStart {
  std::vector<double> genes;   ///< inside the bounds
  double cost = 0.0;           ///< cost at genes [m^2]
  std::vector<double> steps;   ///< per gene: the scale of a first move (e.g. the ES mutability)
};

struct RefineResult {
  std::vector<double> genes;   ///< best point found (the start when nothing better)
  double cost = 0.0;
  uint64_t evaluations = 0;    ///< cost evaluations spent (one residual vector = one)
  RefineStatus status = RefineStatus::kNotRun;
};

class Refiner {
 public:
  virtual ~Refiner() = default;
  /// Minimises cost(space.toPhysical(genes)) from `start` inside the genes' bounds. `pool` may be
  /// null (one thread); results do not depend on the thread count.
  virtual RefineResult refine(const Cost& cost, const ParameterSpace& space,
                              const RefineStart& start, const RefineSettings& settings,
                              ThreadPool* pool) const = 0;
  virtual RefineAlgorithm algorithm() const = 0;

  static std::unique_ptr<Refiner> Create(RefineAlgorithm algorithm);
};

}  // namespace mme

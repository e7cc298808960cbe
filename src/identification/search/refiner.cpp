#include "motion_model_estimation/identification/search/refiner.h"

#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "motion_model_estimation/identification/search/ceres_levenberg_marquardt.h"

namespace mme {

namespace {

struct AlgorithmName {
  RefineAlgorithm algorithm;
  const char* name;
};
constexpr AlgorithmName kAlgorithmNames[] = {
    {RefineAlgorithm::kBobyqa, "bobyqa"},
    {RefineAlgorithm::kNewuoa, "newuoa"},
    {RefineAlgorithm::kPraxis, "praxis"},
    {RefineAlgorithm::kLevenbergMarquardt, "levenberg_marquardt"},
};

/// The genes a refinement moves, as indices (all when `movable` is empty).
std::vector<size_t> movableGenes(const ParameterSpace& space, const std::vector<uint8_t>& movable) {
  std::vector<size_t> out;
  for (size_t k = 0; k < space.size(); ++k)
    if (movable.empty() || (k < movable.size() && movable[k])) out.push_back(k);
  return out;
}

struct NloptContext {
  const Cost* cost;
  const ParameterSpace* space;
  nlopt::opt* opt;
  const std::vector<size_t>* active;  ///< reduced coordinate j -> gene active[j]
  std::vector<double> genes;          ///< the full point (inactive genes at their start)
  const RefineSettings* settings;
  uint64_t window;       ///< evaluations over which progress is judged
  double stall_factor;   ///< the best cost must shrink this much per window (0: no test)
  double start_cost;     ///< the cost before the first window
  uint64_t calls = 0;
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_after;  ///< best cost after each call
  RefineStatus forced = RefineStatus::kNotRun;  ///< why force_stop() was called
};

double nloptObjective(const std::vector<double>& reduced, std::vector<double>& /*grad*/,
                      void* data) {
  auto* ctx = static_cast<NloptContext*>(data);
  ++ctx->calls;
  for (size_t j = 0; j < reduced.size(); ++j) ctx->genes[(*ctx->active)[j]] = reduced[j];
  double c = ctx->cost->evaluate(ctx->space->toPhysical(ctx->genes), nullptr);
  if (!std::isfinite(c)) c = 1e300;
  ctx->best = std::min(ctx->best, c);
  ctx->best_after.push_back(ctx->best);
  if (ctx->settings->mustStop()) {
    const bool cancelled = ctx->settings->cancel && ctx->settings->cancel->load();
    ctx->forced = cancelled ? RefineStatus::kCancelled : RefineStatus::kDeadline;
    ctx->opt->force_stop();
  }
  // Stalled: the last window did not divide the best cost by the factor (converged, at the
  // round-off floor, or crawling), judged against the best cost before that window.
  const uint64_t w = ctx->window;
  if (ctx->calls >= w && ctx->calls % w == 0) {
    const double window_start =
        ctx->calls == w ? ctx->start_cost : ctx->best_after[ctx->calls - w - 1];
    if (!(ctx->stall_factor > 0.0) || !(ctx->best * ctx->stall_factor <= window_start)) {
      if (ctx->forced == RefineStatus::kNotRun) ctx->forced = RefineStatus::kStalled;
      ctx->opt->force_stop();
    }
  }
  return c;
}

/// The Powell family through NLopt (the paper's "variant of the Powell method"). One long run
/// rather than fixed short ones: ill-conditioned costs (a stiff clamp next to a weak cubic term)
/// need BOBYQA's quadratic model to mature, which a restart throws away; it stops when a window
/// of evaluations no longer pays.
class NloptRefiner final : public Refiner {
 public:
  explicit NloptRefiner(RefineAlgorithm algorithm) : algorithm_(algorithm) {}
  RefineAlgorithm algorithm() const override { return algorithm_; }

  RefineResult refine(const Cost& cost, const ParameterSpace& space, const RefineStart& start,
                      const RefineSettings& settings, ThreadPool* /*pool*/) const override {
    RefineResult out;
    out.genes = start.genes;
    out.cost = start.cost;
    const std::vector<size_t> active = movableGenes(space, settings.movable);
    const size_t n = active.size();
    // BOBYQA needs 2n+1 points before it moves.
    if (n == 0 || settings.max_evaluations < 2 * n + 2) return out;
    nlopt::algorithm algo = nlopt::LN_BOBYQA;
    if (algorithm_ == RefineAlgorithm::kNewuoa) algo = nlopt::LN_NEWUOA_BOUND;
    if (algorithm_ == RefineAlgorithm::kPraxis) algo = nlopt::LN_PRAXIS;
    nlopt::opt opt(algo, static_cast<unsigned>(n));
    std::vector<double> lo(n), hi(n), step(n), x(n);
    for (size_t j = 0; j < n; ++j) {
      const Gene& g = space.gene(active[j]);
      lo[j] = g.lower;
      hi[j] = g.upper;
      x[j] = start.genes[active[j]];
      // Initial trust region from the caller's scale (the ES's self-adapted mutability).
      const double s = active[j] < start.steps.size() ? start.steps[active[j]] : 0.0;
      step[j] = std::max(std::min(s * 2.0, 0.25 * (hi[j] - lo[j])), 1e-9);
    }
    opt.set_lower_bounds(lo);
    opt.set_upper_bounds(hi);
    opt.set_initial_step(step);
    const uint64_t window = std::max<uint64_t>(settings.window_evaluations, 1);
    NloptContext ctx{&cost, &space, &opt, &active, start.genes, &settings, window,
                     settings.stall_factor, start.cost, 0, start.cost, {}, RefineStatus::kNotRun};
    ctx.best_after.reserve(std::min<uint64_t>(window, 1u << 20));
    opt.set_min_objective(nloptObjective, &ctx);
    opt.set_maxeval(static_cast<int>(std::min<uint64_t>(settings.max_evaluations, 1u << 30)));
    opt.set_ftol_rel(1e-15);
    double fx = start.cost;
    nlopt::result result = nlopt::FAILURE;
    try {
      result = opt.optimize(x, fx);
    } catch (const nlopt::forced_stop&) {
      result = nlopt::FORCED_STOP;
    } catch (const nlopt::roundoff_limited&) {
      result = nlopt::ROUNDOFF_LIMITED;
    } catch (const std::exception&) {
      result = nlopt::FAILURE;  // x holds the best point NLopt had
    }
    out.evaluations = ctx.calls;
    for (size_t j = 0; j < n; ++j)
      out.genes[active[j]] = std::min(std::max(x[j], lo[j]), hi[j]);
    out.cost = std::min(fx, start.cost);
    if (!(fx < start.cost)) out.genes = start.genes;
    switch (result) {
      case nlopt::FORCED_STOP:
        out.status = ctx.forced == RefineStatus::kNotRun ? RefineStatus::kStalled : ctx.forced;
        break;
      case nlopt::MAXEVAL_REACHED:
      case nlopt::MAXTIME_REACHED:
        out.status = RefineStatus::kEvaluationLimit;
        break;
      case nlopt::SUCCESS:
      case nlopt::STOPVAL_REACHED:
      case nlopt::FTOL_REACHED:
      case nlopt::XTOL_REACHED:
        out.status = RefineStatus::kConverged;
        break;
      case nlopt::ROUNDOFF_LIMITED:
      case nlopt::FAILURE:
      case nlopt::INVALID_ARGS:
      case nlopt::OUT_OF_MEMORY:
      case nlopt::NUM_FAILURES:
      case nlopt::NUM_RESULTS:
        out.status = RefineStatus::kNoProgress;
        break;
    }
    return out;
  }

 private:
  RefineAlgorithm algorithm_;
};

/// Levenberg-Marquardt on the cost's residuals (ceres_levenberg_marquardt.h); a Jacobian over its
/// memory cap falls back to BOBYQA (O(n^2) memory) from the best point reached.
class LmRefiner final : public Refiner {
 public:
  RefineAlgorithm algorithm() const override { return RefineAlgorithm::kLevenbergMarquardt; }

  RefineResult refine(const Cost& cost, const ParameterSpace& space, const RefineStart& start,
                      const RefineSettings& settings, ThreadPool* pool) const override {
    RefineResult out;
    out.genes = start.genes;
    out.cost = start.cost;
    const size_t n = movableGenes(space, settings.movable).size();
    if (n == 0 || settings.max_evaluations < n + 2) return out;  // not one Jacobian and step
    LmSettings lm;
    lm.max_evaluations = settings.max_evaluations;
    lm.stall_factor = settings.stall_factor;
    lm.deadline = settings.deadline;
    lm.cancel = settings.cancel;
    lm.movable = settings.movable;
    LmResult result = levenbergMarquardt(cost, space, start.genes, lm, pool);
    out.evaluations = result.evaluations;
    out.status = result.status;
    if (result.cost < start.cost) {
      out.genes = result.genes;
      out.cost = result.cost;
    }
    if (result.status == RefineStatus::kJacobianTooLarge) {
      RefineStart from = start;
      from.genes = out.genes;
      from.cost = out.cost;
      RefineSettings rest = settings;
      rest.max_evaluations =
          settings.max_evaluations > out.evaluations ? settings.max_evaluations - out.evaluations : 0;
      const RefineResult fallback =
          NloptRefiner(RefineAlgorithm::kBobyqa).refine(cost, space, from, rest, pool);
      out.evaluations += fallback.evaluations;
      if (fallback.cost < out.cost) {
        out.genes = fallback.genes;
        out.cost = fallback.cost;
      }
      // The fallback's ending, unless it never ran: then the reason is the Jacobian.
      if (fallback.status != RefineStatus::kNotRun) out.status = fallback.status;
    }
    return out;
  }
};

}  // namespace

bool parseRefineAlgorithm(const std::string& name, RefineAlgorithm* algorithm) {
  for (const AlgorithmName& a : kAlgorithmNames)
    if (name == a.name) {
      *algorithm = a.algorithm;
      return true;
    }
  return false;
}

const char* refineAlgorithmName(RefineAlgorithm algorithm) {
  for (const AlgorithmName& a : kAlgorithmNames)
    if (a.algorithm == algorithm) return a.name;
  return "?";
}

const char* refineAlgorithmNames() { return "bobyqa, newuoa, praxis or levenberg_marquardt"; }

const char* refineStatusName(RefineStatus status) {
  switch (status) {
    case RefineStatus::kConverged: return "converged";
    case RefineStatus::kStalled: return "stalled";
    case RefineStatus::kNoProgress: return "no_progress";
    case RefineStatus::kEvaluationLimit: return "evaluation_limit";
    case RefineStatus::kDeadline: return "deadline";
    case RefineStatus::kJacobianTooLarge: return "jacobian_too_large";
    case RefineStatus::kNotRun: return "not_run";
    case RefineStatus::kCancelled: return "cancelled";
  }
  return "?";
}

std::unique_ptr<Refiner> Refiner::Create(RefineAlgorithm algorithm) {
  switch (algorithm) {
    case RefineAlgorithm::kBobyqa:
    case RefineAlgorithm::kNewuoa:
    case RefineAlgorithm::kPraxis:
      return std::make_unique<NloptRefiner>(algorithm);
    case RefineAlgorithm::kLevenbergMarquardt:
      return std::make_unique<LmRefiner>();
  }
  throw std::logic_error("Refiner::Create: unknown algorithm");
}

}  // namespace mme

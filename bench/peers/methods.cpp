#include "methods.h"

#include <Eigen/Dense>
#include <nlopt.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>

#include "motion_model_estimation/identification/search/evolution_strategy.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"

#ifdef MME_HAVE_PAGMO
#include <pagmo/algorithm.hpp>
#include <pagmo/algorithms/cmaes.hpp>
#include <pagmo/algorithms/sade.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#endif
#ifdef MME_HAVE_CERES
#include <ceres/ceres.h>
#endif

namespace bench {

std::vector<std::string> allMethods() {
  return {"default", "islands", "es_local", "es_early", "es_lm", "es_global", "cmaes",
          "sade",    "sade_final", "bobyqa", "lm",  "lls"};
}

bool methodAvailable(const std::string& method) {
#ifndef MME_HAVE_PAGMO
  if (method == "cmaes" || method == "sade" || method == "sade_final") return false;
#endif
#ifndef MME_HAVE_CERES
  if (method == "lm") return false;
#endif
  const std::vector<std::string> all = allMethods();
  return std::find(all.begin(), all.end(), method) != all.end();
}

std::vector<std::string> availableMethods() {
  std::vector<std::string> out;
  for (const std::string& m : allMethods())
    if (methodAvailable(m)) out.push_back(m);
  return out;
}

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();

/// Counts evaluations, keeps the best-cost point (the method's answer) and its parameter errors
/// along the run. Every method here runs on one thread.
class Tracker {
 public:
  Tracker(const Problem& problem, const Budget& budget, bool keep_trace)
      : problem_(problem), budget_(budget), keep_trace_(keep_trace), start_(Clock::now()) {}

  /// One full-cost evaluation of genes (reflected into the bounds), recorded.
  double evaluate(std::vector<double> genes) {
    ++evaluations_;
    const double c = costOfGenes(problem_, &genes);
    consider(genes, c);
    return c;
  }
  /// An evaluation made elsewhere (cost already known); points outside the bounds are
  /// counted but never become the answer.
  void counted(const std::vector<double>& genes, double cost) {
    ++evaluations_;
    for (size_t k = 0; k < genes.size(); ++k)
      if (genes[k] < problem_.space->gene(k).lower || genes[k] > problem_.space->gene(k).upper)
        return;
    consider(genes, std::isfinite(cost) ? cost : 1e300);
  }
  /// Engines that evaluate internally (the ES): their totals and their best.
  void observe(const std::vector<double>& genes, double cost, uint64_t evaluations, int generation) {
    evaluations_ = evaluations;
    generations_ = generation;
    consider(genes, cost);
  }
  void setGenerations(int g) { generations_ = g; }
  uint64_t evaluations() const { return evaluations_; }
  double elapsed() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  uint64_t remaining() const {
    return evaluations_ >= budget_.max_evaluations ? 0 : budget_.max_evaluations - evaluations_;
  }
  bool targetReached() const {
    return budget_.stop_max_error_pct > 0.0 && have_best_ && best_errors_.max < budget_.stop_max_error_pct;
  }
  bool done() const {
    return evaluations_ >= budget_.max_evaluations || elapsed() >= budget_.max_wall_s ||
           targetReached();
  }
  bool haveBest() const { return have_best_; }

  void finish(RunResult* r) {
    r->evaluations = evaluations_;
    r->wall_s = elapsed();
    r->generations = generations_;
    r->to_1pct = to_1pct_;
    r->to_001pct = to_001pct_;
    if (have_best_) {
      r->values = problem_.space->toPhysical(best_genes_);
      r->cost = best_cost_;
      r->errors = best_errors_;
    } else {
      r->values.assign(problem_.space->size(), std::numeric_limits<double>::quiet_NaN());
      r->cost = kInf;
      r->errors.median = r->errors.max = 1e300;
    }
    if (r->note.empty())
      r->note = targetReached() ? "target"
                : evaluations_ >= budget_.max_evaluations ? "evaluation budget"
                : elapsed() >= budget_.max_wall_s ? "time limit" : "converged";
    if (keep_trace_ && have_best_) push();
    r->trace = std::move(trace_);
  }

 private:
  void consider(const std::vector<double>& genes, double cost) {
    if (!(cost < best_cost_)) return;
    best_cost_ = cost;
    best_genes_ = genes;
    have_best_ = true;
    best_errors_ = relativeErrors(problem_.space->toPhysical(genes), problem_.truth_values);
    bool milestone = false;
    for (auto [ms, threshold] : {std::make_pair(&to_1pct_, 1.0), std::make_pair(&to_001pct_, 0.01)})
      if (!ms->reached && best_errors_.max < threshold) {
        ms->reached = true;
        ms->evaluations = evaluations_;
        ms->wall_s = elapsed();
        ms->generations = generations_;
        milestone = true;
      }
    if (keep_trace_ && (milestone || trace_.empty() ||
                        evaluations_ >= trace_.back().evaluations + 1 + trace_.back().evaluations / 40))
      push();
  }
  void push() {
    TracePoint p{evaluations_, elapsed(), best_cost_, best_errors_.median, best_errors_.max};
    if (!trace_.empty() && trace_.back().evaluations == p.evaluations) trace_.back() = p;
    else trace_.push_back(p);
  }

  const Problem& problem_;
  Budget budget_;
  bool keep_trace_;
  Clock::time_point start_;
  uint64_t evaluations_ = 0;
  int generations_ = -1;
  bool have_best_ = false;
  double best_cost_ = kInf;
  std::vector<double> best_genes_;
  Errors best_errors_;
  Milestone to_1pct_, to_001pct_;
  std::vector<TracePoint> trace_;
};

// ---------------------------------------------------------------- the engine (two variants)
enum class Schedule { kPaper, kEarlyBobyqa, kEarlyLm };

RunResult runEs(const Problem& p, uint64_t seed, const Budget& budget, bool keep_trace, bool local,
                Schedule schedule) {
  RunResult r;
  Tracker tracker(p, budget, keep_trace);
  // es_lm is the engine's default preset (the Levenberg-Marquardt refinement on the residuals,
  // early and often, on the smooth genes); es_local and es_early the paper's preset, es_early
  // with another refinement schedule (a setting, not a code change): BOBYQA from generation 10,
  // every 10, instead of the paper's 400 / 100.
  mme::EsOptions o =
      mme::esOptionsFor(schedule == Schedule::kEarlyLm ? mme::Preset::kDefault : mme::Preset::kPaper);
  o.seed = seed;
  o.threads = 1;
  // A refinement runs while it pays, possibly for many windows: keep it inside the budget.
  o.refine_total_evaluation_cap = budget.max_evaluations;
  if (schedule == Schedule::kEarlyBobyqa) {
    o.refine_start_generation = kEarlyRefineGeneration;
    o.refine_period = kEarlyRefineGeneration;
  }
  if (!local) {
    // Ablation through the options only (the engine is unchanged): the local-cost operators
    // (partial replica chosen by local cost, local-cost-biased crossover) get no children;
    // their share goes to the global replica. Partly-new children pick parents by global cost.
    o.share_replica += o.share_partial_replica + o.share_crossover;
    o.share_partial_replica = 0.0;
    o.share_crossover = 0.0;
  }
  mme::EvolutionStrategy es(*p.space, o);
  es.setCost(p.cost);
  es.setDeadline(std::chrono::steady_clock::now() +
                 std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                     std::chrono::duration<double>(budget.max_wall_s)));
  if (p.start_spread >= 0.0) {
    // The initial population = the first `population` starts of the spread rule.
    Starts starts(p, seed);
    std::vector<mme::Individual> population(o.population);
    for (mme::Individual& ind : population) {
      ind.genes = starts.next();
      for (size_t k = 0; k < p.space->size(); ++k)
        ind.mutability.push_back(o.initial_mutability * (p.space->gene(k).upper - p.space->gene(k).lower));
    }
    es.evaluate(&population);  // counted by the engine
    es.setPopulation(std::move(population));
  }
  while (!tracker.done()) {
    es.step();
    tracker.observe(es.best().genes, es.best().cost, es.evaluations(), es.generation());
  }
  tracker.finish(&r);
  return r;
}

// ---------------------------------------------------------------- the default engine
/// `identify` with no option but `--islands islands`: identifyModel(identifyOptionsFor(kDefault))
/// on the problem's model and data, one thread, the run's seed, its wall budget and its
/// evaluation budget as lock-step generations of `offspring` children per island. Its own starts
/// (the paper's initial distribution and the equation-error seeds); judged on the final answer,
/// whatever the oracle stop says.
RunResult runDefault(const Problem& p, uint64_t seed, const Budget& budget, bool keep_trace, int islands) {
  RunResult r;
  mme::IdentifyOptions o = mme::identifyOptionsFor(mme::Preset::kDefault);
  o.es.seed = seed;
  o.es.threads = 1;
  o.islands.islands = islands;  // the other island options: identify's defaults
  o.max_wall_time_s = budget.max_wall_s;
  o.generations = static_cast<int>(std::max<uint64_t>(
      1, budget.max_evaluations / static_cast<uint64_t>(islands * std::max(1, o.es.offspring))));
  const auto start = Clock::now();
  // The best-so-far curve of the search (its best on the one-step cost after every generation),
  // then the final answer.
  auto push = [&r, &p](uint64_t evaluations, double wall_s, double cost, const std::vector<double>& values) {
    const Errors e = relativeErrors(values, p.truth_values);
    TracePoint t{evaluations, wall_s, cost, e.median, e.max};
    if (!r.trace.empty() && r.trace.back().evaluations == t.evaluations) r.trace.back() = t;
    else if (r.trace.empty() || t.evaluations >= r.trace.back().evaluations + 1 + r.trace.back().evaluations / 40)
      r.trace.push_back(t);
  };
  std::function<void(const mme::Progress&)> progress;
  if (keep_trace)
    progress = [&](const mme::Progress& pr) {
      if (pr.message.empty() && !pr.best_values.empty())
        push(pr.evaluations, pr.wall_time_s, pr.best_cost, pr.best_values);
    };
  mme::IdentifyResult result;
  try {
    result = mme::identifyModel(p.model, p.data, o, progress);
  } catch (const std::exception& e) {
    r.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
    r.values.assign(p.space->size(), std::numeric_limits<double>::quiet_NaN());
    r.cost = kInf;
    r.errors.median = r.errors.max = 1e300;
    r.note = std::string("identify failed: ") + e.what();
    return r;
  }
  r.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  r.values = result.values;
  r.evaluations = result.evaluations;  // the search's; the output-error solve is not counted
  r.generations = result.generations;
  r.errors = relativeErrors(r.values, p.truth_values);
  // The one-step cost of the answer at the problem's substeps, comparable with the others'.
  r.cost = p.cost->evaluate(r.values, nullptr);
  if (!std::isfinite(r.cost)) r.cost = kInf;
  r.estimator = result.estimator;
  r.substeps = result.substeps;
  r.noise_estimate_m = result.noise_estimate_m;
  if (result.estimator == mme::Estimator::kOutputError) r.residual_std_m = result.noise_std_m;
  for (mme::ParameterFlag f : result.flags) r.flagged += f != mme::ParameterFlag::kNone;
  for (auto [ms, threshold] : {std::make_pair(&r.to_1pct, 1.0), std::make_pair(&r.to_001pct, 0.01)})
    if (r.errors.max < threshold) {
      ms->reached = true;
      ms->evaluations = r.evaluations;
      ms->wall_s = r.wall_s;
      ms->generations = r.generations;
    }
  if (keep_trace) push(r.evaluations, r.wall_s, r.cost, r.values);
  char note[256];
  std::snprintf(note, sizeof(note), "final answer: %s; stop %s; substeps %d; noise estimate %.2g m; "
                "%d widening(s); %d flagged", mme::estimatorName(result.estimator), mme::identifyStopName(result.stop),
                result.substeps, result.noise_estimate_m, result.bound_widenings, r.flagged);
  r.note = note;
  return r;
}

// ---------------------------------------------------------------- NLopt BOBYQA, multi-start
struct NloptContext {
  Tracker* tracker;
  nlopt::opt* opt;
};

double nloptObjective(const std::vector<double>& x, std::vector<double>& /*grad*/, void* data) {
  auto* ctx = static_cast<NloptContext*>(data);
  if (ctx->tracker->done()) {
    ctx->opt->force_stop();
    return 1e300;
  }
  return ctx->tracker->evaluate(x);
}

RunResult runBobyqa(const Problem& p, uint64_t seed, const Budget& budget, bool keep_trace) {
  RunResult r;
  Tracker tracker(p, budget, keep_trace);
  Starts starts(p, seed);
  const size_t n = p.space->size();
  std::vector<double> lo(n), hi(n), step(n);
  for (size_t k = 0; k < n; ++k) {
    const mme::Gene& g = p.space->gene(k);
    lo[k] = g.lower;
    hi[k] = g.upper;
    // Initial trust region: the spread of the paper's initial distribution.
    step[k] = std::min(std::max(g.init_spread, 1e-3 * (g.upper - g.lower)), 0.25 * (g.upper - g.lower));
  }
  while (!tracker.done()) {
    std::vector<double> x = starts.next();
    nlopt::opt opt(nlopt::LN_BOBYQA, static_cast<unsigned>(n));
    opt.set_lower_bounds(lo);
    opt.set_upper_bounds(hi);
    opt.set_initial_step(step);
    NloptContext ctx{&tracker, &opt};
    opt.set_min_objective(nloptObjective, &ctx);
    opt.set_maxeval(static_cast<int>(std::min<uint64_t>(tracker.remaining() + 1, 1u << 30)));
    opt.set_ftol_rel(1e-15);
    opt.set_xtol_abs(1e-12);
    double fx = 0.0;
    try {
      opt.optimize(x, fx);
    } catch (const std::exception&) {
      // forced stop or roundoff-limited: the tracker holds the best point
    }
    ++r.restarts;
  }
  if (r.restarts > 0) --r.restarts;
  tracker.finish(&r);
  return r;
}

// ---------------------------------------------------------------- pagmo2 (CMA-ES, SADE)
#ifdef MME_HAVE_PAGMO
struct PagmoProblem {
  Tracker* tracker = nullptr;
  std::vector<double> lower, upper;
  pagmo::vector_double fitness(const pagmo::vector_double& x) const { return {tracker->evaluate(x)}; }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const { return {lower, upper}; }
};

RunResult runPagmo(const Problem& p, uint64_t seed, const Budget& budget, bool keep_trace, bool cmaes) {
  RunResult r;
  Tracker tracker(p, budget, keep_trace);
  Starts starts(p, seed);
  const size_t n = p.space->size();
  PagmoProblem udp;
  udp.tracker = &tracker;
  for (size_t k = 0; k < n; ++k) {
    udp.lower.push_back(p.space->gene(k).lower);
    udp.upper.push_back(p.space->gene(k).upper);
  }
  // CMA-ES: the standard lambda = 4 + 3 ln n; initial mean = the best of the first lambda
  // starts (pagmo's rule), sigma0 = 1/6 of each gene's range (the paper's initial spread);
  // samples outside the bounds are reflected by the cost (like the engine's moves).
  // SADE (jDE adaptation, rand/1/exp): population max(20, n) from the starts.
  const size_t size = cmaes ? 4 + static_cast<size_t>(std::floor(3.0 * std::log(static_cast<double>(n))))
                            : std::max<size_t>(20, n);
  const int stall_limit = cmaes ? 100 + static_cast<int>(20 * n / size) : 200;
  int generations = 0;
  while (!tracker.done()) {
    pagmo::population pop{pagmo::problem{udp}};
    while (pop.size() < size && !tracker.done()) pop.push_back(starts.next());
    if (pop.size() < size) break;
    const unsigned algo_seed = static_cast<unsigned>(seed * 7919u + static_cast<unsigned>(r.restarts));
    pagmo::algorithm algo = cmaes
        ? pagmo::algorithm{pagmo::cmaes(1u, -1, -1, -1, -1, 1.0 / 6.0, 0.0, 1e-13, true, false, algo_seed)}
        : pagmo::algorithm{pagmo::sade(1u, 2u, 1u, 0.0, 0.0, true, algo_seed)};
    double run_best = kInf;
    int stalled = 0;
    while (!tracker.done()) {
      const uint64_t before = tracker.evaluations();
      pop = algo.evolve(pop);
      tracker.setGenerations(++generations);
      if (tracker.evaluations() == before) break;  // stopped by its own tolerance
      const double champion = pop.champion_f()[0];
      if (champion < run_best * (1.0 - 1e-9)) {
        run_best = champion;
        stalled = 0;
      } else if (++stalled > stall_limit) {
        break;
      }
    }
    ++r.restarts;
  }
  if (r.restarts > 0) --r.restarts;
  tracker.finish(&r);
  return r;
}
#endif

// ---------------------------------------------------------------- Ceres Levenberg-Marquardt
#ifdef MME_HAVE_CERES
/// The cost's own residuals (ShortTermCost::residuals: predicted minus observed position, x y z
/// per term), the same least-squares form the engine's Levenberg-Marquardt refinement uses.
struct CostResiduals {
  const Problem* problem;
  Tracker* tracker;
  bool operator()(double const* const* parameters, double* residuals) const {
    const size_t n = problem->space->size();
    const std::vector<double> genes(parameters[0], parameters[0] + n);
    thread_local std::vector<double> r;
    const double total = problem->cost->residuals(problem->space->toPhysical(genes), &r);
    std::copy(r.begin(), r.end(), residuals);
    tracker->counted(genes, total);
    return std::isfinite(total);
  }
};

struct StopCallback : public ceres::IterationCallback {
  Tracker* tracker;
  explicit StopCallback(Tracker* t) : tracker(t) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return tracker->done() ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }
};

RunResult runLm(const Problem& p, uint64_t seed, const Budget& budget, bool keep_trace) {
  RunResult r;
  Tracker tracker(p, budget, keep_trace);
  Starts starts(p, seed);
  const size_t n = p.space->size();
  const int residual_count = static_cast<int>(p.cost->residualCount());
  while (!tracker.done()) {
    std::vector<double> x = starts.next();
    ceres::Problem::Options problem_options;
    ceres::Problem problem(problem_options);
    // Forward differences: n + 1 evaluations per Jacobian, as the engine's refinement.
    auto* cost = new ceres::DynamicNumericDiffCostFunction<CostResiduals, ceres::FORWARD>(
        new CostResiduals{&p, &tracker});
    cost->AddParameterBlock(static_cast<int>(n));
    cost->SetNumResiduals(residual_count);
    problem.AddResidualBlock(cost, nullptr, x.data());
    for (size_t k = 0; k < n; ++k) {
      problem.SetParameterLowerBound(x.data(), static_cast<int>(k), p.space->gene(k).lower);
      problem.SetParameterUpperBound(x.data(), static_cast<int>(k), p.space->gene(k).upper);
    }
    ceres::Solver::Options options;
    options.minimizer_type = ceres::TRUST_REGION;
    options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    options.linear_solver_type = ceres::DENSE_QR;
    options.max_num_iterations = 100000;
    options.function_tolerance = 1e-16;
    options.gradient_tolerance = 1e-30;
    options.parameter_tolerance = 1e-14;
    options.num_threads = 1;
    options.logging_type = ceres::SILENT;
    options.minimizer_progress_to_stdout = false;
    StopCallback stop(&tracker);
    options.callbacks.push_back(&stop);
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    ++r.restarts;
  }
  if (r.restarts > 0) --r.restarts;
  tracker.finish(&r);
  return r;
}
#endif

// ---------------------------------------------------------------- equation-error LLS
RunResult runLls(const Problem& p, const Budget& budget) {
  RunResult r;
  Tracker tracker(p, budget, false);
  std::vector<double> values;
  std::string why;
  if (!solveEquationError(p, &values, &why)) {
    r.applicable = false;
    r.note = "n/a: " + why;
    tracker.finish(&r);
    r.errors.median = r.errors.max = std::numeric_limits<double>::quiet_NaN();
    return r;
  }
  std::vector<double> genes = p.space->toSearch(values);
  bool inside = true;
  for (size_t k = 0; k < values.size(); ++k) {
    const mme::Gene& g = p.space->gene(k);
    if (!std::isfinite(genes[k])) {  // a log gene of a value <= 0
      inside = false;
      genes[k] = g.lower;
    }
  }
  // One cost evaluation of the answer (LLS itself evaluates no cost); reported values are the
  // raw solution even when it leaves the search bounds.
  tracker.counted(genes, p.cost->evaluate(values, nullptr));
  tracker.finish(&r);
  r.values = values;
  r.errors = relativeErrors(values, p.truth_values);
  r.to_1pct.reached = r.errors.max < 1.0;
  r.to_001pct.reached = r.errors.max < 0.01;
  for (Milestone* m : {&r.to_1pct, &r.to_001pct})
    if (m->reached) {
      m->evaluations = 1;
      m->wall_s = r.wall_s;
    }
  r.note = inside ? "one solve" : "one solve (left the bounds)";
  return r;
}

}  // namespace

bool solveEquationError(const Problem& p, std::vector<double>* values, std::string* why) {
  // The peer "LLS" is the paper's linear least squares on linear springs (llsVerdict, problem.cpp);
  // the solve is the library's equation error (estimators/equation_error.h).
  if (!p.lls_applicable) {
    *why = p.lls_reason;
    return false;
  }
  const mme::EquationErrorResult solved = mme::solveEquationError(p.model, p.data);
  if (!solved.applicable) {
    *why = solved.reason;
    return false;
  }
  if (solved.values.size() != p.space->refs().size()) {
    *why = "the equation error's parameters are not the problem's";
    return false;
  }
  *values = solved.values;
  return true;
}

RunResult runMethod(const std::string& method, const Problem& problem, uint64_t seed,
                    const Budget& budget, bool keep_trace) {
  RunResult r;
  if (method != "default" && method != "islands" && method != "lls" && problem.cost->termCount() == 0) {
    // Occlusion left no (particle, frame) term of the one-step cost (each needs three frames of
    // a particle and two of its neighbours): the cost is zero everywhere, nothing to minimise.
    r.method = method;
    r.applicable = false;
    r.note = "n/a: the one-step cost has no terms (occlusion)";
    r.values.assign(problem.space->size(), std::numeric_limits<double>::quiet_NaN());
    r.errors.median = r.errors.max = std::numeric_limits<double>::quiet_NaN();
    return r;
  }
  if (method == "default") r = runDefault(problem, seed, budget, keep_trace, 1);
  else if (method == "islands") r = runDefault(problem, seed, budget, keep_trace, kIslands);
  else if (method == "es_local") r = runEs(problem, seed, budget, keep_trace, true, Schedule::kPaper);
  else if (method == "es_early")
    r = runEs(problem, seed, budget, keep_trace, true, Schedule::kEarlyBobyqa);
  else if (method == "es_lm") r = runEs(problem, seed, budget, keep_trace, true, Schedule::kEarlyLm);
  else if (method == "es_global")
    r = runEs(problem, seed, budget, keep_trace, false, Schedule::kPaper);
  else if (method == "bobyqa") r = runBobyqa(problem, seed, budget, keep_trace);
  else if (method == "lls") r = runLls(problem, budget);
#ifdef MME_HAVE_PAGMO
  else if (method == "cmaes") r = runPagmo(problem, seed, budget, keep_trace, true);
  else if (method == "sade") r = runPagmo(problem, seed, budget, keep_trace, false);
  else if (method == "sade_final") {
    Budget no_oracle = budget;
    no_oracle.stop_max_error_pct = 0.0;  // its best point at the budget's end is the answer
    r = runPagmo(problem, seed, no_oracle, keep_trace, false);
  }
#endif
#ifdef MME_HAVE_CERES
  else if (method == "lm") r = runLm(problem, seed, budget, keep_trace);
#endif
  else throw std::invalid_argument("method not available: " + method);
  r.method = method;
  r.bounded = r.applicable && rolloutBounded(problem, r.values, r.substeps);
  return r;
}

}  // namespace bench

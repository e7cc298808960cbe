#include "motion_model_estimation/identification/identifier.h"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>
#include <memory>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/stiffness.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"
#include "motion_model_estimation/identification/search/residual_jacobian.h"
#include "output_error_step.h"

namespace mme {

std::string validateOptions(const IdentifyOptions& o) {
  const std::string es = validateOptions(o.es);
  if (!es.empty()) return es;
  const std::string islands = validateOptions(o.islands);
  if (!islands.empty()) return islands;
  if (o.generations < 1) return "generations must be >= 1";
  if (!(o.target_cost >= 0.0)) return "target_cost must be >= 0";
  if (!(o.max_wall_time_s >= 0.0)) return "max_wall_time_s must be >= 0";
  if (o.patience_generations < 0) return "patience_generations must be >= 0";
  return "";
}

IdentifyOptions identifyOptionsFor(Preset preset) {
  IdentifyOptions o;
  o.es = esOptionsFor(preset);
  if (preset == Preset::kPaper) {
    // The paper's method as it was: random starts, its bounds, its cost, the whole budget.
    o.patience_generations = 0;
    o.equation_error_start = false;
    o.values_start = false;
    o.max_bound_widenings = 0;
    o.cost = CostChoice::kShortTerm;
  }
  return o;
}

const char* identifyStopName(IdentifyStop stop) {
  switch (stop) {
    case IdentifyStop::kGenerations: return "generation budget";
    case IdentifyStop::kTargetCost: return "target cost";
    case IdentifyStop::kWallTime: return "wall-time limit";
    case IdentifyStop::kConverged: return "converged";
    case IdentifyStop::kCancelled: return "interrupted";
  }
  return "?";
}

std::vector<ParameterFlag> parameterFlags(const ParameterSpace& space, const std::vector<double>& genes,
                                          const std::vector<uint8_t>* unidentifiable) {
  std::vector<ParameterFlag> flags(space.size(), ParameterFlag::kNone);
  for (size_t k = 0; k < space.size(); ++k) {
    const int side = space.boundSide(k, genes[k]);
    if (side < 0) flags[k] = ParameterFlag::kAtLowerBound;
    else if (side > 0) flags[k] = ParameterFlag::kAtUpperBound;
    else if (unidentifiable && (*unidentifiable)[k]) flags[k] = ParameterFlag::kUnidentifiable;
  }
  return flags;
}

GeneUncertainty estimateStdDevs(const Cost& cost, const ParameterSpace& space,
                                const std::vector<double>& genes, ThreadPool* pool) {
  // Gauss-Newton at the answer (covariance.h): J the residuals' Jacobian over the smooth genes
  // (a threshold has no slope: no std), s^2 = cost / (residuals - genes).
  const size_t n = genes.size();
  GeneUncertainty out;
  out.std_devs.assign(n, std::numeric_limits<double>::quiet_NaN());
  out.unidentifiable.assign(n, 0);
  std::vector<size_t> active;
  for (size_t k = 0; k < n; ++k)
    if (space.gene(k).smooth) active.push_back(k);
  const double dof = static_cast<double>(cost.residualCount()) - static_cast<double>(n);
  if (active.empty()) return out;
  if (dof <= 0) {
    out.failure = "the one-step cost has no more residuals than parameters";
    return out;
  }
  std::vector<double> r;
  const double c = cost.residuals(space.toPhysical(genes), &r);
  if (!std::isfinite(c)) {
    out.failure = "the one-step cost is not finite at the answer";
    return out;
  }
  const Eigen::VectorXd residual =
      Eigen::Map<const Eigen::VectorXd>(r.data(), static_cast<Eigen::Index>(r.size()));
  ResidualJacobian jac;
  if (!forwardJacobian(cost, space, genes, residual, active, 100000000, pool, &jac)) {
    out.failure = "the one-step cost's Jacobian is too large to store";
    return out;
  }
  CovarianceOptions options;
  options.residual_variance = std::max(c, 0.0) / dof;
  const ParameterCovariance covariance =
      parameterCovariance(jac.toSparse(), static_cast<Eigen::Index>(active.size()), options);
  return geneUncertainty(covariance, space, genes, active);
}

namespace {

/// A default bound the answer reached moves this far out (a factor for log genes, ranges for
/// linear ones).
constexpr double kWidenFactor = 10.0;
/// A one-step fit with an RMS residual below this [m] is exact: the data hold no noise to filter.
constexpr double kExactFitRms_m = 1e-9;
/// Converged: the best cost fell by less than this share over the patience generations (a
/// crawl that small moves no parameter that matters; noisy costs crawl for hundreds).
constexpr double kPatienceShare = 1e-4;
/// The one-step cost is starved when its terms are fewer than this share of the observed samples.
constexpr double kStarvedShare = 0.5;
/// A one-step residual this many times what white marker noise alone gives (sqrt(6) sigma per
/// coordinate) is a model that does not explain the motion: the output error may be deferred
/// (IdentifyOptions::defer_output_error_on_misfit). A passive scene's residual sits near 1x.
constexpr double kDeferMisfitFactor = 2.0;

std::string formatValue(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", v);
  return text;
}

/// Smooth genes within 1 % of a default (not user-given) bound, with the side (-1 lower, +1
/// upper): the bounds identification may widen.
std::vector<std::pair<size_t, int>> widenableAtBound(const ParameterSpace& space,
                                                     const std::vector<double>& genes) {
  std::vector<std::pair<size_t, int>> out;
  for (size_t k = 0; k < space.size(); ++k) {
    const Gene& g = space.gene(k);
    if (!g.smooth || g.clamp_length) continue;
    const int side = space.boundSide(k, genes[k]);
    if (side != 0 && !(side < 0 ? g.user_lower : g.user_upper)) out.emplace_back(k, side);
  }
  return out;
}

/// Physical values -> one individual's genes, for a seed of the first population: a value outside
/// a default (not user-given) bound widens that bound to include it (and says so); unusable
/// values (non-finite, not positive on a log scale, a clamp-length gene) take the initial centre.
std::vector<double> seedGenes(const std::vector<double>& values, const std::string& what,
                              ParameterSpace* space, std::vector<std::string>* notes) {
  std::vector<double> genes(space->size());
  for (size_t k = 0; k < space->size(); ++k) {
    const Gene& g = space->gene(k);
    const double v = values[k];
    const bool usable = std::isfinite(v) && (!g.log_scale || v > 0.0) && !g.clamp_length;
    if (!usable) {
      genes[k] = g.init_center;
      continue;
    }
    const double gene = g.log_scale ? std::log(v) : v;
    double lo = g.lower, hi = g.upper;
    const double margin = g.log_scale ? std::log(3.0) : 0.5 * (hi - lo);
    if (gene < lo && !g.user_lower) lo = gene - margin;
    if (gene > hi && !g.user_upper) hi = gene + margin;
    if (lo != g.lower || hi != g.upper) {
      notes->push_back("'" + g.ref.name + "': " + what + " " + formatValue(v) +
                       " lies outside the default search bounds: bounds widened to include it");
      space->setBounds(k, lo, hi);
    }
    genes[k] = std::min(std::max(gene, space->gene(k).lower), space->gene(k).upper);
  }
  return genes;
}

/// Equation-error starts (raw and smoothed differences) as gene vectors; a value outside a
/// default bound widens it (beyond a user's bound it is clamped), an undetermined one is left
/// at the initial distribution's centre. Notes what it widened.
std::vector<std::vector<double>> equationErrorSeeds(const Model& model, const Trajectory& trajectory,
                                                    ParameterSpace* space,
                                                    std::vector<std::string>* notes) {
  std::vector<std::vector<double>> seeds;
  // Types whose rest length enters non-linearly (free k, L, k_nl with values): Gauss-Newton steps
  // of the linearised equation error from the model's values.
  bool linearized = false;
  for (const BondType& t : model.bond_types)
    linearized = linearized || (t.kind == BondKind::kSpring && t.param(kStiffness).free &&
                                t.param(kRestLength).free && t.param(kRestLength).has_value &&
                                t.param(kStiffnessNl).free);
  const std::vector<ParamRef> refs = freeParameters(model);
  for (int half_width : {0, 3}) {
    EquationErrorOptions o;
    o.smoothing_half_width = half_width;
    o.linearize_rest_length = linearized;
    EquationErrorResult ee = solveEquationError(model, trajectory, o);
    if (!ee.applicable) break;
    Model step = model;
    for (int iteration = 1; linearized && iteration < 10; ++iteration) {
      bool finite = true;
      for (double v : ee.values) finite = finite && std::isfinite(v);
      if (!finite) break;
      setValues(step, refs, ee.values);
      ee = solveEquationError(step, trajectory, o);
      if (!ee.applicable) break;
    }
    if (!ee.applicable) break;
    seeds.push_back(seedGenes(ee.values, "the equation-error start", space, notes));
  }
  return seeds;
}

}  // namespace

bool parseCostChoice(const std::string& name, CostChoice* choice) {
  if (name == "auto") *choice = CostChoice::kAuto;
  else if (name == "short_term") *choice = CostChoice::kShortTerm;
  else if (name == "output_error") *choice = CostChoice::kOutputError;
  else return false;
  return true;
}

const char* costChoiceName(CostChoice choice) {
  switch (choice) {
    case CostChoice::kAuto: return "auto";
    case CostChoice::kShortTerm: return "short_term";
    case CostChoice::kOutputError: return "output_error";
  }
  return "?";
}

namespace {

/// The positions of the first frame where every particle is seen (else the model's) [m].
std::vector<Eigen::Vector3d> referencePositions(const Model& model, const Trajectory& trajectory) {
  const int n = static_cast<int>(model.particles.size());
  for (int t = 0; t < trajectory.numFrames(); ++t) {
    bool all = true;
    for (int i = 0; i < n && all; ++i) all = !trajectory.isOccluded(t, i);
    if (!all) continue;
    return std::vector<Eigen::Vector3d>(trajectory.positions_m.begin() + t * n,
                                        trajectory.positions_m.begin() + (t + 1) * n);
  }
  std::vector<Eigen::Vector3d> x;
  for (const Particle& p : model.particles) x.push_back(p.position_m);
  return x;
}

}  // namespace

namespace {

/// One identification (identifyModel), its steps as methods over the state they share: the
/// starts, the search on the one-step cost (widening default bounds the answer presses on), the
/// output error where it is wanted (its starts, the stiff-scene substeps, the final fit), and the
/// result with its flags and uncertainties.
class Identification {
 public:
  /// `search` false: no evolution strategy, the first seed (the model's values) is the answer
  /// the output error starts from (runDeferredOutputError).
  Identification(const Model& model, const Trajectory& trajectory, const IdentifyOptions& options,
                 const std::function<void(const Progress&)>& progress, bool search = true)
      : options_(options), progress_(progress), trajectory_(trajectory), model_(model), search_(search),
        start_(std::chrono::steady_clock::now()),
        cost_(std::make_shared<ShortTermCost>(model_, trajectory_)),
        no_terms_(cost_->termCount() == 0) {
    // Without a single one-step term (heavy occlusion) only the output error can use the data.
    if (no_terms_ && options_.cost == CostChoice::kShortTerm)
      throw InputError("no usable (particle, frame) terms for the one-step cost: too few frames or "
                       "too much occlusion (--cost auto or output_error uses every observed sample)");
    if (!(model_.frame_rate_hz > 0.0)) model_.frame_rate_hz = trajectory_.frame_rate_hz;
    space_ = std::make_unique<ParameterSpace>(model_, trajectory_);
    for (size_t k = 0; k < space_->size(); ++k) has_threshold_genes_ = has_threshold_genes_ || !space_->gene(k).smooth;
  }

  IdentifyResult run() {
    prepareSeeds();
    if (!no_terms_ && search_) {
      search();
    } else if (no_terms_) {
      note("the one-step cost has no term (each needs three frames of a particle and two of its "
           "neighbours): the output error alone, from the equation-error start or the initial "
           "distribution's centre");
    }
    // The search's answer, or without a search the best start there is.
    best_genes_.resize(space_->size());
    for (size_t k = 0; k < space_->size(); ++k) best_genes_[k] = space_->gene(k).init_center;
    if (!seeds_.empty()) best_genes_ = seeds_.front();
    if (es_) best_genes_ = es_->best().genes;
    reference_ = referencePositions(model_, trajectory_);
    omega_h_ = omegaH(space_->toPhysical(best_genes_));
    r_.parameters = space_->refs();
    r_.values = space_->toPhysical(best_genes_);
    r_.global_cost = es_ ? es_->best().cost : std::numeric_limits<double>::infinity();
    r_.estimator = Estimator::kShortTerm;
    r_.noise_estimate_m = estimateMarkerNoise(trajectory_);
    r_.one_step_rms_m = std::sqrt(r_.global_cost / std::max<double>(1.0, cost_->residualCount()));
    unidentifiable_.assign(space_->size(), 0);
    if (stop_ != IdentifyStop::kWallTime && stop_ != IdentifyStop::kCancelled && wantsOutputError()) {
      if (defersOutputError())
        r_.output_error_deferred = true;
      else
        runOutputError();
    }
    return result();
  }

 private:
  bool cancelled() const { return options_.cancel && options_.cancel->load(); }

  double elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

  /// A note for the result, also passed on as a progress message.
  void note(const std::string& text) {
    notes_.push_back(text);
    if (!progress_) return;
    Progress p;
    p.generation = generations_done_;
    p.evaluations = evaluations_done_;
    p.wall_time_s = elapsed();
    p.message = text;
    progress_(p);
  }

  /// The first population's seeds: the equation-error starts, and a complete guess (every free
  /// parameter with a value, e.g. a model identified before) as it is, so that the search never
  /// ends worse than it.
  void prepareSeeds() {
    std::vector<std::string> seed_notes;
    if (options_.equation_error_start)
      seeds_ = equationErrorSeeds(model_, trajectory_, space_.get(), &seed_notes);
    if (options_.values_start) {
      const std::vector<ParamRef> refs = freeParameters(model_);
      bool complete = !refs.empty();
      for (const ParamRef& r : refs) complete = complete && paramOf(model_, r).has_value;
      if (complete)
        seeds_.insert(seeds_.begin(), seedGenes(getValues(model_, refs), "the model's value",
                                                space_.get(), &seed_notes));
    }
    for (const std::string& text : seed_notes) note(text);
  }

  /// The global search on the one-step cost: widening a default bound the refined best presses
  /// on and resuming from that best (a bounded number of times).
  void search() {
    while (true) {
      const bool at_default_bound = runGenerations();
      generations_done_ += es_->generation();
      evaluations_done_ += es_->evaluations();
      countIslands();
      if (stop_ == IdentifyStop::kTargetCost || stop_ == IdentifyStop::kWallTime ||
          stop_ == IdentifyStop::kCancelled ||
          widenings_ >= options_.max_bound_widenings || generations_done_ >= options_.generations)
        return;
      if (!at_default_bound && widenableAtBound(*space_, es_->best().genes).empty()) return;
      const std::vector<double> best = es_->best().genes;
      widenBoundsAt(best);
      ++widenings_;
      seeds_.insert(seeds_.begin(), best);
    }
  }

  /// One run of the evolution strategy from the seeds until a stop rule; true when it stopped
  /// because a refined best pressed on a default bound (the answer lies beyond it).
  bool runGenerations() {
    // Converged: over the last `patience` generations the best cost fell by less than a
    // relative kPatienceShare, or it sits at the round-off floor.
    const double floor_m2 = 1e-26 * static_cast<double>(cost_->residualCount());
    es_ = std::make_unique<IslandModel>(*space_, options_.es, options_.islands);
    es_->setCost(cost_);
    es_->setSeeds(seeds_);
    if (options_.max_wall_time_s > 0.0)
      es_->setDeadline(start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                    std::chrono::duration<double>(options_.max_wall_time_s)));
    es_->setCancel(options_.cancel);
    std::vector<double> best_after;  // per generation of this run
    int refinements_seen = 0;
    stop_ = IdentifyStop::kGenerations;
    while (generations_done_ + es_->generation() < options_.generations) {
      es_->step();
      const double best = es_->best().cost;
      best_after.push_back(best);
      reportGeneration(best);
      if (options_.target_cost > 0.0 && best <= options_.target_cost) {
        stop_ = IdentifyStop::kTargetCost;
        return false;
      }
      if (options_.max_wall_time_s > 0.0 && elapsed() >= options_.max_wall_time_s) {
        stop_ = IdentifyStop::kWallTime;
        return false;
      }
      if (cancelled()) {
        stop_ = IdentifyStop::kCancelled;
        return false;
      }
      if (es_->refinements() != refinements_seen) {
        refinements_seen = es_->refinements();
        if (widenings_ < options_.max_bound_widenings &&
            !widenableAtBound(*space_, es_->best().genes).empty())
          return true;
      }
      if (converged(best_after, floor_m2)) {
        stop_ = IdentifyStop::kConverged;
        return false;
      }
    }
    return false;
  }

  void reportGeneration(double best_cost) {
    if (!progress_) return;
    Progress p;
    p.generation = generations_done_ + es_->generation();
    p.evaluations = evaluations_done_ + es_->evaluations();
    p.best_cost = best_cost;
    p.wall_time_s = elapsed();
    p.best_values = es_->bestValues();
    progress_(p);
  }

  /// Thresholds (conditional bonds) make the cost piecewise: a refinement can settle in a wrong
  /// interval's local optimum that the evolution strategy leaves only after tens of generations
  /// more (a cable object left 50 generations flat at 4.6 % off, then found the basin at
  /// generation 92), so the patience doubles where there is one.
  bool converged(const std::vector<double>& best_after, double floor_m2) const {
    const int patience = options_.patience_generations * (has_threshold_genes_ ? 2 : 1);
    const size_t g = best_after.size();
    const double best = best_after.back();
    return patience > 0 && es_->refinements() > 0 &&
           (best <= floor_m2 || (g > static_cast<size_t>(patience) &&
                                 best_after[g - 1 - patience] - best <= kPatienceShare * best_after[g - 1 - patience]));
  }

  /// Adds the last search's per-island evaluations and accepted immigrants to the run's.
  void countIslands() {
    const size_t n = static_cast<size_t>(es_->islandCount());
    island_evaluations_.resize(n, 0);
    island_accepted_.resize(n, 0);
    for (size_t i = 0; i < n; ++i) {
      island_evaluations_[i] += es_->islandEvaluations(static_cast<int>(i));
      island_accepted_[i] += es_->immigrantsAccepted(static_cast<int>(i));
    }
    migrations_ += es_->migrations();
  }

  /// Widens every default bound `best` presses on by kWidenFactor, and says so.
  void widenBoundsAt(const std::vector<double>& best) {
    for (const std::pair<size_t, int>& hit : widenableAtBound(*space_, best)) {
      const size_t k = hit.first;
      const int side = hit.second;
      const Gene& g = space_->gene(k);
      const double step = g.log_scale ? std::log(kWidenFactor) : (kWidenFactor - 1.0) * (g.upper - g.lower);
      const double lo = side < 0 ? g.lower - step : g.lower, hi = side > 0 ? g.upper + step : g.upper;
      const double value = space_->toPhysical(best)[k];
      const std::string name = g.ref.name;
      const bool log_scale = g.log_scale;
      space_->setBounds(k, lo, hi);
      const Gene& wide = space_->gene(k);
      note("'" + name + "' ended at its default " + (side < 0 ? "lower" : "upper") +
           " search bound (" + formatValue(value) + "): bounds widened to [" +
           formatValue(log_scale ? std::exp(wide.lower) : wide.lower) + ", " +
           formatValue(log_scale ? std::exp(wide.upper) : wide.upper) + "], search resumed");
    }
  }

  /// The stiffest mode's angular frequency times the frame period, at `values`.
  double omegaH(const std::vector<double>& values) const {
    Model m = model_;
    setValues(m, space_->refs(), values);
    return stiffestModeRadPerS(m, reference_) * (1.0 / model_.frame_rate_hz);
  }

  /// Whether the output error gives the answer. Auto: when the markers look noisy and the
  /// one-step fit is not exact (a fit to round-off means noiseless data the one-step model
  /// explains: nothing to gain), or when the one-step cost leaves out most observed samples
  /// (each of its terms needs three frames of a particle and two of its neighbours: occlusion
  /// then starves it, an exact fit of a few terms can be wrong, and the output error uses every
  /// sample).
  bool wantsOutputError() {
    const double fit_rms_m = std::sqrt(r_.global_cost / std::max<double>(1.0, cost_->residualCount()));
    size_t observed = 0;
    for (int t = 0; t < trajectory_.numFrames(); ++t)
      for (int i = 0; i < trajectory_.numMarkers(); ++i)
        observed += !model_.particles[i].fixed && !trajectory_.isOccluded(t, i);
    const bool starved = no_terms_ || (trajectory_.numFrames() >= 3 &&
                                       static_cast<double>(cost_->termCount()) < kStarvedShare * static_cast<double>(observed));
    starved_ = starved;
    const bool output_error =
        options_.cost == CostChoice::kOutputError ||
        (options_.cost == CostChoice::kAuto &&
         (starved || (r_.noise_estimate_m >= options_.auto_noise_threshold_m && fit_rms_m >= kExactFitRms_m)));
    if (output_error && options_.cost == CostChoice::kAuto && starved)
      note("the one-step cost uses " + std::to_string(cost_->termCount()) + " of " +
           std::to_string(observed) + " observed samples (occlusion): the output error uses all");
    return output_error;
  }

  /// The output error left to the caller (IdentifyOptions::defer_output_error_on_misfit): the
  /// search's one-step residual is kDeferMisfitFactor times what the markers' noise gives, and
  /// the one-step cost saw the samples (not starved by occlusion). Says why.
  bool defersOutputError() {
    if (!options_.defer_output_error_on_misfit || options_.cost != CostChoice::kAuto || starved_ || !es_)
      return false;
    const double noise_floor_m = std::sqrt(6.0) * r_.noise_estimate_m;
    if (!(r_.one_step_rms_m > kDeferMisfitFactor * noise_floor_m)) return false;
    note("the search's answer leaves one-step residuals of " + formatValue(r_.one_step_rms_m) +
         " m per coordinate, " + formatValue(r_.one_step_rms_m / std::max(noise_floor_m, 1e-12)) +
         "x what the markers' noise gives (the passive model does not explain the motion): the output "
         "error is deferred, to run only if the sensor muscles do not replace the passive model");
    return true;
  }

  /// The output error (output_error_step.h) from the search's answer; its answer replaces the
  /// search's only where the judge says it predicts no worse.
  void runOutputError() {
    OutputErrorStep step(model_, trajectory_, *space_, options_, reference_, [this] { return elapsed(); },
                         [this](const std::string& text) { note(text); });
    const OutputErrorOutcome outcome = step.run(best_genes_, r_.noise_estimate_m);
    time_cut_ = time_cut_ || outcome.time_cut;
    if (!outcome.adopted) return;
    const OutputErrorResult& oe = outcome.fit;
    model_.substeps = outcome.substeps;
    best_genes_ = oe.genes;
    r_.values = oe.values;
    r_.global_cost = oe.observation_cost_m2;
    r_.noise_std_m = oe.noise_std_m;
    r_.estimator = Estimator::kOutputError;
    r_.std_missing_reason = outcome.std_missing_reason;
    std_devs_ = oe.std_devs;
    unidentifiable_ = oe.unidentifiable;
    if (!oe.std_failure.empty() && r_.std_missing_reason.empty()) r_.std_missing_reason = oe.std_failure;
    omega_h_ = omegaH(r_.values);
  }

  /// A threshold is known only up to the flat interval between the observed lengths where its
  /// condition switches: its std is that interval's (uniform: width / sqrt(12)); an interval
  /// that runs to a search bound means the data never saw the condition switch on that side.
  void thresholdUncertainty() {
    for (size_t k = 0; k < space_->size() && k < std_devs_.size(); ++k) {
      const Gene& g = space_->gene(k);
      if (g.smooth) continue;
      const auto it = std::upper_bound(g.breakpoints.begin(), g.breakpoints.end(), best_genes_[k]);
      if (g.breakpoints.empty() || it == g.breakpoints.begin() || it == g.breakpoints.end()) {
        if (r_.flags[k] == ParameterFlag::kNone) r_.flags[k] = ParameterFlag::kUnidentifiable;
        continue;
      }
      const double lo = *(it - 1), hi = *it;
      const double slope = std::abs(space_->physicalSlope(k, best_genes_));
      std_devs_[k] = slope * (hi - lo) / std::sqrt(12.0);
    }
  }

  /// The one-step answer's std and unidentifiable flags (the output error brings its own).
  void shortTermUncertainty() {
    std_devs_.assign(r_.values.size(), std::numeric_limits<double>::quiet_NaN());
    unidentifiable_.assign(r_.values.size(), 0);
    if (!options_.estimate_std || stop_ == IdentifyStop::kCancelled || !search_) return;
    GeneUncertainty u = estimateStdDevs(*cost_, *space_, best_genes_);
    std_devs_ = std::move(u.std_devs);
    unidentifiable_ = std::move(u.unidentifiable);
    if (!u.failure.empty() && r_.std_missing_reason.empty()) r_.std_missing_reason = u.failure;
  }

  IdentifyResult result() {
    r_.generations = generations_done_;
    r_.evaluations = evaluations_done_;
    r_.frames = trajectory_.numFrames();
    r_.stop = time_cut_ ? IdentifyStop::kWallTime : stop_;
    r_.last_refine_status = es_ ? es_->lastRefineStatus() : RefineStatus::kNotRun;
    r_.bound_widenings = widenings_;
    r_.island_evaluations = island_evaluations_;
    r_.island_immigrants_accepted = island_accepted_;
    r_.migrations = migrations_;
    r_.best_island = es_ ? es_->bestIsland() : 0;
    r_.substeps = model_.substeps;
    r_.stiffest_omega_h = omega_h_;
    r_.notes = notes_;
    if (r_.estimator == Estimator::kShortTerm) shortTermUncertainty();
    r_.flags = parameterFlags(*space_, best_genes_, &unidentifiable_);
    thresholdUncertainty();
    r_.std_devs = std_devs_;
    r_.model = model_;
    setValues(r_.model, r_.parameters, r_.values);
    r_.wall_time_s = elapsed();
    return r_;
  }

  const IdentifyOptions& options_;
  const std::function<void(const Progress&)>& progress_;
  const Trajectory& trajectory_;
  Model model_;
  const bool search_;  ///< run the evolution strategy (false: the output error from the values)
  const std::chrono::steady_clock::time_point start_;
  std::shared_ptr<ShortTermCost> cost_;
  const bool no_terms_;
  bool has_threshold_genes_ = false;  ///< a conditional bond's threshold is searched
  bool starved_ = false;  ///< the one-step cost leaves out most observed samples
  std::unique_ptr<ParameterSpace> space_;
  std::vector<std::vector<double>> seeds_;
  std::vector<std::string> notes_;
  IdentifyStop stop_ = IdentifyStop::kGenerations;
  bool time_cut_ = false;  ///< a time limit ended an output-error fit (never "converged")
  int generations_done_ = 0;
  uint64_t evaluations_done_ = 0;
  int widenings_ = 0;
  std::unique_ptr<IslandModel> es_;  ///< one island: the plain evolution strategy
  std::vector<uint64_t> island_evaluations_, island_accepted_;  ///< summed over the searches
  int migrations_ = 0;
  std::vector<double> best_genes_;
  std::vector<Eigen::Vector3d> reference_;
  double omega_h_ = 0.0;
  IdentifyResult r_;
  std::vector<uint8_t> unidentifiable_;
  std::vector<double> std_devs_;
};

}  // namespace

IdentifyResult identifyModel(const Model& model, const Trajectory& trajectory,
                             const IdentifyOptions& options,
                             const std::function<void(const Progress&)>& progress) {
  const std::string bad = validateOptions(options);
  if (!bad.empty()) throw InputError(bad);
  return Identification(model, trajectory, options, progress).run();
}

IdentifyResult runDeferredOutputError(const IdentifyResult& passive, const Trajectory& trajectory,
                                      const IdentifyOptions& options,
                                      const std::function<void(const Progress&)>& progress) {
  IdentifyOptions o = options;
  o.cost = CostChoice::kOutputError;
  o.defer_output_error_on_misfit = false;
  o.values_start = true;  // the passive answer is the output error's first start
  o.equation_error_start = false;  // the output error tries its own smoothed starts
  const std::string bad = validateOptions(o);
  if (!bad.empty()) throw InputError(bad);
  IdentifyResult out = passive;
  out.output_error_deferred = false;
  if (o.max_wall_time_s > 0.0) {  // the limit counts the passive identification's time too
    o.max_wall_time_s -= passive.wall_time_s;
    if (!(o.max_wall_time_s > 0.0)) {
      out.notes.push_back("the deferred output error did not run: no time left");
      out.stop = IdentifyStop::kWallTime;
      return out;
    }
  }
  const IdentifyResult oe = Identification(passive.model, trajectory, o, progress, false).run();
  out.notes.insert(out.notes.end(), oe.notes.begin(), oe.notes.end());
  out.wall_time_s += oe.wall_time_s;
  if (oe.stop == IdentifyStop::kWallTime || oe.stop == IdentifyStop::kCancelled) out.stop = oe.stop;
  if (oe.estimator != Estimator::kOutputError) return out;
  // The output error's answer, with the search's figures (generations, islands) it started from.
  const IdentifyResult search = out;
  out = oe;
  out.notes = search.notes;
  out.wall_time_s = search.wall_time_s;
  out.stop = search.stop;
  out.generations = search.generations;
  out.evaluations = search.evaluations;
  out.last_refine_status = search.last_refine_status;
  out.bound_widenings = search.bound_widenings;
  out.island_evaluations = search.island_evaluations;
  out.island_immigrants_accepted = search.island_immigrants_accepted;
  out.migrations = search.migrations;
  out.best_island = search.best_island;
  out.one_step_rms_m = search.one_step_rms_m;
  return out;
}

}  // namespace mme

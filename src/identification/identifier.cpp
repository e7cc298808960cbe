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

namespace mme {

std::string validateOptions(const IdentifyOptions& o) {
  const std::string es = validateOptions(o.es);
  if (!es.empty()) return es;
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
  }
  return "?";
}

std::vector<double> estimateStdDevs(const Cost& cost, const ParameterSpace& space,
                                    const std::vector<double>& genes, ThreadPool* pool) {
  // Gauss-Newton: Cov(genes) = s^2 (J^T J)^-1 with s^2 = cost / (residuals - genes), J the
  // residuals' Jacobian over the smooth genes (a threshold has no slope: no std).
  const size_t n = genes.size();
  std::vector<double> out(n, std::numeric_limits<double>::quiet_NaN());
  std::vector<size_t> active;
  for (size_t k = 0; k < n; ++k)
    if (space.gene(k).smooth) active.push_back(k);
  const double dof = static_cast<double>(cost.residualCount()) - static_cast<double>(n);
  if (active.empty() || dof <= 0) return out;
  std::vector<double> r;
  const double c = cost.residuals(space.toPhysical(genes), &r);
  if (!std::isfinite(c)) return out;
  const Eigen::VectorXd residual = Eigen::Map<const Eigen::VectorXd>(r.data(), r.size());
  ResidualJacobian jac;
  if (!forwardJacobian(cost, space, genes, residual, active, 100000000, pool, &jac))
    return out;
  Eigen::MatrixXd jtj;
  Eigen::VectorXd g;
  normalEquations(jac, residual, &jtj, &g);
  const Eigen::Index na = static_cast<Eigen::Index>(active.size());
  Eigen::VectorXd scale(na);
  for (Eigen::Index j = 0; j < na; ++j) scale[j] = jtj(j, j) > 0.0 ? 1.0 / std::sqrt(jtj(j, j)) : 0.0;
  const Eigen::MatrixXd scaled = scale.asDiagonal() * jtj * scale.asDiagonal();
  Eigen::LDLT<Eigen::MatrixXd> ldlt(scaled);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return out;
  const Eigen::MatrixXd inv = ldlt.solve(Eigen::MatrixXd::Identity(na, na));
  const double s2 = std::max(c, 0.0) / dof;
  for (Eigen::Index j = 0; j < na; ++j) {
    const size_t k = active[static_cast<size_t>(j)];
    if (!(scale[j] > 0.0) || !(inv(j, j) >= 0.0)) continue;
    const double gene_std = std::sqrt(s2 * inv(j, j)) * scale[j];
    // Log genes: d(value) = value d(gene); a clamp-length gene: d(tau) = (1 + tau) d(gene).
    out[k] = std::abs(space.physicalSlope(k, genes)) * gene_std;
  }
  return out;
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
/// An output-error residual this many times the data's noise estimate is a misfit worth a word.
constexpr double kMisfitFactor = 2.0;
/// Output-error iterations a start gets before the best start is fitted to convergence.
constexpr int kScoutIterations = 15;
/// The one-step cost is starved when its terms are fewer than this share of the observed samples.
constexpr double kStarvedShare = 0.5;
/// Most substeps per frame the stiff-scene rule asks for.
constexpr int kMaxSubsteps = 64;

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

const char* parameterFlagName(ParameterFlag flag) {
  switch (flag) {
    case ParameterFlag::kNone: return "";
    case ParameterFlag::kAtLowerBound: return "at_lower_bound";
    case ParameterFlag::kAtUpperBound: return "at_upper_bound";
    case ParameterFlag::kUnidentifiable: return "unidentifiable";
  }
  return "?";
}

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

IdentifyResult identifyModel(const Model& input_model, const Trajectory& trajectory,
                             const IdentifyOptions& options,
                             const std::function<void(const Progress&)>& progress) {
  const std::string bad = validateOptions(options);
  if (!bad.empty()) throw InputError(bad);
  const auto start = std::chrono::steady_clock::now();
  Model model = input_model;
  auto cost = std::make_shared<ShortTermCost>(model, trajectory);
  // Without a single one-step term (heavy occlusion) only the output error can use the data.
  const bool no_terms = cost->termCount() == 0;
  if (no_terms && options.cost == CostChoice::kShortTerm)
    throw InputError("no usable (particle, frame) terms for the one-step cost: too few frames or "
                     "too much occlusion (--cost auto or output_error uses every observed sample)");
  if (!(model.frame_rate_hz > 0.0)) model.frame_rate_hz = trajectory.frame_rate_hz;
  ParameterSpace space(model, trajectory);
  bool has_threshold_genes = false;
  for (size_t k = 0; k < space.size(); ++k) has_threshold_genes = has_threshold_genes || !space.gene(k).smooth;
  std::vector<std::string> notes, seed_notes;
  std::vector<std::vector<double>> seeds;
  if (options.equation_error_start)
    seeds = equationErrorSeeds(model, trajectory, &space, &seed_notes);
  if (options.values_start) {
    // A complete guess (every free parameter with a value, e.g. a model identified before) is
    // one individual of the first population as it is: the search never ends worse than it.
    const std::vector<ParamRef> refs = freeParameters(model);
    bool complete = !refs.empty();
    for (const ParamRef& r : refs) complete = complete && paramOf(model, r).has_value;
    if (complete)
      seeds.insert(seeds.begin(), seedGenes(getValues(model, refs), "the model's value", &space,
                                            &seed_notes));
  }
  auto elapsed = [&start]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const auto note = [&](const std::string& text, int generation, uint64_t evaluations) {
    notes.push_back(text);
    if (!progress) return;
    Progress p;
    p.generation = generation;
    p.evaluations = evaluations;
    p.wall_time_s = elapsed();
    p.message = text;
    progress(p);
  };
  for (const std::string& text : seed_notes) note(text, 0, 0);
  IdentifyStop stop = IdentifyStop::kGenerations;
  int generations_done = 0;
  uint64_t evaluations_done = 0;
  int widenings = 0;
  std::unique_ptr<EvolutionStrategy> es;

  // The global search on the one-step cost: widening a default bound the refined best presses
  // on and resuming from that best (a bounded number of times).
  const auto search = [&]() {
    // Converged: over the last `patience` generations the best cost fell by less than a
    // relative kPatienceShare, or it sits at the round-off floor.
    const double floor_m2 = 1e-26 * static_cast<double>(cost->residualCount());
    while (true) {
      es = std::make_unique<EvolutionStrategy>(space, options.es);
      es->setCost(cost);
      es->setSeeds(seeds);
      if (options.max_wall_time_s > 0.0)
        es->setDeadline(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                    std::chrono::duration<double>(options.max_wall_time_s)));
      std::vector<double> best_after;  // per generation of this search
      int refinements_seen = 0;
      bool at_default_bound = false;
      stop = IdentifyStop::kGenerations;
      while (generations_done + es->generation() < options.generations) {
        es->step();
        const double best = es->best().cost;
        best_after.push_back(best);
        if (progress) {
          Progress p;
          p.generation = generations_done + es->generation();
          p.evaluations = evaluations_done + es->evaluations();
          p.best_cost = best;
          p.wall_time_s = elapsed();
          p.best_values = es->bestValues();
          progress(p);
        }
        if (options.target_cost > 0.0 && best <= options.target_cost) {
          stop = IdentifyStop::kTargetCost;
          break;
        }
        if (options.max_wall_time_s > 0.0 && elapsed() >= options.max_wall_time_s) {
          stop = IdentifyStop::kWallTime;
          break;
        }
        if (es->refinements() != refinements_seen) {
          // A refined best pressing on a default bound: the answer lies beyond it.
          refinements_seen = es->refinements();
          if (widenings < options.max_bound_widenings &&
              !widenableAtBound(space, es->best().genes).empty()) {
            at_default_bound = true;
            break;
          }
        }
        // Thresholds (conditional bonds) make the cost piecewise: a refinement can settle in a
        // wrong interval's local optimum that the evolution strategy leaves only after tens of
        // generations more (a cable object left 50 generations flat at 4.6 % off, then found
        // the basin at generation 92), so the patience doubles where there is one.
        const int patience = options.patience_generations * (has_threshold_genes ? 2 : 1);
        const size_t g = best_after.size();
        if (patience > 0 && es->refinements() > 0 &&
            (best <= floor_m2 || (g > static_cast<size_t>(patience) &&
                                  best_after[g - 1 - patience] - best <= kPatienceShare * best_after[g - 1 - patience]))) {
          stop = IdentifyStop::kConverged;
          break;
        }
      }
      generations_done += es->generation();
      evaluations_done += es->evaluations();
      if (stop == IdentifyStop::kTargetCost || stop == IdentifyStop::kWallTime ||
          widenings >= options.max_bound_widenings || generations_done >= options.generations)
        return;
      if (!at_default_bound && widenableAtBound(space, es->best().genes).empty()) return;
      const std::vector<double> best = es->best().genes;
      for (const std::pair<size_t, int>& hit : widenableAtBound(space, best)) {
        const size_t k = hit.first;
        const int side = hit.second;
        const Gene& g = space.gene(k);
        const double step = g.log_scale ? std::log(kWidenFactor) : (kWidenFactor - 1.0) * (g.upper - g.lower);
        const double lo = side < 0 ? g.lower - step : g.lower, hi = side > 0 ? g.upper + step : g.upper;
        const double value = space.toPhysical(best)[k];
        const std::string name = g.ref.name;
        const bool log_scale = g.log_scale;
        space.setBounds(k, lo, hi);
        const Gene& wide = space.gene(k);
        note("'" + name + "' ended at its default " + (side < 0 ? "lower" : "upper") +
                 " search bound (" + formatValue(value) + "): bounds widened to [" +
                 formatValue(log_scale ? std::exp(wide.lower) : wide.lower) + ", " +
                 formatValue(log_scale ? std::exp(wide.upper) : wide.upper) + "], search resumed",
             generations_done, evaluations_done);
      }
      ++widenings;
      seeds.insert(seeds.begin(), best);
    }
  };
  if (!no_terms) {
    search();
  } else {
    note("the one-step cost has no term (each needs three frames of a particle and two of its "
         "neighbours): the output error alone, from the equation-error start or the initial "
         "distribution's centre",
         0, 0);
  }
  // The search's answer, or without a search the best start there is.
  std::vector<double> best_genes(space.size());
  for (size_t k = 0; k < space.size(); ++k) best_genes[k] = space.gene(k).init_center;
  if (!seeds.empty()) best_genes = seeds.front();
  if (es) best_genes = es->best().genes;

  // Stiff scenes: more substeps when the answer's stiffest mode is fast for the frame rate.
  const std::vector<Eigen::Vector3d> reference = referencePositions(model, trajectory);
  const double h = 1.0 / model.frame_rate_hz;
  const auto omegaH = [&](const std::vector<double>& values) {
    Model m = model;
    setValues(m, space.refs(), values);
    return stiffestModeRadPerS(m, reference) * h;
  };
  double omega_h = omegaH(space.toPhysical(best_genes));

  IdentifyResult r;
  r.parameters = space.refs();
  r.values = space.toPhysical(best_genes);
  r.global_cost = es ? es->best().cost : std::numeric_limits<double>::infinity();
  r.estimator = "short_term";
  r.noise_estimate_m = estimateMarkerNoise(trajectory);
  std::vector<uint8_t> unidentifiable(space.size(), 0);
  std::vector<double> std_devs;
  // Auto: the output error when the markers look noisy and the one-step fit is not exact (a
  // fit to round-off means noiseless data the one-step model explains: nothing to gain).
  const double fit_rms_m = std::sqrt(r.global_cost / std::max<double>(1.0, cost->residualCount()));
  // Also when the one-step cost leaves out most observed samples (each of its terms needs three
  // frames of a particle and two of its neighbours): occlusion then starves it, an exact fit of
  // a few terms can be wrong, and the output error uses every sample.
  size_t observed = 0;
  for (int t = 0; t < trajectory.numFrames(); ++t)
    for (int i = 0; i < trajectory.numMarkers(); ++i)
      observed += !model.particles[i].fixed && !trajectory.isOccluded(t, i);
  const bool starved =
      no_terms || (trajectory.numFrames() >= 3 &&
                   static_cast<double>(cost->termCount()) < kStarvedShare * static_cast<double>(observed));
  const bool output_error =
      options.cost == CostChoice::kOutputError ||
      (options.cost == CostChoice::kAuto &&
       (starved || (r.noise_estimate_m >= options.auto_noise_threshold_m && fit_rms_m >= kExactFitRms_m)));
  if (output_error && options.cost == CostChoice::kAuto && starved)
    note("the one-step cost uses " + std::to_string(cost->termCount()) + " of " +
             std::to_string(observed) + " observed samples (occlusion): the output error uses all",
         generations_done, evaluations_done);
  if (output_error && stop != IdentifyStop::kWallTime) {
    // From the search's answer and from the smoothed equation-error solutions (the one-step
    // optimum is biased by noise, badly so at a millimetre); the lowest output-error cost wins.
    std::vector<std::vector<double>> starts{best_genes};
    for (int half_width : {3, 8}) {
      EquationErrorOptions o;
      o.smoothing_half_width = half_width;
      const EquationErrorResult ee = solveEquationError(model, trajectory, o);
      if (!ee.applicable) break;
      std::vector<double> g = best_genes;
      for (size_t k = 0; k < space.size(); ++k) {
        const Gene& gene = space.gene(k);
        const double v = ee.values[k];
        if (!gene.smooth || gene.clamp_length || !std::isfinite(v) || (gene.log_scale && !(v > 0.0)))
          continue;
        g[k] = space.reflect(k, gene.log_scale ? std::log(v) : v);
      }
      starts.push_back(g);
    }
    OutputErrorResult best_oe;
    // Each start is scouted with a few iterations; the best one is then fitted to convergence.
    const auto fit = [&](const Model& m, const std::vector<double>& from, int max_iterations,
                         bool estimate_std) {
      OutputErrorOptions o = options.output_error;
      o.max_iterations = std::min(o.max_iterations, max_iterations);
      o.threads = std::max(o.threads, options.es.threads);
      if (options.max_wall_time_s > 0.0) {
        const double left = options.max_wall_time_s - elapsed();
        if (left <= 0.0) return OutputErrorResult();
        o.max_time_s = o.max_time_s > 0.0 ? std::min(o.max_time_s, left) : left;
      }
      o.estimate_std = estimate_std;
      return estimateOutputError(m, trajectory, space, from, o);
    };
    // A fit that ran but ended non-finite (Ceres could not evaluate the residuals, e.g. a rollout
    // that blew up) is no answer: the search's one-step answer stays.
    const auto usable = [](const OutputErrorResult& oe) {
      return oe.ran && std::isfinite(oe.observation_cost_m2);
    };
    std::string failed;
    for (const std::vector<double>& from : starts) {
      OutputErrorResult oe = fit(model, from, kScoutIterations, false);
      if (oe.ran && !usable(oe)) failed = oe.termination;
      if (!usable(oe)) oe.ran = false;
      if (oe.ran && (!best_oe.ran || oe.observation_cost_m2 < best_oe.observation_cost_m2)) best_oe = oe;
      // A fit as good as the noise allows needs no other start.
      if (best_oe.ran && best_oe.noise_std_m <= 1.2 * best_oe.noise_std_prior_m) break;
    }
    // Stiff scenes: semi-implicit Euler drifts as (omega h)^2; a finer integrator is kept when
    // the simulated motion fits the frames clearly better (data made by a coarse integrator,
    // e.g. a simulation with one step per frame, keep theirs).
    if (best_oe.ran) omega_h = omegaH(best_oe.values);
    if (best_oe.ran && options.max_omega_h_per_substep > 0.0 &&
        omega_h / model.substeps > options.max_omega_h_per_substep) {
      const int needed = std::min(
          kMaxSubsteps, static_cast<int>(std::ceil(omega_h / options.max_omega_h_per_substep)));
      if (needed > model.substeps) {
        Model finer = model;
        finer.substeps = needed;
        const OutputErrorResult oe = fit(finer, best_oe.genes, kScoutIterations, false);
        const bool better = usable(oe) && oe.observation_cost_m2 < 0.5 * best_oe.observation_cost_m2;
        note("the stiffest mode has omega*h = " + formatValue(omega_h) + " per frame: " +
                 std::to_string(needed) + " substeps per frame fit the frames " +
                 (better ? "better" : "no better") + " than " + std::to_string(model.substeps) +
                 " (output-error cost " + formatValue(oe.observation_cost_m2) + " against " +
                 formatValue(best_oe.observation_cost_m2) + " m^2): " +
                 (better ? "the model now uses " + std::to_string(needed) : "kept " + std::to_string(model.substeps)),
             generations_done, evaluations_done);
        if (better) {
          model = finer;
          best_oe = oe;
        }
      }
    }
    if (best_oe.ran) {
      const OutputErrorResult oe = fit(model, best_oe.genes, options.output_error.max_iterations,
                                       options.estimate_std);
      if (usable(oe) && oe.observation_cost_m2 <= best_oe.observation_cost_m2 * (1.0 + 1e-9)) best_oe = oe;
      note("output error: " + std::to_string(best_oe.segments) + " segments, " +
               std::to_string(best_oe.iterations) + " iterations of the final fit (" +
               (best_oe.stages > 1 ? "over " + std::to_string(best_oe.stages) +
                                         " stages growing the data, "
                                   : std::string()) +
               (best_oe.converged ? "converged" : best_oe.termination) + "), marker noise from its residuals " +
               formatValue(best_oe.noise_std_m) + " m (from the data " + formatValue(r.noise_estimate_m) + " m)",
           generations_done, evaluations_done);
      if (best_oe.noise_std_m > kMisfitFactor * std::max(r.noise_estimate_m, 1e-9))
        note("warning: the output-error residual (" + formatValue(best_oe.noise_std_m) +
                 " m RMS) is " + formatValue(best_oe.noise_std_m / std::max(r.noise_estimate_m, 1e-9)) +
                 "x the markers' noise: the model does not explain the motion (missing bonds or "
                 "kinds, a wrong structure, or too few substeps for its stiffness)",
             generations_done, evaluations_done);
      best_genes = best_oe.genes;
      r.values = best_oe.values;
      r.global_cost = best_oe.observation_cost_m2;
      r.noise_std_m = best_oe.noise_std_m;
      r.estimator = "output_error";
      std_devs = best_oe.std_devs;
      unidentifiable = best_oe.unidentifiable;
      omega_h = omegaH(r.values);
    } else if (!failed.empty()) {
      note("warning: the output-error fit failed (" + failed + "): the one-step fit is kept",
           generations_done, evaluations_done);
    }
  }
  r.generations = generations_done;
  r.evaluations = evaluations_done;
  r.frames = trajectory.numFrames();
  r.stop = stop;
  r.last_refine_status = es ? es->lastRefineStatus() : RefineStatus::kNotRun;
  r.bound_widenings = widenings;
  r.substeps = model.substeps;
  r.stiffest_omega_h = omega_h;
  r.notes = notes;
  r.flags.assign(r.values.size(), ParameterFlag::kNone);
  for (size_t k = 0; k < space.size(); ++k) {
    const int side = space.boundSide(k, best_genes[k]);
    if (side != 0) r.flags[k] = side < 0 ? ParameterFlag::kAtLowerBound : ParameterFlag::kAtUpperBound;
    else if (unidentifiable[k]) r.flags[k] = ParameterFlag::kUnidentifiable;
  }
  if (r.estimator == "short_term")
    std_devs = options.estimate_std
                   ? estimateStdDevs(*cost, space, best_genes)
                   : std::vector<double>(r.values.size(), std::numeric_limits<double>::quiet_NaN());
  // A threshold is known only up to the flat interval between the observed lengths where its
  // condition switches: its std is that interval's (uniform: width / sqrt(12)); an interval that
  // runs to a search bound means the data never saw the condition switch on that side.
  for (size_t k = 0; k < space.size() && k < std_devs.size(); ++k) {
    const Gene& g = space.gene(k);
    if (g.smooth) continue;
    const auto it = std::upper_bound(g.breakpoints.begin(), g.breakpoints.end(), best_genes[k]);
    if (g.breakpoints.empty() || it == g.breakpoints.begin() || it == g.breakpoints.end()) {
      if (r.flags[k] == ParameterFlag::kNone) r.flags[k] = ParameterFlag::kUnidentifiable;
      continue;
    }
    const double lo = *(it - 1), hi = *it;
    const double slope = std::abs(space.physicalSlope(k, best_genes));
    std_devs[k] = slope * (hi - lo) / std::sqrt(12.0);
  }
  r.std_devs = std_devs;
  r.model = model;
  setValues(r.model, r.parameters, r.values);
  r.wall_time_s = elapsed();
  return r;
}

}  // namespace mme

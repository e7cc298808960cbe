#include "motion_model_estimation/identification/identifier.h"

#include <Eigen/Dense>

#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>
#include <memory>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/equation_error.h"
#include "motion_model_estimation/identification/levenberg_marquardt.h"

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
  if (preset == Preset::kPaper) o.patience_generations = 0;
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
  detail::JacobianColumns jac;
  if (!detail::forwardJacobian(cost, space, genes, residual, active, 100000000, pool, &jac))
    return out;
  Eigen::MatrixXd jtj;
  Eigen::VectorXd g;
  detail::normalEquations(jac, residual, &jtj, &g);
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

/// Share of a gene's distance to a bound under which it counts as at the bound: 1 % of the
/// value for log genes, 1 % of the range for linear ones.
constexpr double kAtBoundShare = 0.01;
/// A default bound the answer reached moves this far out (a factor for log genes, ranges for
/// linear ones).
constexpr double kWidenFactor = 10.0;

std::string formatValue(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", v);
  return text;
}

/// -1 at the lower bound, +1 at the upper, 0 inside.
int atBound(const Gene& g, double gene) {
  const double tolerance = g.log_scale ? std::log1p(kAtBoundShare) : kAtBoundShare * (g.upper - g.lower);
  if (gene - g.lower <= tolerance) return -1;
  if (g.upper - gene <= tolerance) return 1;
  return 0;
}

/// Smooth genes within 1 % of a default (not user-given) bound, with the side (-1 lower, +1
/// upper): the bounds identification may widen.
std::vector<std::pair<size_t, int>> widenableAtBound(const ParameterSpace& space,
                                                     const std::vector<double>& genes) {
  std::vector<std::pair<size_t, int>> out;
  for (size_t k = 0; k < space.size(); ++k) {
    const Gene& g = space.gene(k);
    if (!g.smooth || g.clamp_length) continue;
    const int side = atBound(g, genes[k]);
    if (side != 0 && !(side < 0 ? g.user_lower : g.user_upper)) out.emplace_back(k, side);
  }
  return out;
}

/// Equation-error starts (raw and smoothed differences) as gene vectors; a value outside a
/// default bound widens it (beyond a user's bound it is clamped), an undetermined one is left
/// at the initial distribution's centre. Notes what it widened.
std::vector<std::vector<double>> equationErrorSeeds(const Model& model, const Trajectory& trajectory,
                                                    ParameterSpace* space,
                                                    std::vector<std::string>* notes) {
  std::vector<std::vector<double>> seeds;
  for (int half_width : {0, 3}) {
    EquationErrorOptions o;
    o.smoothing_half_width = half_width;
    const EquationErrorResult ee = solveEquationError(model, trajectory, o);
    if (!ee.applicable) break;
    std::vector<double> genes(space->size());
    for (size_t k = 0; k < space->size(); ++k) {
      const Gene& g = space->gene(k);
      const double v = ee.values[k];
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
        notes->push_back("'" + g.ref.name + "': the equation-error start " + formatValue(v) +
                         " lies outside the default search bounds: bounds widened to include it");
        space->setBounds(k, lo, hi);
      }
      genes[k] = std::min(std::max(gene, space->gene(k).lower), space->gene(k).upper);
    }
    seeds.push_back(std::move(genes));
  }
  return seeds;
}

}  // namespace

const char* parameterFlagName(ParameterFlag flag) {
  switch (flag) {
    case ParameterFlag::kNone: return "";
    case ParameterFlag::kAtLowerBound: return "at_lower_bound";
    case ParameterFlag::kAtUpperBound: return "at_upper_bound";
  }
  return "?";
}

IdentifyResult identifyModel(const Model& model, const Trajectory& trajectory,
                             const IdentifyOptions& options,
                             const std::function<void(const Progress&)>& progress) {
  const std::string bad = validateOptions(options);
  if (!bad.empty()) throw InputError(bad);
  const auto start = std::chrono::steady_clock::now();
  auto cost = std::make_shared<ShortTermCost>(model, trajectory);
  if (cost->termCount() == 0)
    throw InputError("no usable (particle, frame) terms: too few frames or everything occluded");
  ParameterSpace space(model, trajectory);
  std::vector<std::string> notes, seed_notes;
  std::vector<std::vector<double>> seeds;
  if (options.equation_error_start)
    seeds = equationErrorSeeds(model, trajectory, &space, &seed_notes);
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
  // Convergence: the best cost no longer falls (relative 1e-9) or sits at the round-off floor.
  const double floor_m2 = 1e-26 * static_cast<double>(cost->residualCount());
  IdentifyStop stop = IdentifyStop::kGenerations;
  int generations_done = 0;
  uint64_t evaluations_done = 0;
  int widenings = 0;
  std::unique_ptr<EvolutionStrategy> es;
  while (true) {
    // One search; when its answer ends on a default bound, the bound is widened and the search
    // resumes from that answer (a bounded number of times).
    es = std::make_unique<EvolutionStrategy>(space, options.es);
    es->setCost(cost);
    es->setSeeds(seeds);
    if (options.max_wall_time_s > 0.0)
      es->setDeadline(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                  std::chrono::duration<double>(options.max_wall_time_s)));
    // Converged: over the last `patience` generations the best cost fell by less than a
    // relative 1e-6, or it sits at the round-off floor.
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
      const int patience = options.patience_generations;
      const size_t g = best_after.size();
      if (patience > 0 && es->refinements() > 0 &&
          (best <= floor_m2 || (g > static_cast<size_t>(patience) &&
                                best_after[g - 1 - patience] - best <= 1e-6 * best_after[g - 1 - patience]))) {
        stop = IdentifyStop::kConverged;
        break;
      }
    }
    generations_done += es->generation();
    evaluations_done += es->evaluations();
    if (stop == IdentifyStop::kTargetCost || stop == IdentifyStop::kWallTime ||
        widenings >= options.max_bound_widenings || generations_done >= options.generations)
      break;
    if (!at_default_bound && widenableAtBound(space, es->best().genes).empty()) break;
    const std::vector<double> best = es->best().genes;
    bool widened = false;
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
      widened = true;
    }
    if (!widened) break;
    ++widenings;
    seeds.insert(seeds.begin(), best);
  }
  IdentifyResult r;
  r.parameters = space.refs();
  r.values = es->bestValues();
  r.global_cost = es->best().cost;
  r.generations = generations_done;
  r.evaluations = evaluations_done;
  r.frames = trajectory.numFrames();
  r.stop = stop;
  r.last_refine_status = es->lastRefineStatus();
  r.bound_widenings = widenings;
  r.notes = notes;
  r.flags.assign(r.values.size(), ParameterFlag::kNone);
  for (size_t k = 0; k < space.size(); ++k) {
    const int side = atBound(space.gene(k), es->best().genes[k]);
    if (side != 0) r.flags[k] = side < 0 ? ParameterFlag::kAtLowerBound : ParameterFlag::kAtUpperBound;
  }
  r.std_devs = options.estimate_std
                   ? estimateStdDevs(*cost, space, es->best().genes)
                   : std::vector<double>(r.values.size(), std::numeric_limits<double>::quiet_NaN());
  r.model = model;
  setValues(r.model, r.parameters, r.values);
  r.wall_time_s = elapsed();
  return r;
}

}  // namespace mme

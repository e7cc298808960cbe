#include "motion_model_estimation/identification/identifier.h"

#include <Eigen/Dense>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/error.h"

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
                                    const std::vector<double>& genes) {
  const size_t n = genes.size();
  std::vector<double> out(n, std::numeric_limits<double>::quiet_NaN());
  const double dof = 3.0 * static_cast<double>(cost.termCount()) - static_cast<double>(n);
  if (n == 0 || dof <= 0) return out;
  auto f = [&](const std::vector<double>& g) { return cost.evaluate(space.toPhysical(g), nullptr); };
  const double f0 = f(genes);
  std::vector<double> h(n);
  for (size_t k = 0; k < n; ++k)
    h[k] = 1e-4 * std::max(1.0, std::abs(genes[k])) * (space.gene(k).log_scale ? 0.1 : 1.0);
  Eigen::MatrixXd hess(n, n);
  std::vector<double> g = genes;
  for (size_t i = 0; i < n; ++i) {
    g[i] = genes[i] + h[i]; const double fp = f(g);
    g[i] = genes[i] - h[i]; const double fm = f(g);
    g[i] = genes[i];
    hess(i, i) = (fp - 2.0 * f0 + fm) / (h[i] * h[i]);
    for (size_t j = 0; j < i; ++j) {
      double s = 0.0;
      for (int a : {1, -1})
        for (int b : {1, -1}) {
          g[i] = genes[i] + a * h[i];
          g[j] = genes[j] + b * h[j];
          s += a * b * f(g);
        }
      g[i] = genes[i];
      g[j] = genes[j];
      hess(i, j) = hess(j, i) = s / (4.0 * h[i] * h[j]);
    }
  }
  Eigen::LDLT<Eigen::MatrixXd> ldlt(hess);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return out;
  const Eigen::MatrixXd inv = ldlt.solve(Eigen::MatrixXd::Identity(n, n));
  const double s2 = std::max(f0, 0.0) / dof;
  for (size_t k = 0; k < n; ++k) {
    if (!(inv(k, k) >= 0.0)) continue;
    const double gene_std = std::sqrt(2.0 * s2 * inv(k, k));
    // Log genes: d(value) = value d(gene); a clamp-length gene: d(tau) = (1 + tau) d(gene).
    out[k] = std::abs(space.physicalSlope(k, genes)) * gene_std;
  }
  return out;
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
  EvolutionStrategy es(space, options.es);
  es.setCost(cost);
  if (options.max_wall_time_s > 0.0)
    es.setDeadline(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                               std::chrono::duration<double>(options.max_wall_time_s)));
  auto elapsed = [&start]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  // Convergence: the best cost no longer falls (relative 1e-9) or sits at the round-off floor.
  const double floor_m2 = 1e-26 * static_cast<double>(cost->residualCount());
  double reference_cost = std::numeric_limits<double>::infinity();
  int last_fall_generation = 0;
  IdentifyStop stop = IdentifyStop::kGenerations;
  for (int g = 0; g < options.generations; ++g) {
    es.step();
    if (progress) {
      Progress p;
      p.generation = es.generation();
      p.evaluations = es.evaluations();
      p.best_cost = es.best().cost;
      p.wall_time_s = elapsed();
      p.best_values = es.bestValues();
      progress(p);
    }
    const double best = es.best().cost;
    if (best < reference_cost * (1.0 - 1e-9) && reference_cost > floor_m2) {
      reference_cost = best;
      last_fall_generation = es.generation();
    }
    if (options.target_cost > 0.0 && best <= options.target_cost) {
      stop = IdentifyStop::kTargetCost;
      break;
    }
    if (options.max_wall_time_s > 0.0 && elapsed() >= options.max_wall_time_s) {
      stop = IdentifyStop::kWallTime;
      break;
    }
    if (options.patience_generations > 0 && es.refinements() > 0 &&
        es.generation() - last_fall_generation >= options.patience_generations) {
      stop = IdentifyStop::kConverged;
      break;
    }
  }
  IdentifyResult r;
  r.parameters = space.refs();
  r.values = es.bestValues();
  r.global_cost = es.best().cost;
  r.generations = es.generation();
  r.evaluations = es.evaluations();
  r.frames = trajectory.numFrames();
  r.stop = stop;
  r.last_refine_status = es.lastRefineStatus();
  r.std_devs = options.estimate_std
                   ? estimateStdDevs(*cost, space, es.best().genes)
                   : std::vector<double>(r.values.size(), std::numeric_limits<double>::quiet_NaN());
  r.model = model;
  setValues(r.model, r.parameters, r.values);
  r.wall_time_s = elapsed();
  return r;
}

}  // namespace mme

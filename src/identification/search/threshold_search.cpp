#include "motion_model_estimation/identification/search/threshold_search.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

namespace mme {

RefineResult searchThresholds(const Cost& cost, const ParameterSpace& space,
                              const RefineStart& start, const RefineSettings& settings) {
  RefineResult out;
  out.genes = start.genes;
  out.cost = start.cost;
  out.status = RefineStatus::kConverged;
  bool moved_down = false;
  const auto out_of_budget = [&]() {
    return (settings.max_evaluations > 0 && out.evaluations >= settings.max_evaluations) ||
           settings.mustStop();
  };
  for (size_t k = 0; k < space.size(); ++k) {
    const Gene& g = space.gene(k);
    if (g.smooth || g.breakpoints.empty()) continue;
    if (!settings.movable.empty() && !(k < settings.movable.size() && settings.movable[k])) continue;
    const std::vector<double>& b = g.breakpoints;
    const int last = static_cast<int>(b.size());  // intervals 0..last
    // The middle of flat interval j: between breakpoints j-1 and j (the bounds at the ends).
    const auto middle = [&](int j) {
      const double lo = j == 0 ? g.lower : b[j - 1];
      const double hi = j == last ? g.upper : b[j];
      return 0.5 * (lo + hi);
    };
    std::map<int, double> seen;
    std::vector<double> genes = out.genes;
    const auto costAt = [&](int j) {
      auto it = seen.find(j);
      if (it != seen.end()) return it->second;
      genes[k] = middle(j);
      double c = cost.evaluate(space.toPhysical(genes), nullptr);
      ++out.evaluations;
      if (!std::isfinite(c)) c = std::numeric_limits<double>::infinity();
      seen[j] = c;
      return c;
    };
    int best = static_cast<int>(std::upper_bound(b.begin(), b.end(), out.genes[k]) - b.begin());
    double best_cost = costAt(best);
    int step = 1;
    // Outward: steps doubling while the cost falls, in the direction that first pays.
    for (int dir : {-1, 1}) {
      int s = 1;
      while (!out_of_budget()) {
        const int j = best + dir * s;
        if (j < 0 || j > last) break;
        const double c = costAt(j);
        if (!(c < best_cost)) break;
        best = j;
        best_cost = c;
        step = s;
        s *= 2;
      }
    }
    // Inward: halving steps around the best interval down to its neighbours.
    for (step = std::max(step / 2, 1); step >= 1 && !out_of_budget(); step /= 2) {
      bool improved = true;
      while (improved && !out_of_budget()) {
        improved = false;
        for (int dir : {-1, 1}) {
          const int j = best + dir * step;
          if (j < 0 || j > last) continue;
          const double c = costAt(j);
          if (c < best_cost) {
            best = j;
            best_cost = c;
            improved = true;
          }
        }
      }
    }
    // The middle of the best interval, when it fits at least as well as the start.
    if (best_cost <= out.cost) {
      if (best_cost < out.cost) moved_down = true;
      out.genes[k] = middle(best);
      out.cost = best_cost;
    }
    if (out_of_budget()) {
      out.status = settings.cancel && settings.cancel->load() ? RefineStatus::kCancelled
                   : settings.mustStop()                      ? RefineStatus::kDeadline
                                                              : RefineStatus::kEvaluationLimit;
      return out;
    }
  }
  if (moved_down) out.status = RefineStatus::kStalled;
  return out;
}

bool hasThresholds(const ParameterSpace& space) {
  for (const Gene& g : space.genes())
    if (!g.smooth && !g.breakpoints.empty()) return true;
  return false;
}

RefineResult refineAlternating(const Refiner& refiner, const Cost& cost, const ParameterSpace& space,
                               const RefineStart& start, const RefineSettings& settings,
                               ThreadPool* pool, int rounds) {
  RefineResult result = refiner.refine(cost, space, start, settings, pool);
  if (settings.movable.empty() || !hasThresholds(space)) return result;
  // The thresholds the gradient refinement left alone: a discrete search over their flat
  // intervals, then the smooth genes again for the new thresholds, while it pays.
  uint64_t spent = result.evaluations;
  const RefineStatus smooth_status = result.status;
  const auto left = [&]() {
    return settings.max_evaluations > spent ? settings.max_evaluations - spent : 0;
  };
  for (int round = 0; round < rounds && left() > 0 && !settings.mustStop(); ++round) {
    RefineSettings rest = settings;
    rest.movable.clear();
    rest.max_evaluations = left();
    const RefineResult moved =
        searchThresholds(cost, space, {result.genes, result.cost, start.steps}, rest);
    spent += moved.evaluations;
    if (!(moved.cost < result.cost)) {
      if (moved.cost <= result.cost) result.genes = moved.genes;  // centred in its interval
      break;
    }
    result.genes = moved.genes;
    result.cost = moved.cost;
    rest.movable = settings.movable;
    rest.max_evaluations = left();
    if (rest.max_evaluations == 0) break;
    const RefineResult again =
        refiner.refine(cost, space, {result.genes, result.cost, start.steps}, rest, pool);
    spent += again.evaluations;
    if (again.cost < result.cost) {
      result.genes = again.genes;
      result.cost = again.cost;
    }
  }
  result.evaluations = spent;
  result.status = smooth_status;
  return result;
}

}  // namespace mme

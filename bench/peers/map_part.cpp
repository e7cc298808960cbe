// Part (b) of bench_peers, the stability map: the instances of every axis and setting (biggest
// first), every method that runs on the axis on each, the Cramer-Rao bound once per instance,
// and one line per (axis, setting, seed, method) into stability_runs.csv.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>

#include "instances.h"
#include "motion_model_estimation/core/error.h"
#include "parts.h"

namespace peers {
namespace {

struct MapInstance {
  std::string axis;
  double value;
  int seed;
  Budget budget;
  int frames;
};

std::vector<MapInstance> mapInstances(const Settings& s) {
  std::map<std::string, std::vector<double>> axes;
  Budget budget{45000, 20.0, 1.0};  // stop at success: all parameters within 1 %
  int frames = kMapFrames, seeds = s.seeds;
  if (s.quick) {
    axes = {{"noise", {0.0, 1e-5}}, {"omega_h", {0.5}}, {"occlusion", {0.1}}, {"spread", {0.1}},
            {"unknowns", {10}}, {"conditional", {2}}};
    budget = {3000, 5.0, 1.0};
    frames = 30;
    seeds = std::min(seeds, 2);
  } else {
    axes = {{"noise", {0.0, 1e-6, 1e-5, 1e-4, 1e-3}},
            {"omega_h", {0.05, 0.2, 0.5, 1.0, 2.5}},
            {"occlusion", {0.05, 0.1, 0.2, 0.4, 0.6}},  // 0 = the noise axis' base run
            {"spread", {0.02, 0.1, 0.3, 0.6}},
            {"unknowns", {10, 20, 50, 100, 200}},
            {"conditional", {0, 2, 5, 10}}};
  }
  if (!s.axes.empty()) {
    for (const std::string& a : s.axes)
      if (!axes.count(a)) throw mme::InputError("--axes: no stability-map axis '" + a + "'");
    for (auto it = axes.begin(); it != axes.end();)
      it = std::find(s.axes.begin(), s.axes.end(), it->first) == s.axes.end() ? axes.erase(it) : std::next(it);
  }
  std::vector<MapInstance> out;
  for (const auto& [axis, values] : axes)
    for (double v : values) {
      const bool big = axis == "unknowns" && v >= 100;
      const int n_seeds = axis == "unknowns" && v >= 200 ? std::min(seeds, s.seeds_200) : seeds;
      for (int seed = 1; seed <= n_seeds; ++seed) {
        MapInstance m{axis, v, seed, budget, frames};
        if (big) {
          m.budget.max_wall_s = 40.0;  // shorter than the others: keeps the full run's length in bounds
          m.frames = 30;  // cheaper evaluations for the big objects
        } else if (axis == "unknowns" && !s.quick) {
          m.frames = 30;
        }
        out.push_back(m);
      }
    }
  // Biggest first (better load balance on the worker threads).
  std::stable_sort(out.begin(), out.end(), [](const MapInstance& a, const MapInstance& b) {
    const double wa = a.axis == "unknowns" ? a.value : 0.0, wb = b.axis == "unknowns" ? b.value : 0.0;
    return wa > wb;
  });
  return out;
}

/// The methods of the map on one axis: es_early is a schedule variant shown in the
/// speed-accuracy part only; sade_final (sade judged on its final answer) runs on the
/// conditional axis only, where the oracle stop matters (see the summary's notes).
bool mapRuns(const std::string& method, const std::string& axis) {
  if (method == "es_early") return false;
  if (method == "sade_final") return axis == "conditional";
  return true;
}

/// What the map's runs give per instance, besides the methods' results.
struct MapResults {
  std::vector<std::vector<RunResult>> runs;
  std::vector<size_t> unknowns;
  std::vector<int> substeps;
  std::vector<std::vector<double>> bound_pct;  // per parameter, noisy instances
  std::vector<std::vector<double>> truth;
  std::vector<double> middle_pct;  // threshold interval middles (conditional)
  explicit MapResults(size_t n)
      : runs(n), unknowns(n, 0), substeps(n, 1), bound_pct(n), truth(n), middle_pct(n, NAN) {}
};

/// Runs every instance on the worker pool.
MapResults runMap(const Settings& s, const std::vector<std::string>& methods,
                  const std::vector<MapInstance>& instances) {
  MapResults out(instances.size());
  std::atomic<int> done{0};
  const auto t0 = Clock::now();
  std::vector<std::function<void()>> jobs;
  for (size_t j = 0; j < instances.size(); ++j)
    jobs.push_back([&, j]() {
      const MapInstance& in = instances[j];
      const Problem p = mapProblem(in.axis, in.value, in.seed, in.frames);
      out.unknowns[j] = p.space->size();
      out.substeps[j] = p.model.substeps;
      out.truth[j] = p.truth_values;
      out.middle_pct[j] = bench::thresholdMiddleErrorPct(p);
      // Once per instance (a Ceres solve), not per method.
      out.bound_pct[j] = bench::cramerRaoPct(p);
      for (const std::string& m : methods)
        if (mapRuns(m, in.axis)) out.runs[j].push_back(bench::runMethod(m, p, in.seed, in.budget, false));
      say("(b) %3d/%zu %-11s %-7g seed %2d (%5.0f s)%s\n", ++done, instances.size(), in.axis.c_str(),
          in.value, in.seed, since(t0), brief(out.runs[j]).c_str());
    });
  runPool(jobs, s.workers);
  return out;
}

/// The lines of instance j (twice for the noise axis' base run, which is also the occlusion
/// axis' 0).
void writeMapInstance(std::FILE* f, const MapInstance& in, const MapResults& res, size_t j) {
  const std::vector<double>& bound_pct = res.bound_pct[j];
  std::vector<std::string> axes{in.axis};
  if (in.axis == "noise" && in.value == 0.0) axes.push_back("occlusion");  // shared base
  // The bound's median and worst over the parameters it is defined for.
  std::vector<double> finite;
  for (double b : bound_pct)
    if (std::isfinite(b)) finite.push_back(b);
  const double b_med = median(finite);
  const double b_max = finite.empty() ? NAN : *std::max_element(finite.begin(), finite.end());
  // An efficient estimator's chance of all parameters within 1 %: independent normal errors
  // with the bound as std (correlated errors make the true figure differ somewhat).
  double p_efficient = finite.empty() ? NAN : 1.0;
  for (double b : finite) p_efficient *= std::erf(1.0 / (std::sqrt(2.0) * b));
  for (const std::string& axis : axes)
    for (const RunResult& r : res.runs[j]) {
      const bool pipeline = r.estimator.has_value();
      const double eff = r.applicable ? bench::medianEfficiency(r.values, res.truth[j], bound_pct) : NAN;
      std::fprintf(f, "%s,%g,%d,%s,%zu,%d,%d,%s,%s,%llu,%.4f,%d,%lld,%d,%s,%s,%s,%s,%d,%s,%s,%s,%s,%d,%s\n", axis.c_str(),
                   in.value, in.seed, r.method.c_str(), res.unknowns[j],
                   r.applicable ? 1 : 0, r.applicable && r.errors.max < 1.0 ? 1 : 0,
                   num(r.errors.max).c_str(), num(r.errors.median).c_str(),
                   static_cast<unsigned long long>(r.evaluations), r.wall_s,
                   r.to_1pct.reached ? r.to_1pct.generations : -1,
                   r.to_1pct.reached ? static_cast<long long>(r.to_1pct.evaluations) : -1LL,
                   r.bounded ? 1 : 0, num(b_med).c_str(), num(b_max).c_str(), num(eff).c_str(),
                   pipeline ? (*r.estimator == mme::Estimator::kOutputError ? "1" : "0") : "n/a",
                   r.substeps > 0 ? r.substeps : res.substeps[j],
                   pipeline ? num(r.noise_estimate_m).c_str() : "n/a",
                   r.residual_std_m >= 0.0 ? num(r.residual_std_m).c_str() : "n/a", num(p_efficient).c_str(),
                   num(res.middle_pct[j]).c_str(),
                   r.to_1pct.reached ? 1 : 0,
                   clean(r.note).c_str());
    }
}

}  // namespace

void stabilityMap(const Settings& s, const std::vector<std::string>& methods) {
  const std::vector<MapInstance> instances = mapInstances(s);
  const MapResults res = runMap(s, methods, instances);
  std::FILE* f = openCsv(s, "stability_runs.csv",
      "axis,value,seed,method,unknowns,applicable,success,max_error_pct,median_error_pct,evaluations,"
      "wall_s,generations_to_1pct,evals_to_1pct,bounded,bound_median_pct,bound_max_pct,efficiency,"
      "output_error,substeps,noise_estimate_m,residual_std_m,efficient_success_prob,threshold_middle_max_pct,ever_within_1pct,note");
  for (size_t j = 0; j < instances.size(); ++j) writeMapInstance(f, instances[j], res, j);
  std::fclose(f);
}

}  // namespace peers

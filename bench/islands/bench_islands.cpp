// bench_islands: the island model (search/island_model.h) measured on the stability map's
// conditional cells (cable objects: one threshold interval per cable type, several local
// minima). Writes into --out (default docs/bench):
//   islands_map_runs.csv   one line per (cable types, seed, method): success (every parameter
//                          within 1 %), errors, evaluations, wall time
//   islands_map.csv        success counts per (cable types, method), with the interval-middle
//                          limit (a final answer is a threshold interval's middle at best)
//   islands_scaling_runs.csv / islands_scaling.csv  time and evaluations to the target (every
//                          parameter within 1 %) with 1, 2 and 4 islands on up to 2 threads,
//                          and the evaluation throughput per island
//   islands_map.png, islands_scaling.png (gnuplot, bench/islands/charts.gp), islands.md
// The methods of the map: `default` (identify with no option, bench/peers/methods.h), the
// island variants of islandVariant() below and, with --sade, pagmo2's SADE as bench_peers runs
// it (oracle stop at 1 %).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "../peers/common.h"
#include "../peers/instances.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/identifier.h"

namespace {

using namespace peers;

struct Options {
  std::string out = "docs/bench";
  int seeds = 10;
  int workers = 2;
  bool sade = false;
  bool quick = false;
  std::string only;  ///< map,scaling (empty = both)
  std::vector<std::string> methods;  ///< map: these methods (empty = all but sade)
  std::vector<int> cables;           ///< map: these cable-type counts (empty = 2, 5, 10)
  bool wants(const std::string& part) const {
    return only.empty() || ("," + only + ",").find("," + part + ",") != std::string::npos;
  }
};

/// The map's budget, as bench_peers' stability map: 45 000 evaluations, 20 s.
const Budget kMapBudget{45000, 20.0, 1.0};
/// The map's islands: three populations of a third of the default population each.
constexpr int kMapIslands = 3;
constexpr int kDefaultPopulation = 100;

/// identify's default engine with `islands` islands of `population` each on `threads` threads,
/// the budget's evaluations as lock-step generations. With `stop_at_1pct` the run is cancelled
/// the first time its best is within 1 % everywhere (time to target). Judged on the final answer.
RunResult runIslands(const Problem& p, uint64_t seed, const Budget& budget, const mme::IslandOptions& io,
                     int population, int threads, bool stop_at_1pct) {
  RunResult r;
  const int islands = io.islands;
  mme::IdentifyOptions o = mme::identifyOptionsFor(mme::Preset::kDefault);
  o.es.seed = seed;
  o.es.threads = threads;
  o.es.population = o.es.offspring = population;
  o.islands = io;
  o.max_wall_time_s = budget.max_wall_s;
  o.generations = static_cast<int>(std::max<uint64_t>(1, budget.max_evaluations / static_cast<uint64_t>(islands * population)));
  std::atomic<bool> cancel{false};
  o.cancel = &cancel;
  const auto start = Clock::now();
  auto progress = [&](const mme::Progress& pr) {
    if (!pr.message.empty() || pr.best_values.empty() || r.to_1pct.reached) return;
    if (bench::relativeErrors(pr.best_values, p.truth_values).max < 1.0) {
      r.to_1pct = {true, pr.evaluations, since(start), pr.generation};
      if (stop_at_1pct) cancel = true;
    }
  };
  try {
    const mme::IdentifyResult result = mme::identifyModel(p.model, p.data, o, progress);
    r.values = result.values;
    r.evaluations = result.evaluations;
    r.generations = result.generations;
    char note[160];
    std::snprintf(note, sizeof(note), "stop %s; %d migrations; best island %d", mme::identifyStopName(result.stop),
                  result.migrations, result.best_island);
    r.note = note;
  } catch (const std::exception& e) {
    r.values.assign(p.space->size(), std::numeric_limits<double>::quiet_NaN());
    r.note = std::string("identify failed: ") + e.what();
  }
  r.wall_s = since(start);
  r.errors = bench::relativeErrors(r.values, p.truth_values);
  return r;
}

struct MapRun {
  int cables, seed;
  double middle_pct;
  RunResult run;
  bool right_intervals = false;
};

/// Whether every threshold of `values` lies in the same flat interval (between observed lengths)
/// as the truth's: the run found the global minimum's basin, whatever the 1 % judgement says.
bool inTheTruthsIntervals(const Problem& p, const std::vector<double>& values) {
  for (double v : values)
    if (!std::isfinite(v)) return false;
  const std::vector<double> genes = p.space->toSearch(values), truth = p.space->toSearch(p.truth_values);
  for (size_t k = 0; k < p.space->size(); ++k) {
    const mme::Gene& g = p.space->gene(k);
    if (g.smooth) continue;
    auto interval = [&g](double x) { return std::upper_bound(g.breakpoints.begin(), g.breakpoints.end(), x) - g.breakpoints.begin(); };
    if (interval(genes[k]) != interval(truth[k])) return false;
  }
  return true;
}

/// An island setting of the map: the islands' options and each island's population.
struct IslandVariant {
  mme::IslandOptions options;
  int population;
};

/// The map's island methods: `islands` (`identify --islands 3`: 3 islands of population 100,
/// broadcast migration), `islands_ring` and `islands_alone` (the same with ring migration or
/// none), `islands_third` (3 islands of 34: the default's evaluations per generation) and
/// `one_300` (one population of 300: the islands' evaluations per generation in one population).
bool islandVariant(const std::string& method, IslandVariant* v) {
  v->options = mme::IslandOptions{};
  v->options.islands = kMapIslands;
  v->population = kDefaultPopulation;
  if (method == "islands") return true;
  if (method == "islands_ring") v->options.topology = mme::MigrationTopology::kRing;
  else if (method == "islands_alone") v->options.migrants = 0;
  else if (method == "islands_third") v->population = (kDefaultPopulation + kMapIslands - 1) / kMapIslands;
  else if (method == "one_300") {
    v->options.islands = 1;
    v->population = kMapIslands * kDefaultPopulation;
  } else {
    return false;
  }
  return true;
}

/// (map) cables 2, 5, 10 x seeds x methods on the worker pool; islands_map_runs.csv.
std::vector<MapRun> runMap(const Options& s) {
  const std::vector<int> cables = s.cables.empty() ? std::vector<int>{2, 5, 10} : s.cables;
  std::vector<std::string> methods = s.methods;
  if (methods.empty()) methods = {"default", "one_300", "islands", "islands_ring", "islands_alone", "islands_third"};
  if (s.sade) methods.push_back("sade");
  for (const std::string& m : methods) {
    IslandVariant v;
    if (m != "default" && m != "sade" && !islandVariant(m, &v)) throw mme::InputError("--methods: unknown '" + m + "'");
    if (m == "sade" && !bench::methodAvailable("sade"))
      throw mme::InputError("sade: built without pagmo2 (libpagmo-dev)");
  }
  std::vector<MapRun> runs;
  for (int c : cables)
    for (int seed = 1; seed <= s.seeds; ++seed)
      for (size_t m = 0; m < methods.size(); ++m) runs.push_back({c, seed, NAN, RunResult{}});
  std::vector<std::function<void()>> jobs;
  std::atomic<int> done{0};
  const auto t0 = Clock::now();
  for (size_t j = 0; j < runs.size(); ++j)
    jobs.push_back([&, j]() {
      MapRun& m = runs[j];
      const std::string& method = methods[j % methods.size()];
      const Problem p = mapProblem("conditional", m.cables, m.seed, kMapFrames);
      m.middle_pct = bench::thresholdMiddleErrorPct(p);
      IslandVariant v;
      if (method == "default") m.run = bench::runMethod("default", p, m.seed, kMapBudget, false);
      else if (method == "sade") m.run = bench::runMethod("sade", p, m.seed, kMapBudget, false);
      else if (islandVariant(method, &v)) m.run = runIslands(p, m.seed, kMapBudget, v.options, v.population, 1, false);
      m.run.method = method;
      m.right_intervals = inTheTruthsIntervals(p, m.run.values);
      say("(map) %3d/%zu cables %2d seed %2d %-17s max error %8.3g %%  %7llu evaluations  %5.2f s  (%4.0f s)\n",
          ++done, runs.size(), m.cables, m.seed, method.c_str(), m.run.errors.max,
          static_cast<unsigned long long>(m.run.evaluations), m.run.wall_s, since(t0));
    });
  runPool(jobs, s.workers);
  Settings out;
  out.out = s.out;
  std::FILE* f = openCsv(out, "islands_map_runs.csv",
                         "cables,seed,method,success,right_intervals,max_error_pct,median_error_pct,evaluations,"
                         "wall_s,threshold_middle_max_pct,note");
  for (const MapRun& m : runs)
    std::fprintf(f, "%d,%d,%s,%d,%d,%s,%s,%llu,%.4f,%s,%s\n", m.cables, m.seed, m.run.method.c_str(),
                 m.run.errors.max < 1.0 ? 1 : 0, m.right_intervals ? 1 : 0, num(m.run.errors.max).c_str(), num(m.run.errors.median).c_str(),
                 static_cast<unsigned long long>(m.run.evaluations), m.run.wall_s, num(m.middle_pct).c_str(),
                 clean(m.run.note).c_str());
  std::fclose(f);
  return runs;
}

/// islands_map.csv from the runs; returns its lines for islands.md.
std::vector<std::string> writeMapCounts(const Options& s, const std::vector<MapRun>& runs) {
  std::map<std::pair<int, std::string>, std::vector<const MapRun*>> cells;
  std::map<int, std::pair<int, int>> middles;  // cables -> (within 1 %, instances), counted once
  for (const MapRun& m : runs) {
    cells[{m.cables, m.run.method}].push_back(&m);
    if (m.run.method == "default") {
      middles[m.cables].first += m.middle_pct < 1.0 ? 1 : 0;
      middles[m.cables].second += 1;
    }
  }
  Settings out;
  out.out = s.out;
  std::FILE* f = openCsv(out, "islands_map.csv",
                         "cables,method,successes,runs,median_evaluations,median_wall_s,middle_within_1pct,"
                         "right_intervals");
  std::vector<std::string> lines;
  for (const auto& [key, list] : cells) {
    int ok = 0, basin = 0;
    std::vector<double> evals, wall;
    for (const MapRun* m : list) {
      ok += m->run.errors.max < 1.0 ? 1 : 0;
      basin += m->right_intervals ? 1 : 0;
      evals.push_back(static_cast<double>(m->run.evaluations));
      wall.push_back(m->run.wall_s);
    }
    const auto& mid = middles[key.first];
    std::fprintf(f, "%d,%s,%d,%zu,%.0f,%.4f,%d,%d\n", key.first, key.second.c_str(), ok, list.size(), median(evals),
                 median(wall), mid.first, basin);
    char line[256];
    std::snprintf(line, sizeof(line), "| %d | %s | %d/%zu | %d/%zu | %.0f | %.3f | %d/%d |", key.first,
                  key.second.c_str(), ok, list.size(), basin, list.size(), median(evals), median(wall), mid.first,
                  mid.second);
    lines.push_back(line);
  }
  std::fclose(f);
  return lines;
}

/// Median with the runs that never reached counted as +infinity (NaN when most never did).
double censoredMedian(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  if (v.empty()) return NAN;
  const double m = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  return std::isfinite(m) ? m : NAN;
}

/// (scaling) cable objects with 5 cable types, seeds 1..N, 1, 2 and 4 islands of the default
/// population on min(islands, 2) threads, one run at a time: the wall time and evaluations to
/// the target, and each island's evaluations per second. Returns islands.md's lines.
std::vector<std::string> runScaling(const Options& s) {
  const std::vector<int> counts{1, 2, 4};
  Settings out;
  out.out = s.out;
  std::FILE* f = openCsv(out, "islands_scaling_runs.csv",
                         "islands,threads,seed,reached,wall_to_target_s,evals_to_target,evaluations,wall_s,"
                         "evals_per_s_per_island,load");
  std::FILE* g = openCsv(out, "islands_scaling.csv",
                         "islands,threads,reached,runs,median_wall_to_target_s,median_evals_to_target,"
                         "evals_per_s_per_island,speedup_wall_vs_1");
  std::vector<std::string> lines;
  double base_wall = NAN;
  const Budget budget{s.quick ? 9000u : 45000u, 20.0, 1.0};
  for (int n : counts) {
    const int threads = std::min(n, 2);
    std::vector<double> wall, evals, rate;
    int reached = 0;
    for (int seed = 1; seed <= s.seeds; ++seed) {
      const Problem p = mapProblem("conditional", 5, seed, kMapFrames);
      mme::IslandOptions io;
      io.islands = n;
      const RunResult r = runIslands(p, seed, budget, io, kDefaultPopulation, threads, true);
      const double per_island = static_cast<double>(r.evaluations) / std::max(1e-9, r.wall_s) / n;
      reached += r.to_1pct.reached ? 1 : 0;
      wall.push_back(r.to_1pct.reached ? r.to_1pct.wall_s : INFINITY);
      evals.push_back(r.to_1pct.reached ? static_cast<double>(r.to_1pct.evaluations) : INFINITY);
      rate.push_back(per_island);
      std::fprintf(f, "%d,%d,%d,%d,%s,%s,%llu,%.4f,%.0f,%s\n", n, threads, seed, r.to_1pct.reached ? 1 : 0,
                   num(wall.back()).c_str(), num(evals.back()).c_str(), static_cast<unsigned long long>(r.evaluations),
                   r.wall_s, per_island, loadAverage().c_str());
      say("(scaling) islands %d threads %d seed %2d: %s %.3f s, %llu evaluations to target\n", n, threads, seed,
          r.to_1pct.reached ? "reached in" : "missed,", r.to_1pct.reached ? r.to_1pct.wall_s : r.wall_s,
          static_cast<unsigned long long>(r.to_1pct.evaluations));
    }
    const double w = censoredMedian(wall), e = censoredMedian(evals), t = median(rate);
    if (n == 1) base_wall = w;
    std::fprintf(g, "%d,%d,%d,%d,%s,%s,%.0f,%s\n", n, threads, reached, s.seeds, num(w).c_str(), num(e).c_str(), t,
                 num(base_wall / w).c_str());
    char line[256];
    std::snprintf(line, sizeof(line), "| %d | %d | %d/%d | %s | %s | %.0f | %s |", n, threads, reached, s.seeds,
                  num(w, "%.3f").c_str(), num(e, "%.0f").c_str(), t, num(base_wall / w, "%.2f").c_str());
    lines.push_back(line);
  }
  std::fclose(f);
  std::fclose(g);
  return lines;
}

void writeMarkdown(const Options& s, const std::vector<std::string>& map_lines,
                   const std::vector<std::string>& scaling_lines, double wall_s) {
  const std::string path = s.out + "/islands.md";
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw mme::InputError("cannot write " + path);
  std::fprintf(f, "# Island model: conditional objects and scaling\n\n"
               "Generated by `bench_islands --out docs/bench --sade` (bench/islands/bench_islands.cpp; built by "
               "`cmake --build BUILD --target bench_islands`, run from the repository root) in %.0f s on 2 cores "
               "shared with other jobs (load average at the end: %s). Islands run as threads of one process.\n\n",
               wall_s, loadAverage().c_str());
  if (!map_lines.empty()) {
    std::fprintf(f, "## Conditional cells of the stability map\n\n"
                 "Cable objects (mapProblem(\"conditional\", cables, seed), 60 frames, noise-free), %d seeds, "
                 "budget 45 000 evaluations / 20 s, every method stopping by its own rules (the islands and "
                 "`one_300` as `default`: converged when the best cost stalls). `default`: identify with no "
                 "option (one population of 100); `one_300`: one population of 300 (the evaluations per "
                 "generation of three islands of 100); `islands`: `identify --islands 3` (3 islands of 100, 2 "
                 "migrants every 10 generations to every other island); `islands_ring`: the same, migrants to "
                 "the next island only; `islands_alone`: the same, no migration; `islands_third`: 3 islands of "
                 "34 (the default's evaluations per generation), broadcast; `sade`: pagmo2 SADE as bench_peers "
                 "runs it (stopped by the oracle the first time within 1 %%). "
                 "Success: every parameter within 1 %% of the truth, judged on the final answer (not sade). "
                 "`middle`: instances whose threshold-interval middles are all within 1 %% of the truth, the "
                 "most a method judged on its final answer can reach. `right intervals`: runs whose every threshold "
                 "lies in the truth's flat interval (the global minimum's basin found).\n\n"
                 "| cables | method | success | right intervals | median evaluations | median wall [s] | middle |\n"
                 "|---|---|---|---|---|---|---|\n",
                 s.seeds);
    for (const std::string& l : map_lines) std::fprintf(f, "%s\n", l.c_str());
    std::fprintf(f, "\n![success counts](islands_map.png)\n\n");
  }
  if (!scaling_lines.empty()) {
    std::fprintf(f, "## Time to target against islands\n\n"
                 "Cable objects with 5 cable types, %d seeds, islands of population 100 each, on min(islands, 2) "
                 "threads, one run at a time; the run stops the first time its best has every parameter within 1 %% "
                 "(the target). Medians over the seeds, a run that never reached counting as infinite. Throughput: "
                 "cost evaluations per second per island over the whole run. Speed-up: the 1-island median time "
                 "over this one, in the same run of the program.\n\n"
                 "| islands | threads | reached | median time to target [s] | median evaluations to target | "
                 "evaluations/s per island | speed-up |\n|---|---|---|---|---|---|---|\n",
                 s.seeds);
    for (const std::string& l : scaling_lines) std::fprintf(f, "%s\n", l.c_str());
    std::fprintf(f, "\n![time to target](islands_scaling.png)\n");
  }
  std::fclose(f);
}

int parseArguments(int argc, char** argv, Options* s) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw mme::InputError(a + " needs a value");
      return argv[++i];
    };
    if (a == "--out") s->out = value();
    else if (a == "--seeds") s->seeds = std::max(1, std::atoi(value().c_str()));
    else if (a == "--workers") s->workers = std::max(1, std::atoi(value().c_str()));
    else if (a == "--only") s->only = value();
    else if (a == "--sade") s->sade = true;
    else if (a == "--quick") s->quick = true;
    else if (a == "--methods" || a == "--cables") {
      std::stringstream ss(value());
      std::string item;
      while (std::getline(ss, item, ',')) {
        if (a == "--methods") s->methods.push_back(item);
        else s->cables.push_back(std::atoi(item.c_str()));
      }
    }
    else {
      std::fprintf(stderr, "usage: bench_islands [--out DIR] [--seeds N] [--workers W] [--only map,scaling] "
                           "[--methods M,..] [--cables C,..] [--sade] [--quick]\n");
      return 2;
    }
  }
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Options s;
    const int code = parseArguments(argc, argv, &s);
    if (code >= 0) return code;
    const auto t0 = Clock::now();
    std::vector<std::string> map_lines, scaling_lines;
    if (s.wants("map")) map_lines = writeMapCounts(s, runMap(s));
    if (s.wants("scaling")) scaling_lines = runScaling(s);
    writeMarkdown(s, map_lines, scaling_lines, since(t0));
    const std::string chart = "gnuplot -e \"dir='" + s.out + "'\" bench/islands/charts.gp";
    if (std::system("command -v gnuplot >/dev/null") == 0 && std::system(chart.c_str()) != 0)
      std::fprintf(stderr, "bench_islands: gnuplot failed: %s\n", chart.c_str());
    std::printf("bench_islands: wrote %s/islands*.csv and islands.md (%.0f s)\n", s.out.c_str(), since(t0));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_islands: %s\n", e.what());
    return 2;
  }
}

// bench_peers: speed against accuracy, side by side with peer optimisers, and a
// stability map of where each method fails. Every method runs on the same cost function, scenes,
// seeds and machine in one run (see methods.h for the methods, problem.h for the problems).
// Run through scripts/bench, which builds it, runs it and draws the charts. Writes into --out:
//   speed_accuracy_runs.csv   (a) one line per (scene, method, seed): final errors, effort,
//                                 evaluations/wall time to 1 % and 0.01 % max error
//   speed_accuracy_trace.csv  (a) best-so-far curves: errors against evaluations and wall time
//   stability_runs.csv        (b) one line per (axis, setting, seed, method)
//   stability_rates.csv       (b) success rate (all parameters within 1 %) per axis/setting/method
//   rollout.csv               (c) share of identified models whose long rollout stays bounded
//   scaling.csv               (d) engine time per generation against particles and threads
//   unknowns_generations.csv  generations to converge (max error < 1 %) against unknowns
//   targets.csv, summary.md   the benchmark's targets as measured ratios; the summary tables//
// This file holds the command line and the order of the parts; the parts are in speed_part.cpp,
// map_part.cpp and scaling_part.cpp, their problems in instances.cpp, the summary in summary*.cpp.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "methods.h"
#include "motion_model_estimation/core/error.h"
#include "parts.h"

namespace {

using namespace peers;

/// Reads the command line into `s`. Returns -1 to run, otherwise the exit code (usage: 2,
/// --list-methods: 0).
int parseArguments(int argc, char** argv, Settings* out) {
  Settings& s = *out;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw mme::InputError(a + " needs a value");
      return argv[++i];
    };
    if (a == "--quick") s.quick = true;
    else if (a == "--summary-only") s.summary_only = true;
    else if (a == "--out") s.out = value();
    else if (a == "--workers") s.workers = std::max(1, std::atoi(value().c_str()));
    else if (a == "--seeds") s.seeds = std::max(1, std::atoi(value().c_str()));
    else if (a == "--seeds-200") s.seeds_200 = std::max(1, std::atoi(value().c_str()));
    else if (a == "--only") s.only = value();
    else if (a == "--methods" || a == "--scenes" || a == "--axes") {
      std::stringstream ss(value());
      std::string m;
      while (std::getline(ss, m, ','))
        (a == "--methods" ? s.methods : a == "--scenes" ? s.scenes : s.axes).push_back(m);
    } else if (a == "--speed-seeds") {
      s.speed_seeds = std::atoi(value().c_str());
      if (s.speed_seeds < 1) throw mme::InputError("--speed-seeds must be a positive integer");
    } else if (a == "--list-methods") {
      for (const std::string& m : bench::availableMethods()) std::printf("%s\n", m.c_str());
      return 0;
    } else {
      std::fprintf(stderr,
                   "usage: bench_peers [--quick] [--out DIR] [--workers N] [--seeds N] [--seeds-200 N]\n"
                   "                   [--only speed,map,scaling] [--methods a,b,...] [--summary-only]\n"
                   "                   [--scenes a,b,...] [--speed-seeds N] [--axes a,b,...]\n"
                   "                   [--list-methods]\n");
      return 2;
    }
  }
  return -1;
}

/// The methods to run (--methods or all compiled in), checked, and the run's first lines.
std::vector<std::string> announceMethods(const Settings& s) {
  std::vector<std::string> methods = s.methods.empty() ? bench::availableMethods() : s.methods;
  for (const std::string& m : methods)
    if (!bench::methodAvailable(m)) throw mme::InputError("method '" + m + "' is not available");
  std::string missing;
  for (const std::string& m : bench::allMethods())
    if (!bench::methodAvailable(m)) missing += " " + m;
  std::printf("bench_peers: methods:");
  for (const std::string& m : methods) std::printf(" %s", m.c_str());
  std::printf("%s\n", missing.empty() ? "" : ("; not compiled in (peer libraries missing: scripts/setup "
                                               "--peers installs them):" + missing).c_str());
  std::printf("bench_peers: %s run, %d worker(s), load average %s\n", s.quick ? "quick" : "full",
              s.workers, loadAverage().c_str());
  std::fflush(stdout);
  return methods;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Settings s;
    const int code = parseArguments(argc, argv, &s);
    if (code >= 0) return code;
    const auto t0 = Clock::now();
    if (!s.summary_only) {
      const std::vector<std::string> methods = announceMethods(s);
      if (s.wants("speed")) speedScenes(s);  // a bad --scenes fails before anything runs
      if (s.wants("scaling")) scaling(s);  // first: timing needs the machine to itself
      if (s.wants("speed")) speedAccuracy(s, methods);
      if (s.wants("map")) stabilityMap(s, methods);
    }
    summary(s, s.summary_only ? 0.0 : since(t0));
    std::printf("bench_peers: done in %.0f s; results in %s\n", since(t0), s.out.c_str());
    return 0;
  } catch (const mme::InputError& e) {
    std::fprintf(stderr, "bench_peers: %s\n", e.what());
    return 2;
  }
}

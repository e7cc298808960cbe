// Part (d) of bench_peers, the engine's scaling: time per generation of the evolution strategy
// on sheets of growing size with 1 and 2 threads (the same generations, timed in alternation,
// medians kept) and the parallel efficiency.
#include <algorithm>
#include <map>
#include <memory>

#include "motion_model_estimation/identification/search/evolution_strategy.h"
#include "parts.h"

namespace peers {

void scaling(const Settings& s) {
  std::vector<std::pair<int, int>> sizes = {{2, 5}, {10, 10}, {25, 40}, {100, 100}};
  if (s.quick) sizes = {{2, 5}, {10, 10}};
  const int frames = 10;
  std::FILE* f = openCsv(s, "scaling.csv",
      "particles,bonds,unknowns,frames,threads,s_per_generation,s_per_evaluation,parallel_efficiency,"
      "load_average");
  for (const auto& [rows, cols] : sizes) {
    const mme::Model truth = bench::makeSheet(rows, cols, 100.0, 5);
    mme::State state;
    const mme::Trajectory data = bench::simulateWindow(truth, frames, 100.0, 0, &state);
    const auto cost = std::make_shared<mme::ShortTermCost>(bench::forgetFreeValues(truth), data);
    const mme::ParameterSpace space(bench::forgetFreeValues(truth), data);
    const std::vector<double> values = mme::getValues(truth, space.refs());
    auto t0 = Clock::now();
    int evals = 0;
    while (evals < 3 || since(t0) < 0.3) {
      cost->evaluate(values, nullptr);
      ++evals;
    }
    const double per_eval = since(t0) / evals;
    // The same generations (same seed: the same children, whatever the thread count) timed
    // with 1 and 2 threads in alternation, several times; the median of each is kept. One
    // timing of each on a shared 2-core machine swings by tens of percent.
    const int generations = std::max(3, static_cast<int>(0.3 / (100 * per_eval)));
    const int repeats = s.quick ? 1 : 5;
    std::map<int, std::vector<double>> per_gen_s;
    for (int rep = 0; rep < repeats; ++rep)
      for (int threads : {1, 2}) {
        mme::EsOptions o;
        o.seed = 1;
        o.threads = threads;
        mme::EvolutionStrategy es(space, o);
        es.setCost(cost);
        es.step();  // initial population + first generation (not timed)
        t0 = Clock::now();
        for (int g = 0; g < generations; ++g) es.step();
        per_gen_s[threads].push_back(since(t0) / generations);
      }
    const double t1 = median(per_gen_s[1]);
    for (int threads : {1, 2}) {
      const double per_gen = median(per_gen_s[threads]);
      const double eff = t1 / (threads * per_gen);
      std::fprintf(f, "%zu,%zu,%zu,%d,%d,%.6g,%.6g,%.4f,%s\n", truth.particles.size(), truth.bonds.size(),
                   space.size(), frames, threads, per_gen, per_eval, eff, loadAverage().c_str());
      std::fflush(f);
      say("(d) %6zu particles %6zu bonds, %d thread(s): %.4g s per generation (median of %d x %d "
          "generations; %.3g s per evaluation), efficiency %.0f %%\n", truth.particles.size(),
          truth.bonds.size(), threads, per_gen, repeats, generations, per_eval, 100.0 * eff);
    }
  }
  std::fclose(f);
}

}  // namespace peers

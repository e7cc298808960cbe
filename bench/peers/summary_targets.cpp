// The targets table of bench_peers' summary: the engine against CMA-ES on paper_object, the
// generations to converge against the number of unknowns, the default engine on the stability
// map (against the best peer, and per cell) and the parallel efficiency; each target also one
// line of targets.csv.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>

#include "methods.h"
#include "summary.h"

namespace peers {
namespace {

/// An engine variant as the targets table names it: its refinement settings.
std::string engineLabel(const std::string& method) {
  auto schedule = [](const char* algorithm, int generation) {
    const std::string g = std::to_string(generation);
    return std::string(" (") + algorithm + " refinement from generation " + g + ", every " + g + ")";
  };
  if (method == "es_early") return method + schedule("BOBYQA", bench::kEarlyRefineGeneration);
  if (method == "es_lm") return method + schedule("Levenberg-Marquardt", bench::kLmRefineGeneration);
  return method;
}


/// Runs per (method, unknowns) of the map's unknowns axis, and what the successful ones took.
struct UnknownsRuns {
  std::map<std::string, std::map<int, std::vector<double>>> gens, evals;
  std::map<std::string, std::map<int, int>> seeds, succ;
};

UnknownsRuns collectUnknowns(const std::vector<Row>& st) {
  UnknownsRuns runs;
  auto& gens = runs.gens;
  auto& evals = runs.evals;
  auto& seeds = runs.seeds;
  auto& succ = runs.succ;
  for (const Row& r : st) {
    if (r.at("axis") != "unknowns") continue;
    const std::string& m = r.at("method");
    const int u = std::atoi(r.at("unknowns").c_str());
    ++seeds[m][u];
    if (r.at("success") == "1") {
      ++succ[m][u];
      gens[m][u].push_back(toD(r, "generations_to_1pct"));
      evals[m][u].push_back(toD(r, "evals_to_1pct"));
    }
  }
  return runs;
}

/// Per judged method: its table cell, the verdict and the largest/smallest ratio.
struct UnknownsVerdicts {
  std::map<std::string, std::string> cells, verdicts;
  std::map<std::string, double> ratios;
};

UnknownsVerdicts judgeUnknowns(UnknownsRuns& runs) {
  auto& gens = runs.gens;
  auto& seeds = runs.seeds;
  auto& succ = runs.succ;
  // Ratio = generations at the largest unknowns over generations at the smallest (medians over
  // the seeds that converged); "no convergence at N" when the largest never converged.
  const std::vector<std::string> judged = {"es_local", "es_lm", "cmaes"};
  UnknownsVerdicts out;
  auto& cells = out.cells;
  auto& verdicts = out.verdicts;
  auto& ratios = out.ratios;
  for (const std::string& m : judged) {
    std::string line;
    double first = NAN, last = NAN, lo = NAN, hi = NAN;
    int largest = 0;
    for (const auto& [u, n] : seeds[m]) {
      const double g = median(gens[m][u]);
      line += std::to_string(u) + ": " + (std::isfinite(g) ? num(g, "%.0f") : "never") + " (" +
              std::to_string(succ[m][u]) + "/" + std::to_string(n) + ");  ";
      if (u == seeds[m].begin()->first) first = g;
      last = g;
      largest = u;
      if (std::isfinite(g)) {
        lo = std::isfinite(lo) ? std::min(lo, g) : g;
        hi = std::isfinite(hi) ? std::max(hi, g) : g;
      }
    }
    ratios[m] = last / first;
    const double spread = hi / lo;
    verdicts[m] = std::isfinite(ratios[m])
                      ? num(ratios[m], "%.3g") + "x (max/min over sizes " + num(spread, "%.3g") + "x)"
                      : (seeds[m].empty() ? std::string("n/a")
                                          : "no convergence at " + std::to_string(largest) +
                                                " unknowns (max/min over converged sizes " +
                                                num(spread, "%.3g") + "x)");
    cells[m] = line.empty() ? "not run" : line;
  }
  return out;
}

/// (axis, value) cells of the map, in file order.
using Cells = std::vector<std::pair<std::string, std::string>>;

/// Runs and successes of method m in one map cell.
std::pair<int, int> countRuns(const std::vector<Row>& st, const std::string& axis, const std::string& value,
                              const std::string& m) {
  std::pair<int, int> runs_ok{0, 0};
  for (const Row& r : st)
    if (r.at("axis") == axis && r.at("value") == value && r.at("method") == m) {
      ++runs_ok.first;
      runs_ok.second += r.at("success") == "1";
    }
  return runs_ok;
}

/// The cells `default` ran in and the peers the map ran (sade_final and the package's own
/// islands left out).
void defaultCells(const std::vector<Row>& st, Cells* cells_out, std::vector<std::string>* peers_out) {
  Cells& cells = *cells_out;
  std::vector<std::string>& peers = *peers_out;
  for (const Row& r : st) {
    if (r.at("method") == "default" &&
        std::find(cells.begin(), cells.end(), std::make_pair(r.at("axis"), r.at("value"))) == cells.end())
      cells.emplace_back(r.at("axis"), r.at("value"));
    if (r.at("method") != "default" && r.at("method") != "sade_final" && r.at("method") != "islands" &&
        std::find(peers.begin(), peers.end(), r.at("method")) == peers.end())
      peers.push_back(r.at("method"));
  }
}

/// `default` against the best peer's success count in every cell.
void bestPeerTarget(const std::vector<Row>& st, const Cells& cells, const std::vector<std::string>& peers,
                    std::ostream& md, std::ostream& targets_csv) {
  std::string below;
  int n_below = 0;
  for (const auto& [axis, value] : cells) {
    const auto [runs, ok] = countRuns(st, axis, value, "default");
    int best = -1;
    std::string who;
    for (const std::string& m : peers) {
      const int k = countRuns(st, axis, value, m).second;
      if (k > best) {
        best = k;
        who = m;
      } else if (k == best) {
        who += "/" + m;
      }
    }
    if (ok < best) {
      ++n_below;
      below += (below.empty() ? "" : "; ") + axis + "=" + value + ": " + std::to_string(ok) + "/" +
               std::to_string(runs) + " against " + who + " " + std::to_string(best) + "/" + std::to_string(runs);
    }
  }
  md << "| default engine: in every stability-map cell at least the best peer's success count | "
     << (peers.empty() ? std::string("no peer ran")
                       : std::to_string(cells.size() - n_below) + " of " + std::to_string(cells.size()) +
                             " cells at or above the best peer" + (below.empty() ? "" : "; below: " + below))
     << " | " << (!peers.empty() && n_below == 0 ? "yes" : "no") << " |\n";
  targets_csv << "default cells below the best peer," << n_below << ",0," << (!peers.empty() && n_below == 0) << "\n";
}

/// A per-cell target: (axis, value, the share of runs it needs).
struct CellTarget {
  std::string axis;
  double value;
  double share;
};

/// What else the cell says about `default`: the successes an efficient estimator would expect
/// (noisy cells) and the threshold interval middles within 1 % (conditional cells).
std::string cellNotes(const std::vector<Row>& st, const CellTarget& t, const std::string& value) {
  std::string measured;
  double expected = 0.0;
  bool bounded_cell = false;
  for (const Row& r : st)
    if (r.at("axis") == t.axis && r.at("value") == value && r.at("method") == "default" &&
        std::isfinite(toD(r, "efficient_success_prob"))) {
      expected += toD(r, "efficient_success_prob");
      bounded_cell = true;
    }
  if (bounded_cell) measured += " (an efficient estimator: " + num(expected, "%.1f") + " expected)";
  int middles = 0, middles_ok = 0;
  for (const Row& r : st)
    if (r.at("axis") == t.axis && r.at("value") == value && r.at("method") == "default" &&
        std::isfinite(toD(r, "threshold_middle_max_pct"))) {
      ++middles;
      middles_ok += toD(r, "threshold_middle_max_pct") < 1.0;
    }
  if (middles > 0)
    measured += " (interval middles within 1 %: " + std::to_string(middles_ok) + "/" + std::to_string(middles) + ")";
  return measured;
}

/// One row of per-cell targets of `default`.
void cellTargets(const std::vector<Row>& st, const Cells& cells, const std::string& label,
                 const std::vector<CellTarget>& targets, std::ostream& md, std::ostream& targets_csv) {
  std::string measured;
  bool met = true, any = false;
  for (const CellTarget& t : targets) {
    std::string value;
    for (const auto& c : cells)
      if (c.first == t.axis && std::abs(std::atof(c.second.c_str()) - t.value) <= 1e-9 * std::max(1.0, t.value))
        value = c.second;
    measured += (measured.empty() ? "" : ";  ") + t.axis + " " + num(t.value) + ": ";
    if (value.empty()) {
      measured += "not run";
      met = false;
      continue;
    }
    any = true;
    const auto [runs, ok] = countRuns(st, t.axis, value, "default");
    const bool cell_met = ok >= t.share * runs - 1e-9;
    met = met && cell_met;
    measured += std::to_string(ok) + "/" + std::to_string(runs) + (cell_met ? "" : " (below)");
    measured += cellNotes(st, t, value);
    targets_csv << "default " << t.axis << " " << value << " success rate,"
                << num(runs ? static_cast<double>(ok) / runs : NAN) << "," << num(t.share) << "," << cell_met << "\n";
  }
  md << "| " << label << " | " << measured << " | " << (any && met ? "yes" : "no") << " |\n";
}

}  // namespace

void engineTargets(const SummaryData& d, std::ostream& md, std::ostream& targets_csv) {
  const std::vector<Row>& sa = d.sa;
  // Per seed on paper_object: CMA-ES / engine evaluations and wall time to max error < 0.01 %,
  // for the engine with the paper's refinement schedule (es_local, the target), es_early and
  // es_lm (the same engine with other refinement settings).
  for (const std::string engine : {"es_local", "es_early", "es_lm"}) {
    std::map<int, std::map<std::string, const Row*>> by_seed;
    for (const Row& r : sa)
      if (r.at("scene") == "paper_object") by_seed[std::atoi(r.at("seed").c_str())][r.at("method")] = &r;
    std::vector<double> ev_ratio, wall_ratio;
    int es_ok = 0, cma_ok = 0, pairs = 0;
    bool lower_bound = false;
    for (const auto& [seed, m] : by_seed) {
      if (!m.count(engine) || !m.count("cmaes")) continue;
      ++pairs;
      const Row& es = *m.at(engine);
      const Row& cma = *m.at("cmaes");
      const double es_e = toD(es, "evals_to_0.01pct"), es_w = toD(es, "wall_to_0.01pct");
      double cma_e = toD(cma, "evals_to_0.01pct"), cma_w = toD(cma, "wall_to_0.01pct");
      es_ok += es_e >= 0;
      cma_ok += cma_e >= 0;
      if (es_e < 0) continue;
      if (cma_e < 0) {  // never reached: its whole budget is a lower bound
        cma_e = toD(cma, "evaluations");
        cma_w = toD(cma, "wall_s");
        lower_bound = true;
      }
      ev_ratio.push_back(cma_e / std::max(es_e, 1.0));
      wall_ratio.push_back(cma_w / std::max(es_w, 1e-9));
    }
    if (engine != "es_local" && pairs == 0) continue;
    const double er = median(ev_ratio), wr = median(wall_ratio);
    const std::string pre = lower_bound ? ">= " : "";
    auto ratio = [&pre](double x) { return std::isfinite(x) ? pre + num(x, "%.3g") + "x" : std::string("n/a"); };
    const std::string who = engineLabel(engine);
    md << "| " << who << " reaches 0.01 % on paper_object with >= 10x fewer evaluations than CMA-ES | "
       << (pairs ? ratio(er) + " (median over " + std::to_string(ev_ratio.size()) + " seeds; " + engine +
                       " reached 0.01 % in " + std::to_string(es_ok) + "/" + std::to_string(pairs) +
                       ", CMA-ES in " + std::to_string(cma_ok) + "/" + std::to_string(pairs) + ")"
                 : std::string("not run (CMA-ES not compiled in)"))
       << " | " << (pairs && er >= 10 ? "yes" : "no") << " |\n";
    md << "| ... and >= 10x less wall time | " << (pairs ? ratio(wr) : "not run") << " | "
       << (pairs && wr >= 10 ? "yes" : "no") << " |\n";
    targets_csv << "paper_object evals to 0.01% cmaes/" << engine << "," << num(er) << ",10," << (er >= 10) << "\n";
    targets_csv << "paper_object wall to 0.01% cmaes/" << engine << "," << num(wr) << ",10," << (wr >= 10) << "\n";
  }
}

void unknownsTargets(const SummaryData& d, std::ostream& md, std::ostream& targets_csv,
                     std::ostream& gens_csv) {
  UnknownsRuns runs = collectUnknowns(d.st);
  UnknownsVerdicts v = judgeUnknowns(runs);
  auto& gens = runs.gens;
  auto& evals = runs.evals;
  auto& seeds = runs.seeds;
  auto& succ = runs.succ;
  auto& cells = v.cells;
  auto& verdicts = v.verdicts;
  auto& ratios = v.ratios;
  const std::vector<std::string>& order = d.order;
  for (const std::string& m : order)
    for (const auto& [u, n] : seeds[m])
      gens_csv << u << "," << m << "," << n << "," << succ[m][u] << "," << num(median(gens[m][u]))
               << "," << num(median(evals[m][u])) << "\n";
  for (const std::string& m : {std::string("es_local"), std::string("es_lm")}) {
    const std::string who = engineLabel(m);
    if (m != "es_local" && seeds[m].empty()) continue;
    md << "| " << who << " generations to converge (max error < 1 %) stay within 1.5x from 10 to "
          "200 unknowns | unknowns: median generations (successes/seeds): "
       << cells[m] << "largest/smallest = " << verdicts[m] << " | "
       << (ratios[m] <= 1.5 ? "yes" : "no") << " |\n";
    targets_csv << m << " generations to 1% largest/smallest unknowns," << num(ratios[m]) << ",1.5,"
                << (ratios[m] <= 1.5) << "\n";
  }
  md << "| ... while CMA-ES grows (its generations: lambda = 4 + 3 ln n samples each) | "
     << cells["cmaes"] << "largest/smallest = " << verdicts["cmaes"] << " | "
     << (std::isfinite(ratios["cmaes"]) && ratios["cmaes"] > 1.5 ? "yes" : "no") << " |\n";
  targets_csv << "cmaes generations to 1% largest/smallest unknowns," << num(ratios["cmaes"])
              << ",1.5," << (ratios["cmaes"] > 1.5) << "\n";
}

// The default engine on the stability map (judged on its final answer; the others stop at
// the first point within 1 %).
void defaultTargets(const SummaryData& d, std::ostream& md, std::ostream& targets_csv) {
  const std::vector<Row>& st = d.st;
  if (!std::any_of(st.begin(), st.end(), [](const Row& r) { return r.at("method") == "default"; })) return;
  Cells cells;
  std::vector<std::string> peers;
  defaultCells(st, &cells, &peers);
  bestPeerTarget(st, cells, peers, md, targets_csv);
  cellTargets(st, cells, "default engine: conditional bonds, 2 / 5 / 10 cable types, >= 9/10 each",
              {{"conditional", 2, 0.9}, {"conditional", 5, 0.9}, {"conditional", 10, 0.9}},
              md, targets_csv);
  cellTargets(st, cells, "default engine: noise 1e-5 m 10/10 and 1e-4 m >= 9/10, occlusion 0.4 >= 9/10, "
              "omega*h 0.5 and 1.0 >= 9/10",
              {{"noise", 1e-5, 1.0}, {"noise", 1e-4, 0.9}, {"occlusion", 0.4, 0.9},
               {"omega_h", 0.5, 0.9}, {"omega_h", 1.0, 0.9}},
              md, targets_csv);
}

void parallelTarget(const SummaryData& d, std::ostream& md, std::ostream& targets_csv) {
  std::string line;
  double best_eff = NAN, largest_eff = NAN;
  for (const Row& r : d.sc)
    if (r.at("threads") == "2") {
      const double e = toD(r, "parallel_efficiency");
      line += r.at("particles") + " particles: " + num(100 * e, "%.0f") + " %;  ";
      best_eff = std::isfinite(best_eff) ? std::max(best_eff, e) : e;
      largest_eff = e;
    }
  md << "| parallel efficiency on 2 threads >= 85 % | " << (line.empty() ? "not run" : line)
     << " | " << (largest_eff >= 0.85 ? "yes (largest size)" : "no (largest size)") << " |\n\n";
  targets_csv << "parallel efficiency 2 threads largest size," << num(largest_eff) << ",0.85,"
              << (largest_eff >= 0.85) << "\n";
}

}  // namespace peers

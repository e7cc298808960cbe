// The failure section of bench_peers' summary: one sentence per method on why it fails where it
// fails, beside the map settings where it did in this run, and for the default engine the
// facts of every cell where it fell short, generated from stability_runs.csv.
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "summary.h"

namespace peers {
namespace {

/// One sentence per method: why it fails where it fails (from the mechanisms; the settings where
/// it failed in this run are listed next to it by the summary).
const std::map<std::string, std::string>& failureReasons() {
  static const std::map<std::string, std::string> reasons = {
      {"es_local",
       "it needs a few hundred generations of 100 children before its BOBYQA refinement (from "
       "generation 400) polishes the answer, so it fails when the budget ends first (large "
       "objects, whose refinement also costs O(n^2) per step) and, like every method minimising "
       "this cost, where the cost's minimum itself is off by more than 1 % (noise amplified by "
       "1/h^2 in the one-step prediction, the one-step model's discretisation error at large "
       "omega*h, too few surviving terms under heavy occlusion)."},
      {"es_lm",
       "the same ES, refined by Levenberg-Marquardt on the residuals from generation 5: once its "
       "best individual lies in the basin a few Jacobians finish the job, so it fails where "
       "Gauss-Newton has no useful slope (the free thresholds of conditional bonds, where the cost "
       "is flat between switching events, so the refinement spends evaluations the ES needed) and, "
       "like every method minimising this cost, where the cost's minimum itself is off by more "
       "than 1 % (noise, large omega*h, heavy occlusion)."},
      {"es_global",
       "without the local-cost operators every child mutates all genes at once, so progress per "
       "generation falls as the number of unknowns grows and it runs out of budget earlier than "
       "es_local; elsewhere it fails where the cost's minimum is wrong (noise, omega*h, "
       "occlusion)."},
      {"cmaes",
       "it learns a full covariance matrix whose learning rate falls as 1/n^2, so on many unknowns "
       "it spends its budget adapting before it converges, and on conditional bonds the piecewise "
       "cost (flat between switching events) misleads its ranking-based step-size control; it "
       "fails with the others where the cost's minimum is wrong."},
      {"sade",
       "differential evolution converges only linearly and needs a population of at least "
       "max(20, n) individuals, so on a budget of tens of thousands of evaluations it rarely gets "
       "every parameter within 1 %, and less so as the unknowns grow."},
      {"bobyqa",
       "a local quadratic-model search: it converges fast from starts inside the right basin but "
       "stalls on the flat steps of conditional bonds (no slope for a free threshold) and its "
       "O(n^2)-per-step model algebra makes it too slow beyond ~100 unknowns."},
      {"lm",
       "Gauss-Newton steps need a useful numeric Jacobian of the residuals: it fails where that "
       "derivative is zero or meaningless (free thresholds of conditional bonds) and, as a local "
       "method, from starts outside the basin (it restarts from the next random "
       "start); each iteration costs n+1 evaluations."},
      {"default",
       "the package's default pipeline (`identify` with no option: the ES with Levenberg-Marquardt "
       "on the one-step cost, equation-error seeds, threshold search, bound widening, convergence "
       "stop, automatic substeps for stiff scenes, the output-error estimator for the final answer "
       "once the markers' estimated noise reaches 1e-7 m), judged on its final answer with no oracle "
       "stop. Generated from this run's runs, every cell where it fell short of all runs:"},
      {"islands",
       "`default` with three islands of 100 (broadcast migration of 2 individuals every 10 "
       "generations) at the same total evaluations: separate populations settle in different "
       "threshold intervals and migration spreads the best one, but it fails where `default` "
       "fails for reasons no search changes (the cost's minimum off by noise, omega*h or "
       "occlusion; a threshold interval whose middle is more than 1 % from the truth), and on a "
       "budget of evaluations it has a third of `default`'s generations."},
      {"sade_final",
       "`sade` judged on its best point at the budget's end instead of being stopped the first time "
       "it passes within 1 % (conditional axis only): the difference between the two columns is "
       "what the oracle stop gave it."},
      {"lls",
       "it solves the equation error exactly in one step (for substeps = 1 that is the paper's "
       "cost itself, so it is the cost's global minimum), hence it fails exactly where that "
       "minimum is off (noise divided by h^2 in the finite-difference accelerations, "
       "discretisation bias at large omega*h) and cannot be used at all on conditional, "
       "non-linear or sub-stepped models (n/a)."}};
  return reasons;
}

/// What `default`'s runs say in every map cell where it fell short of all runs: successes, the
/// estimator of its final answer, its errors (and the bound's, where noisy), why it stopped, the
/// substeps it chose, flagged parameters and wall time. Generated from the CSV, not written by
/// hand, so it cannot drift from the data.
std::string defaultFailureFacts(const std::vector<Row>& st) {
  std::vector<std::pair<std::string, std::string>> cells;  // (axis, value) in file order
  for (const Row& r : st)
    if (r.at("method") == "default" &&
        std::find(cells.begin(), cells.end(), std::make_pair(r.at("axis"), r.at("value"))) == cells.end())
      cells.emplace_back(r.at("axis"), r.at("value"));
  std::string out;
  for (const auto& [axis, value] : cells) {
    int runs = 0, ok = 0, oe = 0, bounded = 0;
    std::vector<double> mx, bmax, eff, sub, flagged, wall, resid, noise_est;
    std::map<std::string, int> stops;
    for (const Row& r : st) {
      if (r.at("method") != "default" || r.at("axis") != axis || r.at("value") != value) continue;
      ++runs;
      ok += r.at("success") == "1";
      oe += r.at("output_error") == "1";
      bounded += r.at("bounded") == "1";
      if (toD(r, "max_error_pct") < 1e299) mx.push_back(toD(r, "max_error_pct"));  // else: no answer
      resid.push_back(toD(r, "residual_std_m"));
      noise_est.push_back(toD(r, "noise_estimate_m"));
      bmax.push_back(toD(r, "bound_max_pct"));
      eff.push_back(toD(r, "efficiency"));
      sub.push_back(toD(r, "substeps"));
      wall.push_back(toD(r, "wall_s"));
      const std::string& note = r.at("note");
      const size_t at = note.find("stop ");
      if (note.rfind("identify failed", 0) == 0) ++stops["identify failed (" + note.substr(std::min<size_t>(17, note.size())) + ")"];
      else if (at != std::string::npos) ++stops[note.substr(at + 5, note.find(';', at) - at - 5)];
      const size_t f = note.find(" flagged");
      if (f != std::string::npos) {
        const size_t b = note.rfind(' ', f - 1);
        flagged.push_back(std::atof(note.substr(b + 1, f - b - 1).c_str()));
      }
    }
    if (ok == runs) continue;
    const auto [lo_sub, hi_sub] = std::minmax_element(sub.begin(), sub.end());
    std::string stop_text;
    for (const auto& [why, n] : stops) stop_text += (stop_text.empty() ? "" : ", ") + why + " " + std::to_string(n);
    out += " " + axis + "=" + value + ": " + std::to_string(ok) + "/" + std::to_string(runs) +
           "; final answer by output error in " + std::to_string(oe) + "; max error median " +
           (mx.empty() ? std::string("- (no answer)") : num(median(mx), "%.3g") + " %");
    if (std::isfinite(median(resid)))
      out += " (output-error residual RMS median " + num(median(resid), "%.2g") + " m against a noise "
             "estimate of " + num(median(noise_est), "%.2g") + " m)";
    if (std::isfinite(median(bmax)))
      out += " (the bound's worst parameter " + num(median(bmax), "%.3g") + " %, median efficiency " +
             num(median(eff), "%.2g") + ")";
    out += "; stops: " + (stop_text.empty() ? std::string("-") : stop_text) + "; substeps " +
           (sub.empty() ? std::string("-")
                        : num(*lo_sub, "%.0f") + (*hi_sub > *lo_sub ? "-" + num(*hi_sub, "%.0f") : "")) +
           "; flagged parameters (median) " + num(median(flagged), "%.0f") + "; rollout bounded " +
           std::to_string(bounded) + "/" + std::to_string(runs) + "; wall median " + num(median(wall), "%.2g") +
           " s.";
  }
  return out.empty() ? " it succeeded in every run of every cell." : out;
}


}  // namespace

void failureSection(const SummaryData& d, const FailureCells& fails_at, std::ostream& md) {
  const std::vector<Row>& st = d.st;
  md << "## Why each method fails where it fails\n\n";
  for (const std::string& m : d.order) {
    if (!failureReasons().count(m)) continue;
    if (std::none_of(st.begin(), st.end(), [&m](const Row& r) { return r.at("method") == m; })) continue;
    const auto it = fails_at.find(m);
    std::string where = it == fails_at.end() ? "nowhere in this run's map" : "";
    if (it != fails_at.end())
      for (const std::string& w : it->second) where += (where.empty() ? "" : ", ") + w;
    md << "- **" << m << "** (success < 50 % at: " << where << "): " << failureReasons().at(m);
    if (m == "default") md << defaultFailureFacts(st);
    md << "\n";
  }
  md << "\n";
}

}  // namespace peers

// Sections (a), (c) and (d) of bench_peers' summary: the speed-accuracy table of every scene,
// the long rollouts that stay bounded (with rollout.csv) and the engine's scaling.
#include <algorithm>
#include <fstream>
#include <sstream>

#include "summary.h"

namespace peers {
namespace {

/// One scene's table: per method, medians over the seeds.
void speedSceneTable(const std::vector<Row>& sa, const std::vector<std::string>& order, const std::string& scene,
                     std::ostream& md) {
  md << "### " << scene << "\n\n| method | seeds | median err % | max err % | evaluations | wall s | "
        "evals to 1 % | evals to 0.01 % | wall s to 0.01 % | rollout bounded | end |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& m : order) {
    std::vector<double> med, mx, ev, wall, e1, e001, w001;
    int n = 0, bounded = 0, reached1 = 0, reached001 = 0;
    bool applicable = true;
    std::string note, unknowns;
    for (const Row& r : sa) {
      if (r.at("scene") != scene || r.at("method") != m) continue;
      ++n;
      unknowns = r.at("unknowns");
      applicable = r.at("applicable") == "1";
      note = r.at("note");
      med.push_back(toD(r, "median_error_pct"));
      mx.push_back(toD(r, "max_error_pct"));
      ev.push_back(toD(r, "evaluations"));
      wall.push_back(toD(r, "wall_s"));
      bounded += r.at("bounded") == "1";
      if (toD(r, "evals_to_1pct") >= 0) { ++reached1; e1.push_back(toD(r, "evals_to_1pct")); }
      if (toD(r, "evals_to_0.01pct") >= 0) {
        ++reached001;
        e001.push_back(toD(r, "evals_to_0.01pct"));
        w001.push_back(toD(r, "wall_to_0.01pct"));
      }
    }
    if (n == 0) continue;
    if (!applicable) {
      md << "| " << m << " | " << n << " | n/a | n/a | | | | | | | " << note << " |\n";
      continue;
    }
    auto reach = [&](const std::vector<double>& v, int k) {
      return k == 0 ? std::string("never") : num(median(v), "%.4g") + (k < n ? " (" + std::to_string(k) + "/" + std::to_string(n) + ")" : "");
    };
    md << "| " << m << " | " << n << " | " << num(median(med), "%.3g") << " | " << num(median(mx), "%.3g")
       << " | " << num(median(ev), "%.0f") << " | " << num(median(wall), "%.3g") << " | "
       << reach(e1, reached1) << " | " << reach(e001, reached001) << " | "
       << (reached001 ? num(median(w001), "%.3g") : "never") << " | " << bounded << "/" << n << " | "
       << note << " |\n";
  }
  md << "\n";
}

}  // namespace

void speedSection(const SummaryData& d, std::ostream& md) {
  const std::vector<Row>& sa = d.sa;
  md << "## (a) Speed against accuracy\n\nMedian over seeds; the answer of a method is its best-cost "
        "point; evaluations = full-cost equivalents (LM: one residual vector = one evaluation; its "
        "forward-difference Jacobian costs n+1). Runs stop at 0.001 % max error, at the evaluation budget or "
        "at the time limit; `default` stops by itself and is judged on its final answer (its "
        "\"evals to\" columns: its whole run when the final answer is within the threshold). "
        "paper_object is timed alone (no other job on the machine), and its runs "
        "under 1 s are timed three times (the same seed gives the same run), the median time kept. "
        "Curves: `speed_accuracy_<scene>.png` (seed 1).\n\n";
  std::vector<std::string> scenes;
  for (const Row& r : sa)
    if (std::find(scenes.begin(), scenes.end(), r.at("scene")) == scenes.end()) scenes.push_back(r.at("scene"));
  for (const std::string& scene : scenes) speedSceneTable(sa, d.order, scene, md);
}

void rolloutSection(const SummaryData& d, std::ostream& md) {
  const std::vector<Row>& sa = d.sa;
  const std::vector<Row>& st = d.st;
  const std::vector<std::string>& order = d.order;
  md << "## (c) Long rollouts (10x the window, at least 100 frames) that stay bounded\n\n"
        "The identified model (identification substeps; `default`: the substeps it chose; a run "
        "without an answer counts as unbounded) is simulated from the exact state at the "
        "first data frame; bounded = every particle stays within 10x the larger of the object's "
        "extent and the true motion's largest displacement. Chart: `rollout.png`.\n\n"
        "| method | map runs | bounded | share | speed-accuracy runs | bounded | share |\n"
        "|---|---|---|---|---|---|---|\n";
  std::ostringstream csv;
  csv << "method,map_runs,map_bounded,map_share,speed_runs,speed_bounded,speed_share\n";
  for (const std::string& m : order) {
    int n_map = 0, b_map = 0, n_sa = 0, b_sa = 0;
    for (const Row& r : st)
      if (r.at("method") == m && r.at("applicable") == "1" &&
          !(r.at("axis") == "occlusion" && r.at("value") == "0")) {
        ++n_map;
        b_map += r.at("bounded") == "1";
      }
    for (const Row& r : sa)
      if (r.at("method") == m && r.at("applicable") == "1") {
        ++n_sa;
        b_sa += r.at("bounded") == "1";
      }
    if (n_map + n_sa == 0) continue;
    md << "| " << m << " | " << n_map << " | " << b_map << " | "
       << (n_map ? num(100.0 * b_map / n_map, "%.0f") + " %" : "-") << " | " << n_sa << " | " << b_sa
       << " | " << (n_sa ? num(100.0 * b_sa / n_sa, "%.0f") + " %" : "-") << " |\n";
    csv << m << "," << n_map << "," << b_map << "," << (n_map ? num(double(b_map) / n_map) : "n/a") << ","
        << n_sa << "," << b_sa << "," << (n_sa ? num(double(b_sa) / n_sa) : "n/a") << "\n";
  }
  std::ofstream(d.s.out + "/rollout.csv") << csv.str();
  md << "\nThe omega_h axis beyond the explicit limit (omega*h > 2 with one step per frame) "
        "makes any model close to the truth unstable in a rollout: see the per-setting "
        "`bounded_rate` column of `stability_rates.csv`.\n\n";
}

void scalingSection(const SummaryData& d, std::ostream& md) {
  md << "## (d) Engine scaling: time per generation (100 children)\n\nSheets of linear springs "
        "(structural, shear, bending: 6 unknowns), 10 frames; es_local with `threads` 1 and 2. "
        "Chart: `scaling.png`.\n\n| particles | bonds | threads | s per generation | s per evaluation | "
        "efficiency | load average |\n|---|---|---|---|---|---|---|\n";
  for (const Row& r : d.sc)
    md << "| " << r.at("particles") << " | " << r.at("bonds") << " | " << r.at("threads") << " | "
       << num(toD(r, "s_per_generation"), "%.4g") << " | " << num(toD(r, "s_per_evaluation"), "%.3g") << " | "
       << num(100 * toD(r, "parallel_efficiency"), "%.0f") << " % | " << r.at("load_average") << " |\n";
  md << "\n";
}

}  // namespace peers

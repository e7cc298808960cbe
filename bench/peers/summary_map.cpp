// Section (b) of bench_peers' summary: the stability map's success rates, one table per axis
// (with stability_rates.csv, and the settings where each method fails), the notes on the
// conditional axis, and the noise axis against the Cramer-Rao bound (with efficiency.csv).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "instances.h"
#include "summary.h"

namespace peers {
namespace {

/// The settings of one axis in the map, in numeric order.
std::vector<std::string> axisValues(const std::vector<Row>& st, const std::string& axis) {
  std::vector<std::string> values;
  for (const Row& r : st)
    if (r.at("axis") == axis && std::find(values.begin(), values.end(), r.at("value")) == values.end())
      values.push_back(r.at("value"));
  std::sort(values.begin(), values.end(), [](const std::string& a, const std::string& b) {
    return std::atof(a.c_str()) < std::atof(b.c_str());
  });
  return values;
}

/// One setting's row: successes/runs per method (and its line of stability_rates.csv).
void axisRow(const std::vector<Row>& st, const std::string& axis, size_t pos, const std::string& v,
             const std::vector<std::string>& columns, std::ostream& md, std::ostream& rates_csv,
             FailureCells* fails_at_out) {
  FailureCells& fails_at = *fails_at_out;
  md << "| " << v << " |";
  for (const std::string& m : columns) {
    int runs = 0, ok = 0, bounded = 0, not_applicable = 0;
    std::vector<double> ev, wall;
    for (const Row& r : st) {
      if (r.at("axis") != axis || r.at("value") != v || r.at("method") != m) continue;
      ++runs;
      not_applicable += r.at("applicable") != "1";
      ok += r.at("success") == "1";
      bounded += r.at("bounded") == "1";
      if (r.at("success") == "1") ev.push_back(toD(r, "evals_to_1pct"));
      wall.push_back(toD(r, "wall_s"));
    }
    if (runs == 0) {
      md << " |";
      continue;
    }
    if (not_applicable == runs) {
      md << " n/a |";
      rates_csv << axis << "," << v << "," << pos << "," << m << "," << runs << ",0,n/a,n/a,n/a,n/a\n";
      continue;
    }
    md << " " << ok << "/" << runs << (not_applicable ? " (" + std::to_string(not_applicable) + " n/a)" : "") << " |";
    rates_csv << axis << "," << v << "," << pos << "," << m << "," << runs << "," << ok << ","
              << num(static_cast<double>(ok) / runs) << "," << num(static_cast<double>(bounded) / runs)
              << "," << num(median(ev)) << "," << num(median(wall)) << "\n";
    if (2 * ok < runs) fails_at[m].push_back(axis + "=" + v);
  }
  md << "\n";
}

/// sade_final's runs that passed within 1 % but ended outside (conditional axis).
void sadeFinalNote(const std::vector<Row>& st, const std::string& axis, const std::vector<std::string>& values,
                   std::ostream& md) {
  md << "`sade_final` is `sade` without the oracle stop, judged on its best point at the "
        "budget's end (as `default` is judged on its final answer); its runs that passed within "
        "1 % at some moment but ended outside: ";
  std::string lost;
  for (const std::string& v : values) {
    int passed = 0, kept = 0;
    for (const Row& r : st)
      if (r.at("axis") == axis && r.at("value") == v && r.at("method") == "sade_final") {
        passed += r.at("ever_within_1pct") == "1";
        kept += r.at("success") == "1";
      }
    lost += (lost.empty() ? "" : ", ") + v + " cables: " + std::to_string(passed - kept) + " of " +
            std::to_string(passed);
  }
  md << lost << ".\n\n";
}

/// How far the data determine the thresholds: the middle of the truth's flat interval.
void thresholdNote(const std::vector<Row>& st, const std::string& axis, const std::vector<std::string>& values,
                   const std::vector<std::string>& columns, std::ostream& md) {
  std::string line;
  for (const std::string& v : values) {
    int n = 0, within = 0;
    std::vector<double> mid;
    for (const Row& r : st)
      if (r.at("axis") == axis && r.at("value") == v && r.at("method") == columns.front() &&
          std::isfinite(toD(r, "threshold_middle_max_pct"))) {
        ++n;
        within += toD(r, "threshold_middle_max_pct") < 1.0;
        mid.push_back(toD(r, "threshold_middle_max_pct"));
      }
    if (n > 0)
      line += (line.empty() ? "" : ", ") + v + " cables: " + std::to_string(within) + "/" +
              std::to_string(n) + " (median worst " + num(median(mid), "%.2g") + " %)";
  }
  if (!line.empty())
    md << "A threshold is determined by the data only up to the flat interval between the "
          "observed lengths around it; the middle of the truth's interval (what the threshold "
          "search returns at best) has every threshold within 1 % of the truth in: " << line
       << ". The rest cannot be a success for a method judged on such a final answer.\n\n";
}

/// One axis' table and its notes.
void axisTable(const std::vector<Row>& st, const std::vector<std::string>& map_order, const std::string& axis,
               const std::string& doc, std::ostream& md, std::ostream& rates_csv, FailureCells* fails_at) {
  const std::vector<std::string> values = axisValues(st, axis);
  if (values.empty()) return;
  // The columns: the methods with runs on this axis (sade_final: the conditional axis only).
  std::vector<std::string> columns;
  for (const std::string& m : map_order)
    if (std::any_of(st.begin(), st.end(), [&](const Row& r) { return r.at("axis") == axis && r.at("method") == m; }))
      columns.push_back(m);
  md << "### " << axis << ": " << doc << "\n\n| " << axis << " |";
  for (const std::string& m : columns) md << " " << m << " |";
  md << "\n|---|";
  for (size_t k = 0; k < columns.size(); ++k) md << "---|";
  md << "\n";
  for (size_t pos = 0; pos < values.size(); ++pos) axisRow(st, axis, pos, values[pos], columns, md, rates_csv, fails_at);
  md << "\n";
  if (axis == "conditional" && std::find(columns.begin(), columns.end(), "sade_final") != columns.end())
    sadeFinalNote(st, axis, values, md);
  if (axis == "conditional") thresholdNote(st, axis, values, columns, md);
}

/// One noise level's table against the bound (and its lines of efficiency.csv).
void noiseLevelTable(const std::vector<Row>& st, const std::vector<std::string>& map_order, const std::string& v,
                     std::ostream& md, std::ostream& eff_csv) {
double expected = 0.0;
int instances = 0;
for (const Row& r : st)
  if (r.at("axis") == "noise" && r.at("value") == v && r.at("method") == map_order.front()) {
    ++instances;
    expected += std::isfinite(toD(r, "efficient_success_prob")) ? toD(r, "efficient_success_prob") : 0.0;
  }
md << "#### noise " << v << " m\n\nAn efficient estimator (errors normal with the bound as std, "
      "independent) would get every parameter within 1 % in " << num(expected, "%.1f") << " of "
   << instances << " runs (expected).\n\n| method | successes | median error % | max error % | "
      "bound median % | bound max % | median efficiency (error / bound) | final answer by output error |\n"
      "|---|---|---|---|---|---|---|---|\n";
for (const std::string& m : map_order) {
  int runs = 0, ok = 0, oe = 0, pipeline = 0;
  std::vector<double> med, mx, bmed, bmax, eff;
  for (const Row& r : st) {
    if (r.at("axis") != "noise" || r.at("value") != v || r.at("method") != m) continue;
    ++runs;
    ok += r.at("success") == "1";
    med.push_back(toD(r, "median_error_pct"));
    mx.push_back(toD(r, "max_error_pct"));
    bmed.push_back(toD(r, "bound_median_pct"));
    bmax.push_back(toD(r, "bound_max_pct"));
    eff.push_back(toD(r, "efficiency"));
    if (r.count("output_error") && r.at("output_error") != "n/a") {
      ++pipeline;
      oe += r.at("output_error") == "1";
    }
  }
  if (runs == 0) continue;
  const std::string oe_cell = pipeline ? std::to_string(oe) + "/" + std::to_string(pipeline) : "-";
  md << "| " << m << " | " << ok << "/" << runs << " | " << num(median(med), "%.3g") << " | "
     << num(median(mx), "%.3g") << " | " << num(median(bmed), "%.3g") << " | "
     << num(median(bmax), "%.3g") << " | " << num(median(eff), "%.3g") << " | " << oe_cell << " |\n";
  eff_csv << v << "," << m << "," << runs << "," << ok << "," << num(median(med)) << ","
          << num(median(mx)) << "," << num(median(bmed)) << "," << num(median(bmax)) << ","
          << num(median(eff)) << "," << (pipeline ? std::to_string(oe) : "n/a") << ","
          << num(expected) << "\n";
}
md << "\n";
}

}  // namespace

void mapSection(const SummaryData& d, const std::vector<std::string>& map_order, std::ostream& md,
                FailureCells* fails_at) {
  md << "## (b) Stability map: success rate (all parameters within 1 %)\n\nBase: paper_object, "
     << kMapFrames << " frames at 100 Hz, noise-free, fully visible, starts from the paper's initial "
        "distribution; each axis changes one thing. Budget per run: 45 000 evaluations or 20 s "
        "(40 s from 100 unknowns); a run stops at success, except `default` and `islands` (judged "
        "on their final answer; they stop by themselves) and `sade_final`. Cells: successes/runs. Chart: "
        "`stability_map.png`.\n\n";
  std::vector<std::string> axis_order = {"noise", "omega_h", "occlusion", "spread", "unknowns", "conditional"};
  const std::map<std::string, std::string> axis_doc = {
      {"noise", "Gaussian noise std [m] on every coordinate"},
      {"omega_h", "omega_max * h: frame rate set from the stiffest mode; data integrated with 20 "
                  "substeps per frame, identification with 1 (explicit limit: 2)"},
      {"occlusion", "share of samples occluded at random"},
      {"spread", "initial-guess spread: starts = truth + N(0, spread x gene range) (log genes)"},
      {"unknowns", "random objects (makeRandomObject, 2 unknowns per bond type), 30 frames"},
      {"conditional", "cable types (active only when stretched; free min_distance) among 10 "
                      "spring types of a random 15-particle object"}};
  std::ostringstream rates_csv;
  rates_csv << "axis,value,position,method,runs,successes,success_rate,bounded_rate,"
               "median_evals_to_1pct,median_wall_s\n";
  for (const std::string& axis : axis_order)
    axisTable(d.st, map_order, axis, axis_doc.at(axis), md, rates_csv, fails_at);
  std::ofstream(d.s.out + "/stability_rates.csv") << rates_csv.str();
}

void noiseSection(const SummaryData& d, const std::vector<std::string>& map_order, std::ostream& md) {
  const std::vector<Row>& st = d.st;
  std::vector<std::string> levels;
  for (const Row& r : st)
    if (r.at("axis") == "noise" && toD(r, "value") > 0.0 &&
        std::find(levels.begin(), levels.end(), r.at("value")) == levels.end())
      levels.push_back(r.at("value"));
  std::sort(levels.begin(), levels.end(), [](const std::string& a, const std::string& b) {
    return std::atof(a.c_str()) < std::atof(b.c_str());
  });
  std::ostringstream eff_csv;
  eff_csv << "noise_m,method,runs,successes,median_error_pct,max_error_pct,bound_median_pct,"
             "bound_max_pct,median_efficiency,output_error_runs,efficient_expected_successes\n";
  if (!levels.empty())
    md << "### noise: errors against the Cramer-Rao bound\n\nThe bound (`mme::cramerRaoBound`): "
          "the 1-sigma error an efficient estimator of the output-error model reaches, initial "
          "positions and velocities unknown, for white marker noise of the axis' std; computed once "
          "per instance on the truth (identification substeps) and its noiseless data (same "
          "occlusion pattern); n/a for thresholds. Per run, efficiency = median over the parameters "
          "of |error| / bound; an efficient estimator's is about 0.67 (the median of |N(0, 1)|). "
          "Medians over the seeds. The methods stopped by the oracle at 1 % report the point where "
          "it stopped them where they succeed (a figure of the stop, not of their minimum). Chart: "
          "`efficiency.png`.\n\n";
  for (const std::string& v : levels) noiseLevelTable(st, map_order, v, md, eff_csv);
  if (!st.empty()) std::ofstream(d.s.out + "/efficiency.csv") << eff_csv.str();
}

}  // namespace peers

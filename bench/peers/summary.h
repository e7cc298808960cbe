// The sections of bench_peers' summary.md, one writer each, and what they share: the CSV files
// read back (the summary is drawn from them alone, so `--summary-only` redraws it from a run's
// files). summary.cpp puts the sections in order.
#pragma once

#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "common.h"

namespace peers {

/// The run's CSV files read back, and the methods in the summary's order.
struct SummaryData {
  const Settings& s;
  std::vector<std::string> order;  ///< every method, in the tables' order
  std::vector<Row> sa;             ///< speed_accuracy_runs.csv
  std::vector<Row> st;             ///< stability_runs.csv
  std::vector<Row> sc;             ///< scaling.csv
};

/// method -> the map settings where its success rate is below 50 %.
using FailureCells = std::map<std::string, std::vector<std::string>>;

// summary_targets.cpp: the targets table (rows into md, lines into targets_csv).
void engineTargets(const SummaryData& d, std::ostream& md, std::ostream& targets_csv);
void unknownsTargets(const SummaryData& d, std::ostream& md, std::ostream& targets_csv,
                     std::ostream& gens_csv);
void defaultTargets(const SummaryData& d, std::ostream& md, std::ostream& targets_csv);
void parallelTarget(const SummaryData& d, std::ostream& md, std::ostream& targets_csv);

// summary_tables.cpp: (a) speed against accuracy, (c) rollouts (rollout.csv), (d) scaling.
void speedSection(const SummaryData& d, std::ostream& md);
void rolloutSection(const SummaryData& d, std::ostream& md);
void scalingSection(const SummaryData& d, std::ostream& md);

// summary_map.cpp: (b) the stability map (stability_rates.csv; fills fails_at) and the noise
// axis against the Cramer-Rao bound (efficiency.csv). map_order: the methods the map ran.
void mapSection(const SummaryData& d, const std::vector<std::string>& map_order, std::ostream& md,
                FailureCells* fails_at);
void noiseSection(const SummaryData& d, const std::vector<std::string>& map_order, std::ostream& md);

// summary_failures.cpp: why each method fails where it fails.
void failureSection(const SummaryData& d, const FailureCells& fails_at, std::ostream& md);

}  // namespace peers

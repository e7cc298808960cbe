// The parts of a bench_peers run, each writing its CSV files into Settings::out: (a) speed
// against accuracy (speed_part.cpp), (b) the stability map (map_part.cpp), (d) the engine's
// scaling (scaling_part.cpp), and the summary drawn from the CSV files (summary.cpp).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "common.h"

namespace peers {

/// A scene of the speed part: its seeds, each run's budget and how to build its problem.
struct SpeedScene {
  std::string name;
  int seeds;
  Budget budget;
  std::function<Problem()> build;
  bool sequential;  ///< timed alone (no other benchmark job on the machine)
};

/// The speed part's scenes for this mode, narrowed by --scenes (an unknown name: InputError)
/// and with --speed-seeds applied.
std::vector<SpeedScene> speedScenes(const Settings& s);

/// (a): speed_accuracy_runs.csv and speed_accuracy_trace.csv.
void speedAccuracy(const Settings& s, const std::vector<std::string>& methods);

/// (b): stability_runs.csv.
void stabilityMap(const Settings& s, const std::vector<std::string>& methods);

/// (d): scaling.csv.
void scaling(const Settings& s);

/// summary.md, targets.csv, unknowns_generations.csv, stability_rates.csv, efficiency.csv and
/// rollout.csv from the CSV files in Settings::out (total_wall_s 0: not reported).
void summary(const Settings& s, double total_wall_s);

}  // namespace peers

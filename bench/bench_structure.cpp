// bench_structure: the structure step alone, as `identify --select-structure` runs it (the
// markers as particles, identify's default search settings for the levels' refits), on one
// capture: its wall and CPU time, the chosen level, and the report CSV for a diff between builds.
//
//   bench_structure TRAJECTORY [--frames N] [--report OUT.csv] [--progress 1]
//
// --progress 1 prints the selection's own lines on stderr, each with the seconds since its start.
// Prints one line: file, markers, frames, wall_s, cpu_s, chosen level, bonds, types, parameters.
// Time is measured here and only compared as ratios of runs on the same machine at the same time.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <fstream>
#include <string>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/structure/marker_model.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "motion_model_estimation/io/trajectory_io.h"

namespace {

/// identify's settings for the structure step (its defaults: the default preset, 1000
/// generations, population 100, seed 1, one thread, no time limit).
mme::StructureOptions identifyDefaults() {
  mme::StructureOptions so;
  mme::IdentifyOptions& o = so.identify;
  o = mme::identifyOptionsFor(mme::Preset::kDefault);
  o.generations = 1000;
  o.es.population = 100;
  o.es.offspring = o.es.population;
  o.es.seed = 1;
  o.es.threads = 1;
  return so;
}

int run(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_structure TRAJECTORY [--frames N] [--report OUT.csv] [--progress 1]\n");
    return 2;
  }
  const std::string path = argv[1];
  int frames = 240;
  std::string report;
  bool progress = false;
  for (int k = 2; k + 1 < argc; k += 2) {
    const std::string key = argv[k];
    if (key == "--frames") frames = std::atoi(argv[k + 1]);
    else if (key == "--report") report = argv[k + 1];
    else if (key == "--progress") progress = std::string(argv[k + 1]) != "0";
    else throw mme::InputError("unknown option '" + key + "'");
  }
  if (frames < 1) throw mme::InputError("--frames must be at least 1");
  const mme::Trajectory data = mme::readTrajectoryFile(path);
  mme::Model model = mme::markerModel(data);
  const mme::Trajectory used = mme::sliceFrames(data, 0, std::min(frames, data.numFrames()));
  const std::clock_t cpu_start = std::clock();
  const auto wall_start = std::chrono::steady_clock::now();
  mme::StructureOptions so = identifyDefaults();
  if (progress)
    so.progress = [wall_start](const std::string& line) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      std::fprintf(stderr, "[%7.2f s] %s\n", s, line.c_str());
    };
  const mme::StructureResult r = mme::selectStructure(model, used, so);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const double cpu_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  const mme::StructureCandidate* chosen = nullptr;
  for (const mme::StructureCandidate& c : r.candidates)
    if (c.chosen) chosen = &c;
  if (!report.empty()) std::ofstream(report) << mme::structureReportCsv(r);
  std::printf("%s markers %d frames %d wall_s %.2f cpu_s %.2f chosen %s bonds %d types %d parameters %d\n",
              path.c_str(), used.numMarkers(), used.numFrames(), wall_s, cpu_s,
              chosen ? chosen->name.c_str() : "-", chosen ? chosen->bonds : 0,
              chosen ? chosen->bond_types : 0, chosen ? chosen->parameters : 0);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const mme::InputError& e) {
    std::fprintf(stderr, "bench_structure: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_structure: %s\n", e.what());
    return 2;
  }
}

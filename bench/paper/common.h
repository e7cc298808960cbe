// bench_paper's shared pieces: the settings from the command line, relative parameter errors,
// one identification run with its error trace, the CSV and table writers and the summary.csv line
// every paper experiment appends. Each experiment lives in its own file (experiments.h lists them)
// and runs the offline pipeline's named steps (pipeline/identify_pipeline.h), so that what the
// bench measures is what `identify` runs.
#pragma once

#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/pipeline/identify_pipeline.h"

namespace paper {

using mme::Model;

struct Errors {
  double mean = 0, median = 0, max = 0;  // relative errors [%]
};

Errors relativeErrors(const std::vector<double>& values, const std::vector<double>& truth);

/// The model as identification sees it: free values forgotten (bounds kept).
Model forgetFreeValues(Model m);

struct RunResult {
  mme::IdentifyResult result;
  Errors errors;
  int generations_to_target = -1;  // first generation with max error < 0.01 %
};

RunResult runEs(const Model& truth, const mme::Trajectory& data, mme::IdentifyOptions options,
                const std::function<void(const mme::Progress&, const Errors&)>& per_generation);

std::FILE* openCsv(const std::string& path, const char* header);
void writeTable(const std::string& path, const RunResult& r, const Model& truth);
void printTable(const char* title, const RunResult& r, const Model& truth);

struct Settings {
  std::string out_dir = "docs/paper";
  bool quick = false;
  int threads = 1;
  std::string only;
  int generations = 0;       // 0 = each experiment's default
  int refine_start = -1;     // -1 = engine default
  int refine_period = -1;
  int refine_evaluations = -1;
  std::string refine;        // "" = the preset's
  mme::Preset preset = mme::Preset::kPaper;  // the paper's experiments with its own settings
  uint64_t seed = 1;
  std::string fig5_cases;    // "" = every case of fig5
  std::string stages_cases;  // "" = every recording of stages
  bool wants(const std::string& name) const {
    return only.empty() || ("," + only + ",").find("," + name + ",") != std::string::npos;
  }
  bool wantsFig5Case(const std::string& name) const { return listed(fig5_cases, name); }
  bool wantsStagesCase(const std::string& name) const { return listed(stages_cases, name); }
  /// `name` is in the comma-separated `list`, or the list is empty (everything).
  static bool listed(const std::string& list, const std::string& name) {
    return list.empty() || ("," + list + ",").find("," + name + ",") != std::string::npos;
  }
};

/// summary.csv (open only when an experiment that writes to it runs).
extern std::FILE* g_summary;

/// Appends one experiment's line to summary.csv.
void summary(const std::string& experiment, const RunResult& r);

/// The identification options of the ES experiments (the preset, --generations, the refinement
/// overrides, threads and seed).
mme::IdentifyOptions esOptions(const Settings& s, int generations);

/// The pipeline's options for its identification step alone: `identify`, and `progress` after
/// every generation (may be empty).
mme::PipelineOptions identifyStep(const mme::IdentifyOptions& identify,
                                  std::function<void(const mme::Progress&)> progress = nullptr);

/// The pipeline's options for its structure step as the benchmarks run it: the default engine,
/// no std.
mme::PipelineOptions structureStep(const Settings& s);

/// The pipeline's structure step on the fitted part of `split` only (`split.fit`, its starting
/// model: particles from the markers), so that the held-out frames a benchmark then reports were seen by no choice: the
/// selection ranks its levels on the end of the fitted part, never on `split.held`'s frames
/// from `split.held_start`. Throws std::logic_error (checkUnseen) when the frames it saw reach
/// the reported ones.
mme::StructureResult selectStructureOnFitted(const mme::HeldOutSplit& split,
                                             const mme::PipelineOptions& options);

/// Throws std::logic_error naming `who` unless every frame of `seen` comes before the first
/// frame `split` reports (`split.held` from `split.held_start`), by their times.
void checkUnseen(const mme::Trajectory& seen, const mme::HeldOutSplit& split, const std::string& who);

}  // namespace paper

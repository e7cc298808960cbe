// bench_paper: reproduces the paper's experiments (section 4) on the built-in scenes and writes CSV
// files (see --help; one file per experiment in this folder, experiments.h lists them):
//   fig1.csv     log cost and parameter error against generations, paper_object, 4 noise levels
//   table1.csv   provot_cloth from its single equilibrium frame
//   table2.csv   fluid_jet
//   scaling.csv  generations to 0.01% error against the number of bond types (random objects)
//   summary.csv  one line per experiment (errors, generations, wall time)
//   fig5.csv     log cost against generations without muscles, with dampers, with muscles
//                (walker and real recordings; fig5_summary.csv: held-out prediction errors)
// Also: `bench_paper compare TRUTH.yaml ESTIMATE.yaml` prints per-parameter errors.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "common.h"
#include "experiments.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/model_yaml.h"

using namespace paper;

namespace {

int compare(const std::string& truth_path, const std::string& estimate_path) {
  const Model truth = mme::loadModelFile(truth_path);
  const Model estimate = mme::loadModelFile(estimate_path);
  const std::vector<mme::ParamRef> refs = mme::freeParameters(estimate);
  std::vector<double> t, e;
  std::printf("%-26s %14s %14s %10s\n", "parameter", "true", "estimate", "error %");
  for (const mme::ParamRef& r : refs) {
    t.push_back(mme::getParam(truth, r));
    e.push_back(mme::getParam(estimate, r));
    std::printf("%-26s %14.8g %14.8g %10.5f\n", r.name.c_str(), t.back(), e.back(),
                100.0 * (e.back() - t.back()) / std::abs(t.back()));
  }
  const Errors err = relativeErrors(e, t);
  std::printf("compare: %zu parameters, median error %.5f %%, max %.5f %%\n", refs.size(),
              err.median, err.max);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc == 4 && std::strcmp(argv[1], "compare") == 0) return compare(argv[2], argv[3]);
    Settings s;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--quick") s.quick = true;
      else if (a == "--out-dir" && i + 1 < argc) s.out_dir = argv[++i];
      else if (a == "--threads" && i + 1 < argc) s.threads = std::max(1, std::atoi(argv[++i]));
      else if (a == "--only" && i + 1 < argc) s.only = argv[++i];
      else if (a == "--generations" && i + 1 < argc) s.generations = std::atoi(argv[++i]);
      else if (a == "--refine-start" && i + 1 < argc) s.refine_start = std::atoi(argv[++i]);
      else if (a == "--refine-period" && i + 1 < argc) s.refine_period = std::atoi(argv[++i]);
      else if (a == "--refine-evaluations" && i + 1 < argc) s.refine_evaluations = std::atoi(argv[++i]);
      else if (a == "--refine" && i + 1 < argc) s.refine = argv[++i];
      else if (a == "--preset" && i + 1 < argc) {
        if (!mme::parsePreset(argv[++i], &s.preset)) {
          std::fprintf(stderr, "bench_paper: --preset must be %s\n", mme::presetNames());
          return 2;
        }
      }
      else if (a == "--seed" && i + 1 < argc) s.seed = std::strtoull(argv[++i], nullptr, 10);
      else if (a == "--fig5-cases" && i + 1 < argc) s.fig5_cases = argv[++i];
      else if (a == "--stages-cases" && i + 1 < argc) s.stages_cases = argv[++i];
      else {
        std::fprintf(stderr, "usage: bench_paper [--quick] [--out-dir DIR] [--threads T] "
                             "[--only fig1,table1,table2,scaling,random18,defaults,accuracy,\n"
                             "        online,structure,structure_real,fig5,stages,walker_oe,\n"
                             "        walker_identify,oe_speed,oe_speed_small]\n"
                             "       [--generations N] [--refine-start G] [--refine-period G]\n"
                             "       [--refine-evaluations E] [--refine ALGORITHM] [--seed S]\n"
                             "       [--fig5-cases walker,Sample01_Eb015pi.c3d,...] (default: all)\n"
                             "       [--stages-cases Sample01_Eb015pi.c3d,...] (default: all)\n"
                             "       [--preset paper|default] (default: paper)\n"
                             "       bench_paper compare TRUTH.yaml ESTIMATE.yaml\n");
        return 2;
      }
    }
    // summary.csv only when an experiment that writes to it runs (a partial run into the same
    // directory keeps the last full one's).
    if (s.wants("table1") || s.wants("fig1") || s.wants("table2") || s.wants("scaling") ||
        s.wants("random18"))
      g_summary = openCsv(s.out_dir + "/summary.csv",
                          "experiment,unknowns,mean_error_percent,median_error_percent,"
                          "max_error_percent,generations,generations_to_0.01pct,evaluations,"
                          "wall_s,global_cost");
    if (s.wants("random18")) randomObjectFiles(s);
    if (s.wants("defaults")) defaultsExperiment(s);
    if (s.wants("accuracy")) accuracyExperiment(s);
    if (s.wants("online")) onlineExperiment(s);
    if (s.wants("structure")) structureExperiment(s);
    if (s.wants("structure") || s.wants("structure_real")) structureRealExperiment(s);
    if (s.wants("fig5")) figure5(s);
    if (!s.only.empty() && s.wants("stages")) stagesExperiment(s);  // opt-in only
    if (!s.only.empty() && s.wants("walker_oe")) walkerOutputError(s);  // opt-in only
    if (!s.only.empty() && s.wants("walker_identify")) walkerIdentify(s);  // opt-in only
    if (!s.only.empty() && (s.wants("oe_speed") || s.wants("oe_speed_small")))
      outputErrorSpeed(s);  // opt-in only
    if (s.wants("table1")) table1(s);
    if (s.wants("fig1")) figure1(s);
    if (s.wants("table2")) table2(s);
    if (s.wants("scaling")) scaling(s);
    if (g_summary) std::fclose(g_summary);
    return 0;
  } catch (const mme::InputError& e) {
    std::fprintf(stderr, "bench_paper: %s\n", e.what());
    return 2;
  }
}

// The paper's own experiments on the built-in scenes (section 4), each appending its line to
// summary.csv: fig. 1 (paper_object under four noise levels), tables I and II (provot_cloth,
// fluid_jet), the scaling with the number of bond types, and the random18 model files for the
// CLI pipeline.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "common.h"
#include "experiments.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace paper {

void figure1(const Settings& s) {
  const mme::Scene scene = mme::makeScene("paper_object");
  std::FILE* f = openCsv(s.out_dir + "/fig1.csv",
                         "noise_std_m,generation,evaluations,log10_cost,log10_mean_error_percent,"
                         "median_error_percent,max_error_percent,wall_s");
  for (double noise : {0.0, 1e-5, 1e-4, 1e-3}) {
    mme::Trajectory data =
        mme::simulateTrajectory(scene.model, scene.default_frames, scene.model.frame_rate_hz);
    mme::addGaussianNoise(&data, noise, 11);
    auto log = [&](const mme::Progress& p, const Errors& e) {
      std::fprintf(f, "%g,%d,%llu,%.6f,%.6f,%.6g,%.6g,%.3f\n", noise, p.generation,
                   static_cast<unsigned long long>(p.evaluations),
                   std::log10(std::max(p.best_cost, 1e-300)),
                   std::log10(std::max(e.mean, 1e-300)), e.median, e.max, p.wall_time_s);
    };
    const RunResult r = runEs(scene.model, data, esOptions(s, 1000), log);
    char name[64];
    std::snprintf(name, sizeof(name), "fig1_noise_%g", noise);
    std::printf("paper_object noise %g m: mean error %.5f %%, median %.5f %%, max %.5f %%, "
                "cost %.3e, %.1f s, %d generations to max error < 0.01 %%\n",
                noise, r.errors.mean, r.errors.median, r.errors.max, r.result.global_cost,
                r.result.wall_time_s, r.generations_to_target);
    summary(name, r);
  }
  std::fclose(f);
}

void table1(const Settings& s) {
  const mme::Scene scene = mme::makeScene("provot_cloth");
  const RunResult r = runEs(scene.model, scene.reference_data, esOptions(s, 1000), nullptr);
  printTable("Table I: provot_cloth (single equilibrium frame)", r, scene.model);
  writeTable(s.out_dir + "/table1.csv", r, scene.model);
  summary("table1_provot_cloth", r);
}

void table2(const Settings& s) {
  const mme::Scene scene = mme::makeScene("fluid_jet");
  const mme::Trajectory data =
      mme::simulateTrajectory(scene.model, scene.default_frames, scene.model.frame_rate_hz);
  const RunResult r = runEs(scene.model, data, esOptions(s, 1000), nullptr);
  printTable("Table II: fluid_jet", r, scene.model);
  writeTable(s.out_dir + "/table2.csv", r, scene.model);
  summary("table2_fluid_jet", r);
}

void scaling(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/scaling.csv",
                         "bond_types,unknowns,particles,bonds,generations_to_0.01pct,"
                         "final_max_error_percent,evaluations,wall_s");
  for (int types : {5, 10, 20, 40}) {
    mme::RandomObjectSpec spec;
    spec.bond_types = types;
    spec.particles = std::max(8, types + types / 2);
    spec.bonds = 3 * types;
    spec.frame_rate_hz = 100.0;
    spec.seed = 100 + types;
    const Model truth = mme::makeRandomObject(spec);
    const mme::Trajectory data = mme::simulateTrajectory(truth, 100, spec.frame_rate_hz);
    const RunResult r = runEs(truth, data, esOptions(s, 1500), nullptr);
    std::fprintf(f, "%d,%d,%d,%d,%d,%.6g,%llu,%.3f\n", types, 2 * types, spec.particles,
                 spec.bonds, r.generations_to_target, r.errors.max,
                 static_cast<unsigned long long>(r.result.evaluations), r.result.wall_time_s);
    std::fflush(f);
    std::printf("random object, %d bond types (%d unknowns): max error %.5f %%, generations to "
                "0.01 %%: %d, %.1f s\n", types, 2 * types, r.errors.max, r.generations_to_target,
                r.result.wall_time_s);
    summary("scaling_" + std::to_string(types) + "_types", r);
  }
  std::fclose(f);
}

/// Writes the truth and the no-values model of the 18-marker random object (a benchmark target) for
/// the CLI pipeline in scripts/bench-paper.
void randomObjectFiles(const Settings& s) {
  mme::RandomObjectSpec spec;  // 18 markers, 12 types, 40 bonds, 120 Hz
  spec.seed = 2026;
  Model truth = mme::makeRandomObject(spec);
  mme::writeModelFile(s.out_dir + "/random18_truth.yaml", truth);
  // No values and no bounds for the free parameters: the defaults must do.
  Model blank = forgetFreeValues(truth);
  for (mme::BondType& t : blank.bond_types)
    for (mme::Param& p : t.params) {
      p.has_min = p.has_max = false;
      p.min = -INFINITY;
      p.max = INFINITY;
    }
  mme::writeModelFile(s.out_dir + "/random18_model.yaml", blank);
  std::printf("wrote %s/random18_truth.yaml and random18_model.yaml\n", s.out_dir.c_str());
}

}  // namespace paper

// Reproduces the paper's experiments (section 4) on the built-in scenes and writes CSV files:
//   fig1.csv     log cost and parameter error against generations, paper_object, 4 noise levels
//   table1.csv   provot_cloth from its single equilibrium frame
//   table2.csv   fluid_jet
//   scaling.csv  generations to 0.01% error against the number of bond types (random objects)
//   summary.csv  one line per experiment (errors, generations, wall time)
//   fig5.csv     log cost against generations without muscles, with dampers, with muscles
//                (walker and real recordings; fig5_summary.csv: held-out prediction errors)
// Also: `bench_paper compare TRUTH.yaml ESTIMATE.yaml` prints per-parameter errors.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/structure/marker_model.h"
#include "motion_model_estimation/identification/muscles/muscle_placement.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "motion_model_estimation/identification/online/online_estimator.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "motion_model_estimation/identification/search/parameter_space.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/io/trc.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace {

using mme::Model;

struct Errors {
  double mean = 0, median = 0, max = 0;  // relative errors [%]
};

Errors relativeErrors(const std::vector<double>& values, const std::vector<double>& truth) {
  std::vector<double> e;
  for (size_t k = 0; k < values.size(); ++k)
    e.push_back(100.0 * std::abs(values[k] - truth[k]) / std::max(std::abs(truth[k]), 1e-300));
  Errors out;
  if (e.empty()) return out;
  for (double x : e) out.mean += x / e.size();
  out.max = *std::max_element(e.begin(), e.end());
  std::sort(e.begin(), e.end());
  out.median = e.size() % 2 ? e[e.size() / 2] : 0.5 * (e[e.size() / 2 - 1] + e[e.size() / 2]);
  return out;
}

/// The model as identification sees it: free values forgotten (bounds kept).
Model forgetFreeValues(Model m) {
  for (const mme::ParamRef& r : mme::freeParameters(m)) {
    mme::Param& p = mme::paramOf(m, r);
    p.has_value = false;
  }
  return m;
}

struct RunResult {
  mme::IdentifyResult result;
  Errors errors;
  int generations_to_target = -1;  // first generation with max error < 0.01 %
};

RunResult runEs(const Model& truth, const mme::Trajectory& data, mme::IdentifyOptions options,
                const std::function<void(const mme::Progress&, const Errors&)>& per_generation) {
  const std::vector<double> true_values = mme::getValues(truth, mme::freeParameters(truth));
  RunResult out;
  auto progress = [&](const mme::Progress& p) {
    const Errors e = relativeErrors(p.best_values, true_values);
    if (out.generations_to_target < 0 && e.max < 0.01) out.generations_to_target = p.generation;
    if (per_generation) per_generation(p, e);
  };
  out.result = mme::identifyModel(forgetFreeValues(truth), data, options, progress);
  out.errors = relativeErrors(out.result.values, true_values);
  return out;
}

std::FILE* openCsv(const std::string& path, const char* header) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw mme::InputError(path + ": cannot write");
  std::fprintf(f, "%s\n", header);
  return f;
}

void writeTable(const std::string& path, const RunResult& r, const Model& truth) {
  std::FILE* f = openCsv(path, "parameter,reference,estimate,error_percent,std");
  const std::vector<double> ref = mme::getValues(truth, mme::freeParameters(truth));
  for (size_t k = 0; k < r.result.parameters.size(); ++k)
    std::fprintf(f, "%s,%.9g,%.9g,%.6f,%.3g\n", r.result.parameters[k].name.c_str(), ref[k],
                 r.result.values[k], 100.0 * (r.result.values[k] - ref[k]) / std::abs(ref[k]),
                 r.result.std_devs[k]);
  std::fclose(f);
}

void printTable(const char* title, const RunResult& r, const Model& truth) {
  const std::vector<double> ref = mme::getValues(truth, mme::freeParameters(truth));
  std::printf("\n%s\n%-26s %14s %14s %10s\n", title, "parameter", "reference", "estimate", "error %");
  for (size_t k = 0; k < r.result.parameters.size(); ++k)
    std::printf("%-26s %14.7g %14.7g %10.4f\n", r.result.parameters[k].name.c_str(), ref[k],
                r.result.values[k], 100.0 * (r.result.values[k] - ref[k]) / std::abs(ref[k]));
  std::printf("median error %.5f %%, max %.5f %%, cost %.3e, %d generations, %llu evaluations, "
              "%.1f s\n", r.errors.median, r.errors.max, r.result.global_cost,
              r.result.generations, static_cast<unsigned long long>(r.result.evaluations),
              r.result.wall_time_s);
}

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
  bool wants(const std::string& name) const {
    return only.empty() || ("," + only + ",").find("," + name + ",") != std::string::npos;
  }
  bool wantsFig5Case(const std::string& name) const {
    return fig5_cases.empty() ||
           ("," + fig5_cases + ",").find("," + name + ",") != std::string::npos;
  }
};

std::FILE* g_summary = nullptr;

void summary(const std::string& experiment, const RunResult& r) {
  std::fprintf(g_summary, "%s,%zu,%.6g,%.6g,%.6g,%d,%d,%llu,%.3f,%.6g\n", experiment.c_str(),
               r.result.parameters.size(), r.errors.mean, r.errors.median, r.errors.max,
               r.result.generations, r.generations_to_target,
               static_cast<unsigned long long>(r.result.evaluations), r.result.wall_time_s,
               r.result.global_cost);
  std::fflush(g_summary);
}

mme::IdentifyOptions esOptions(const Settings& s, int generations) {
  mme::IdentifyOptions o = mme::identifyOptionsFor(s.preset);
  if (s.generations > 0) generations = s.generations;
  o.generations = s.quick ? std::max(20, generations / 20) : generations;
  if (s.refine_start >= 0) o.es.refine_start_generation = s.refine_start;
  if (s.refine_period >= 0) o.es.refine_period = s.refine_period;
  if (s.refine_evaluations >= 0) o.es.refine_max_evaluations = s.refine_evaluations;
  if (!s.refine.empty() && !mme::parseRefineAlgorithm(s.refine, &o.es.refine_algorithm))
    throw mme::InputError(std::string("--refine must be ") + mme::refineAlgorithmNames());
  o.es.threads = s.threads;
  o.es.seed = s.seed;
  return o;
}

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

/// Writes the truth and the no-values model of the 18-marker random object (issue target) for
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

/// What a user gets by default: random objects like random18 and soft objects hanging
/// under gravity (springs stretched 2.4-20x their rest length), 10 seeds each, noiseless, each
/// through a TRC file in millimetres, with a model file that gives no value and no bound for any
/// free parameter; `identify`'s default engine (Preset::kDefault, whatever --preset says).
void defaultsExperiment(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/defaults.csv",
                         "object,seed,unknowns,median_error_percent,max_error_percent,wall_s,"
                         "generations,evaluations,bound_widenings,flagged,stop");
  const int seeds = s.quick ? 2 : 10;
  const std::string trc = s.out_dir + "/defaults_tmp.trc";
  for (const std::string object : {"random18", "hanging16"}) {
    std::vector<double> worst, times;
    for (int seed = 1; seed <= seeds; ++seed) {
      Model truth;
      int frames = 0;
      if (object == "random18") {
        mme::RandomObjectSpec spec;  // 18 markers, 12 types, 40 bonds, 120 Hz
        spec.seed = 100 + seed;
        truth = mme::makeRandomObject(spec);
        frames = 120;
      } else {
        mme::HangingObjectSpec spec;  // 16 markers (2 fixed), 8 damped types, 30 bonds, 120 Hz
        spec.seed = 200 + seed;
        truth = mme::makeHangingObject(spec);
        frames = 300;
      }
      mme::writeTrc(trc, mme::simulateTrajectory(truth, frames, truth.frame_rate_hz), "mm");
      const mme::Trajectory data = mme::readTrajectoryFile(trc);
      Model blank = truth;
      for (mme::BondType& t : blank.bond_types)
        for (mme::Param& p : t.params) {
          p.has_min = p.has_max = false;
          p.min = -INFINITY;
          p.max = INFINITY;
        }
      mme::IdentifyOptions o = mme::identifyOptionsFor(mme::Preset::kDefault);
      o.es.threads = s.threads;
      o.es.seed = s.seed;
      o.estimate_std = false;
      const RunResult r = runEs(blank, data, o, nullptr);
      size_t flagged = 0;
      for (mme::ParameterFlag flag : r.result.flags) flagged += flag != mme::ParameterFlag::kNone;
      std::fprintf(f, "%s,%d,%zu,%.6g,%.6g,%.3f,%d,%llu,%d,%zu,%s\n", object.c_str(), seed,
                   r.result.parameters.size(), r.errors.median, r.errors.max, r.result.wall_time_s,
                   r.result.generations, static_cast<unsigned long long>(r.result.evaluations),
                   r.result.bound_widenings, flagged, mme::identifyStopName(r.result.stop));
      std::fflush(f);
      std::printf("defaults: %s seed %2d: %zu unknowns, median %.2e %%, max %.2e %%, %.2f s, "
                  "%d generations, %d widenings\n", object.c_str(), seed, r.result.parameters.size(),
                  r.errors.median, r.errors.max, r.result.wall_time_s, r.result.generations,
                  r.result.bound_widenings);
      worst.push_back(r.errors.max);
      times.push_back(r.result.wall_time_s);
    }
    std::printf("defaults: %s: worst max error %.2e %%, slowest %.2f s over %d seeds\n",
                object.c_str(), *std::max_element(worst.begin(), worst.end()),
                *std::max_element(times.begin(), times.end()), seeds);
  }
  std::remove(trc.c_str());
  std::fclose(f);
}

/// Accuracy under noise against the Cramer-Rao bound: paper_object, 100 frames, the
/// default engine (identify's defaults: the output-error estimator on noisy data), seeds 1..N
/// per noise level. Per run: median and max error, the bound's median and max, how many
/// parameters lie within 3 reported std, the largest std / bound ratio.
void accuracyExperiment(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/accuracy.csv",
                         "noise_std_m,seed,estimator,median_error_percent,max_error_percent,"
                         "bound_median_percent,bound_max_percent,within_3std,parameters,"
                         "max_std_over_bound,noise_estimate_m,wall_s");
  const mme::Scene scene = mme::makeScene("paper_object");
  const mme::Trajectory clean = mme::simulateTrajectory(scene.model, 100, scene.model.frame_rate_hz);
  const std::vector<double> truth = mme::getValues(scene.model, mme::freeParameters(scene.model));
  const int seeds = s.quick ? 2 : 20;
  for (double noise : {1e-5, 1e-4, 1e-3}) {
    const mme::ParameterSpace space(scene.model, clean);
    const std::vector<double> bound = mme::cramerRaoBound(scene.model, clean, space, noise);
    std::vector<double> bound_pct;
    for (size_t k = 0; k < bound.size(); ++k) bound_pct.push_back(100.0 * bound[k] / std::abs(truth[k]));
    Errors b;  // the bound's median and max [%]
    {
      std::vector<double> sorted = bound_pct;
      std::sort(sorted.begin(), sorted.end());
      const size_t m = sorted.size();
      b.median = m % 2 ? sorted[m / 2] : 0.5 * (sorted[m / 2 - 1] + sorted[m / 2]);
      b.max = sorted.back();
    }
    std::vector<double> medians, maxima;
    int within = 0, total = 0;
    double worst_ratio = 0.0;
    for (int seed = 1; seed <= seeds; ++seed) {
      mme::Trajectory data = clean;
      mme::addGaussianNoise(&data, noise, 500 + seed);
      mme::IdentifyOptions o = mme::identifyOptionsFor(mme::Preset::kDefault);
      o.es.threads = s.threads;
      o.es.seed = s.seed;
      const RunResult r = runEs(scene.model, data, o, nullptr);
      int run_within = 0;
      double ratio = 0.0;
      for (size_t k = 0; k < truth.size(); ++k) {
        const double sd = r.result.std_devs[k];
        if (std::isfinite(sd) && std::abs(r.result.values[k] - truth[k]) <= 3.0 * sd) ++run_within;
        if (std::isfinite(sd) && bound[k] > 0.0) ratio = std::max(ratio, sd / bound[k]);
      }
      within += run_within;
      total += static_cast<int>(truth.size());
      worst_ratio = std::max(worst_ratio, ratio);
      medians.push_back(r.errors.median);
      maxima.push_back(r.errors.max);
      std::fprintf(f, "%g,%d,%s,%.6g,%.6g,%.6g,%.6g,%d,%zu,%.4g,%.4g,%.3f\n", noise, seed,
                   mme::estimatorName(r.result.estimator), r.errors.median, r.errors.max, b.median, b.max,
                   run_within, truth.size(), ratio, r.result.noise_estimate_m, r.result.wall_time_s);
      std::fflush(f);
    }
    std::sort(medians.begin(), medians.end());
    std::printf("accuracy: noise %g m, %d seeds: median of median errors %.4f %% (bound median "
                "%.4f %%, ratio %.2f), worst max error %.4f %% (bound max %.4f %%); |error| <= 3 std "
                "for %d of %d parameters (%.1f %%); largest std / bound %.2f\n",
                noise, seeds, medians[medians.size() / 2], b.median,
                medians[medians.size() / 2] / b.median, *std::max_element(maxima.begin(), maxima.end()),
                b.max, within, total, 100.0 * within / total, worst_ratio);
  }
  std::fclose(f);
}

/// The online estimator against the offline identification of the same window (within
/// 2x once converged): frames fed at the data's rate, an update every 1/10 s of frames, then the
/// window stops and updates run until a refinement finished on it; identifyModel on that window.
void onlineExperiment(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/online.csv",
                         "case,markers,unknowns,window_frames,online_estimator,online_cost_m2,"
                         "identify_estimator,identify_cost_m2,ratio,online_updates,identify_wall_s");
  struct Case {
    std::string name;
    Model model;
    mme::Trajectory data;
  };
  std::vector<Case> cases;
  {
    mme::RandomObjectSpec spec;  // the big soak model: 43 markers, 91 damped types
    spec.particles = 43;
    spec.bond_types = 91;
    spec.bonds = 91;
    spec.damping_max_nspm = 0.05;
    const Model truth = mme::makeRandomObject(spec);
    mme::Trajectory data = mme::simulateTrajectory(truth, 240, truth.frame_rate_hz);
    mme::addGaussianNoise(&data, 2e-4, 17);
    cases.push_back({"random43_noise0.2mm", forgetFreeValues(truth), data});
  }
  {
    const std::string path = std::string(MME_TEST_DATA_DIR) + "/real/motion_capture_walk.trc";
    const mme::Trajectory data = mme::readTrajectoryFile(path);
    cases.push_back({"motion_capture_walk", mme::markerModel(data, 91), data});
  }
  for (const Case& c : cases) {
    mme::OnlineEstimatorOptions o;
    o.window_frames = 100;
    o.es.threads = s.threads;
    mme::OnlineEstimator online(c.model, o);
    const int n = c.data.numMarkers();
    const int per_update = std::max(1, static_cast<int>(c.data.frame_rate_hz / 10.0));
    int updates = 0;
    for (int t = 0; t < c.data.numFrames(); ++t) {
      std::vector<Eigen::Vector3d> x(c.data.positions_m.begin() + t * n, c.data.positions_m.begin() + (t + 1) * n);
      std::vector<uint8_t> occluded(c.data.occluded.begin() + t * n, c.data.occluded.begin() + (t + 1) * n);
      online.addFrame(c.data.times_s[t], x, occluded);
      if ((t + 1) % per_update == 0 && online.update()) ++updates;
    }
    // The window stands still: refinements and output-error fits (each at most ~refine_max_s,
    // warm from the last) go on until the estimate's cost stops falling (1 % over 3 rounds).
    std::vector<double> costs;
    for (int k = 0; k < 30; ++k) {
      online.waitForRefinement();
      if (online.update()) ++updates;
      costs.push_back(online.estimate().global_cost);
      const size_t m = costs.size();
      if (m > 4 && costs[m - 4] - costs[m - 1] <= 0.01 * costs[m - 4]) break;
    }
    online.waitForRefinement();
    if (online.update()) ++updates;
    const mme::Estimate e = online.estimate();
    const mme::Trajectory window = online.window();
    mme::IdentifyOptions io = mme::identifyOptionsFor(mme::Preset::kDefault);
    io.es.threads = s.threads;
    io.estimate_std = false;
    Model model = c.model;
    if (!(model.frame_rate_hz > 0)) model.frame_rate_hz = window.frame_rate_hz;
    const mme::IdentifyResult r = mme::identifyModel(model, window, io);
    const double ratio = e.global_cost / r.global_cost;
    std::fprintf(f, "%s,%d,%zu,%d,%s,%.6g,%s,%.6g,%.4g,%d,%.2f\n", c.name.c_str(), n,
                 r.parameters.size(), window.numFrames(), mme::estimatorName(e.estimator), e.global_cost,
                 mme::estimatorName(r.estimator), r.global_cost, ratio, updates, r.wall_time_s);
    std::fflush(f);
    std::printf("online: %s (%d markers, %zu unknowns): online %s cost %.4g m^2, identify %s cost "
                "%.4g m^2 on the same %d frames: ratio %.3g (%d updates)\n", c.name.c_str(), n,
                r.parameters.size(), mme::estimatorName(e.estimator), e.global_cost, mme::estimatorName(r.estimator),
                r.global_cost, window.numFrames(), ratio, updates);
  }
  std::fclose(f);
}

/// Structure selection as the benchmarks run it: the default engine, no std.
mme::StructureOptions structureOptions(const Settings& s) {
  mme::StructureOptions so;
  so.identify = mme::identifyOptionsFor(mme::Preset::kDefault);
  so.identify.es.threads = s.threads;
  so.identify.estimate_std = false;
  return so;
}

/// Structure selection: random objects of known structure (15-25 markers, springs
/// only, springs + dampers, hardening springs; bent chains with flexion; noiseless, 10 seeds
/// each), a 40-marker object for the time, and the real recordings (held-out frames as the judge).
void structureExperiment(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/structure.csv",
                         "case,seed,markers,true_bonds,true_types,candidate_bonds,bonds,types,"
                         "f1,components_exact,types_within_10pct,max_error_percent,wall_s");
  const int seeds = s.quick ? 1 : 10;
  mme::StructureOptions so = structureOptions(s);
  if (std::getenv("MME_STRUCTURE_VERBOSE"))
    so.progress = [](const std::string& line) { std::printf("  %s\n", line.c_str()); };
  const auto run = [&](const std::string& name, int seed, const Model& truth, int frames,
                       double noise_m) {
    mme::Trajectory data = mme::simulateTrajectory(truth, frames, truth.frame_rate_hz);
    if (noise_m > 0.0) mme::addGaussianNoise(&data, noise_m, 1000 + seed);
    Model particles = truth;
    particles.bonds.clear();
    particles.bond_types.clear();
    const auto start = std::chrono::steady_clock::now();
    const mme::StructureResult r = mme::selectStructure(particles, data, so);
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const mme::StructureScore sc = mme::scoreStructure(truth, r.model);
    // The components: dampers, cubic terms, flexion and drags exactly where the truth has them.
    const mme::StructureScore self = mme::scoreStructure(truth, truth);
    const bool exact = (self.damped_everywhere ? sc.damped_everywhere : sc.damped_nowhere) &&
                       (self.cubic_everywhere ? sc.cubic_everywhere : sc.cubic_nowhere) &&
                       sc.flexion_f1 == 1.0 && sc.viscosity_bonds == self.viscosity_bonds;
    const int true_types = static_cast<int>(truth.bond_types.size());
    const bool types_ok = std::abs(sc.types - true_types) <= 0.1 * true_types;
    std::fprintf(f, "%s,%d,%zu,%zu,%d,%d,%zu,%d,%.4f,%d,%d,%.6g,%.3f\n", name.c_str(), seed,
                 truth.particles.size(), truth.bonds.size(), true_types, r.candidate_bonds,
                 r.model.bonds.size(), sc.types, sc.f1, exact ? 1 : 0, types_ok ? 1 : 0,
                 100.0 * sc.max_relative_error, wall_s);
    std::fflush(f);
    std::printf("structure: %s seed %2d: %zu markers, %d candidates -> %zu bonds (truth %zu), %d "
                "types (truth %d), F1 %.3f, components %s, max error %.2e %%, %.2f s\n",
                name.c_str(), seed, truth.particles.size(), r.candidate_bonds, r.model.bonds.size(),
                truth.bonds.size(), sc.types, true_types, sc.f1, exact ? "exact" : "WRONG",
                100.0 * sc.max_relative_error, wall_s);
  };
  for (const bool damped : {false, true})
    for (int seed = 1; seed <= seeds; ++seed) {
      mme::RandomObjectSpec spec;
      spec.particles = 15 + (7 * seed) % 11;  // 15..25
      spec.bond_types = 8;
      spec.bonds = 2 * spec.particles;
      spec.damping_max_nspm = damped ? 0.5 : 0.0;
      spec.seed = 300 + seed;
      run(damped ? "springs_dampers" : "springs", seed, mme::makeRandomObject(spec), 240, 0.0);
    }
  // Bent chains with flexion (3-5 chains of 4-6 particles, half of them damped) and hardening
  // springs (cubic terms worth 5-10 % of the tension at 10 % strain).
  for (int seed = 1; seed <= seeds; ++seed) {
    mme::ChainObjectSpec spec;
    spec.chains = 3 + seed % 3;
    spec.links = 4 + (seed / 3) % 3;
    spec.damping_max_nspm = seed % 2 ? 0.0 : 0.5;
    spec.seed = 500 + seed;
    run("chains_flexion", seed, mme::makeChainObject(spec), 240, 0.0);
  }
  for (int seed = 1; seed <= seeds; ++seed) {
    mme::RandomObjectSpec spec;
    spec.particles = 15 + (7 * seed) % 11;
    spec.bond_types = 6;
    spec.bonds = 2 * spec.particles;
    spec.stiffness_nl_scale = 10.0;
    spec.seed = 600 + seed;
    run("springs_cubic", seed, mme::makeRandomObject(spec), 240, 0.0);
  }
  // Not a target yet: the same springs-only objects with 10 um of marker noise, 600 frames.
  for (int seed = 1; seed <= (s.quick ? 0 : 5); ++seed) {
    mme::RandomObjectSpec spec;
    spec.particles = 15 + (7 * seed) % 11;
    spec.bond_types = 8;
    spec.bonds = 2 * spec.particles;
    spec.seed = 300 + seed;
    run("springs_noise_10um", seed, mme::makeRandomObject(spec), 600, 1e-5);
  }
  {
    mme::RandomObjectSpec spec;
    spec.particles = 40;
    spec.bond_types = 12;
    spec.bonds = 90;
    spec.seed = 400;
    run("springs_40_markers", 1, mme::makeRandomObject(spec), 240, 0.0);
  }
  std::fclose(f);
}

/// Structure selection on the real recordings (their first 300 frames): no truth; the held-out
/// frames judge. Part of `--only structure`; alone as `--only structure_real`.
void structureRealExperiment(const Settings& s) {
  mme::StructureOptions so = structureOptions(s);
  std::FILE* g = openCsv(s.out_dir + "/structure_real.csv",
                         "file,markers,frames,candidate_bonds,full_candidate_parameters,chosen,"
                         "bonds,types,parameters,model_rms_10_m,constant_velocity_rms_10_m,"
                         "constant_acceleration_rms_10_m,gravity_only_rms_10_m,bounded,wall_s");
  for (const char* file : {"motion_capture_walk.trc", "subject01_walk1.trc", "arm26_elbow_flex.trc",
                           "Sample01_Eb015pi.c3d", "Sample02_pc_int.c3d",
                           "Sample26_Walking_Hybrid_1_1.c3d"}) {
    if (s.quick && std::string(file) != "arm26_elbow_flex.trc") continue;
    const std::string path = std::string(MME_TEST_DATA_DIR) + "/real/" + file;
    mme::Trajectory data = mme::readTrajectoryFile(path);
    data = mme::sliceFrames(data, 0, std::min(data.numFrames(), 300));
    Model particles = mme::markerModel(data);
    const auto start = std::chrono::steady_clock::now();
    try {
      const mme::StructureResult r = mme::selectStructure(particles, data, so);
      const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const mme::StructureCandidate* chosen = nullptr;
      for (const mme::StructureCandidate& c : r.candidates)
        if (c.chosen) chosen = &c;
      const int full_params = 3 * r.candidate_bonds + 3;
      std::fprintf(g, "%s,%d,%d,%d,%d,%s,%d,%d,%d,%.6g,%.6g,%.6g,%.6g,%d,%.2f\n", file,
                   data.numMarkers(), data.numFrames(), r.candidate_bonds, full_params,
                   chosen->name.c_str(), chosen->bonds, chosen->bond_types, chosen->parameters,
                   chosen->held_out_rms_m[2], r.guess_rms_m[0][2], r.guess_rms_m[1][2],
                   r.guess_rms_m[2][2], chosen->rollout_bounded ? 1 : 0, wall_s);
      std::fflush(g);
      std::printf("structure: %s: %s, %d bonds, %d types, %d parameters (full candidate model %d); "
                  "10 frames ahead on held-out frames: model %.2f mm, constant velocity %.2f mm, "
                  "constant acceleration %.2f mm; %.1f s\n", file, chosen->name.c_str(),
                  chosen->bonds, chosen->bond_types, chosen->parameters, full_params,
                  1e3 * chosen->held_out_rms_m[2], 1e3 * r.guess_rms_m[0][2],
                  1e3 * r.guess_rms_m[1][2], wall_s);
    } catch (const mme::InputError& e) {
      std::printf("structure: %s: %s\n", file, e.what());
    }
  }
  std::fclose(g);
}

/// The walker's first 50 noiseless frames and its muscle-free parameters (docs/scenes.md).
struct WalkerCase {
  mme::Scene scene = mme::makeScene("walker");
  int frames = 50;
  mme::Trajectory data = mme::simulateTrajectory(scene.model, frames, scene.model.frame_rate_hz);
  std::vector<mme::ParamRef> refs = mme::freeParameters(scene.model);
  std::vector<double> truth = mme::getValues(scene.model, refs);

  /// The true values off by +-`off` (relative). signs_seed 0: alternate signs (- on even
  /// indices); otherwise each sign drawn from std::mt19937(signs_seed).
  std::vector<double> off(double off, unsigned signs_seed = 0) const {
    std::vector<double> v = truth;
    std::mt19937 rng(signs_seed);
    for (size_t k = 0; k < v.size(); ++k) {
      const bool up = signs_seed == 0 ? k % 2 == 1 : (rng() & 1u) == 1u;
      v[k] *= up ? 1.0 + off : 1.0 - off;
    }
    return v;
  }
};

/// How close an answer on the walker is (docs/scenes.md): the parameters within 1 % of the
/// truth, the median and worst relative errors (and the worst's name), and the open loop's RMS
/// distance from the data at the last frame.
struct WalkerScore {
  int within_1pct = 0;
  double median_error = 0.0, worst_error = 0.0, open_loop_rms_m = 0.0;
  std::string worst_name;
};

WalkerScore scoreWalker(const Model& truth_model, const mme::Trajectory& data,
                        const std::vector<double>& values) {
  const std::vector<mme::ParamRef> refs = mme::freeParameters(truth_model);
  const std::vector<double> truth = mme::getValues(truth_model, refs);
  WalkerScore score;
  std::vector<double> errors;
  for (size_t k = 0; k < truth.size(); ++k) errors.push_back(std::fabs(values[k] / truth[k] - 1.0));
  score.within_1pct = static_cast<int>(
      std::count_if(errors.begin(), errors.end(), [](double e) { return e < 0.01; }));
  const size_t worst = static_cast<size_t>(std::max_element(errors.begin(), errors.end()) - errors.begin());
  score.worst_error = errors[worst];
  score.worst_name = refs[worst].name;
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  score.median_error = errors[errors.size() / 2];
  Model fitted = truth_model;
  mme::setValues(fitted, refs, values);
  const int frames = data.numFrames();
  const mme::Trajectory open_loop = mme::simulateTrajectory(fitted, frames, fitted.frame_rate_hz);
  double sum2 = 0.0;
  for (int i = 0; i < data.numMarkers(); ++i)
    sum2 += (open_loop.position(frames - 1, i) - data.position(frames - 1, i)).squaredNorm();
  score.open_loop_rms_m = std::sqrt(sum2 / (3.0 * data.numMarkers()));
  return score;
}

/// The output error alone on the walker (the walker's identification targets): 50 noiseless frames,
/// 10-frame segments, its 40 muscle-free parameters started at the truth and 1 % off (alternate
/// signs), the default options (start states fitted by the model, soft then hard continuity) at
/// most 100 iterations per stage, for comparison 1 % off with hard continuity only, and 1 % off
/// with signs drawn at random (seeds 1 and 2: how much the answer depends on the start), and
/// the three 1 % starts again growing the data (OutputErrorOptions::grow_segments 1: the first
/// segment's frames, then 2, 4, then all). Every
/// parameter's error beside its Cramer-Rao bound at 0.1 mm marker noise (what the 50 frames can
/// tell about it) goes to walker_oe_params.csv. Opt-in (`--only walker_oe`, ~40 minutes): the
/// "Identifying the walker" figures of docs/scenes.md.
void walkerOutputError(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/walker_oe.csv",
                         "start_off,signs,continuity,segment_frames,grow_segments,iterations,"
                         "termination,wall_s,"
                         "start_cost_m2,cost_m2,within_1pct,median_error,worst_error,open_loop_1s_rms_m");
  const WalkerCase walker;
  const mme::Scene& scene = walker.scene;
  const mme::Trajectory& data = walker.data;
  const std::vector<mme::ParamRef>& refs = walker.refs;
  const std::vector<double>& truth = walker.truth;
  const mme::ParameterSpace space(scene.model, data);
  struct Run {
    double off;
    bool soft_first;
    unsigned signs_seed;  // 0: alternate signs
    int grow_segments;    // OutputErrorOptions::grow_segments (0: every frame at once)
  };
  std::vector<std::vector<double>> answers;
  size_t growing = 0;  // the answer from 1 % off (alternate signs) growing the data
  for (const Run run : {Run{0.0, true, 0, 0}, Run{0.01, true, 0, 0}, Run{0.01, false, 0, 0},
                        Run{0.01, true, 1, 0}, Run{0.01, true, 2, 0}, Run{0.01, true, 0, 1},
                        Run{0.01, true, 1, 1}, Run{0.01, true, 2, 1}}) {
    if (s.quick && run.signs_seed != 0) continue;
    const std::vector<double> start = walker.off(run.off, run.signs_seed);
    mme::OutputErrorOptions o;
    o.segment_frames = 10;
    o.max_iterations = s.quick ? 3 : 100;
    o.threads = s.threads;
    o.estimate_std = false;
    o.noise_std_m = 1e-4;  // a weight only: the data are noiseless
    if (!run.soft_first) o.first_continuity_weight = 0.0;
    o.grow_segments = run.grow_segments;
    const mme::OutputErrorResult r =
        mme::estimateOutputError(scene.model, data, space, space.toSearch(start), o);
    answers.push_back(r.values);
    if (run.off > 0.0 && run.soft_first && run.signs_seed == 0 && run.grow_segments > 0)
      growing = answers.size() - 1;
    const WalkerScore score = scoreWalker(scene.model, data, r.values);
    const char* continuity = run.soft_first ? "soft_then_hard" : "hard";
    const std::string signs =
        run.signs_seed == 0 ? "alternate" : "random_seed_" + std::to_string(run.signs_seed);
    std::fprintf(f, "%g,%s,%s,%d,%d,%d,%s,%.2f,%.6g,%.6g,%d,%.6g,%.6g,%.6g\n", run.off,
                 signs.c_str(), continuity, o.segment_frames, run.grow_segments, r.iterations,
                 r.converged ? "converged" : "limit", r.wall_time_s, r.start_cost_m2,
                 r.observation_cost_m2, score.within_1pct, score.median_error, score.worst_error,
                 score.open_loop_rms_m);
    std::fflush(f);
    std::printf("walker_oe: from %g %% off (%s signs), %s continuity, %d-frame segments, "
                "growing from %d segment(s) (0: all at once): %d "
                "iterations (%s), %.1f s; cost %.4g -> %.4g m^2; %d of %zu parameters within 1 %%, "
                "median %.3g %%, worst %.3g %% (%s); open loop after 1 s %.3g m RMS\n",
                100.0 * run.off, signs.c_str(), continuity, o.segment_frames, run.grow_segments,
                r.iterations,
                r.termination.c_str(), r.wall_time_s, r.start_cost_m2, r.observation_cost_m2,
                score.within_1pct, truth.size(), 100.0 * score.median_error,
                100.0 * score.worst_error, score.worst_name.c_str(), score.open_loop_rms_m);
    std::fflush(stdout);
  }
  std::fclose(f);
  // What 50 frames can tell about each parameter: its Cramer-Rao bound at 0.1 mm noise.
  const std::vector<double> bound = mme::cramerRaoBound(scene.model, data, space, 1e-4);
  std::FILE* g = openCsv(s.out_dir + "/walker_oe_params.csv",
                         "parameter,true_value,error_from_truth_percent,error_from_1pct_percent,"
                         "error_hard_only_percent,error_from_1pct_growing_percent,"
                         "cramer_rao_0.1mm_percent");
  for (size_t k = 0; k < truth.size(); ++k) {
    std::fprintf(g, "%s,%.9g", refs[k].name.c_str(), truth[k]);
    for (size_t a : {size_t{0}, size_t{1}, size_t{2}, growing})
      std::fprintf(g, ",%.6g", 100.0 * (answers[a][k] / truth[k] - 1.0));
    std::fprintf(g, ",%.6g\n", 100.0 * bound[k] / std::fabs(truth[k]));
  }
  std::fclose(g);
  std::printf("walker_oe: per-parameter errors and Cramer-Rao bounds in %s/walker_oe_params.csv\n",
              s.out_dir.c_str());
}

/// What a user gets without flags on the walker: identifyModel with the default preset (the
/// evolution strategy, then the output error) from initial guesses 1 % off (alternate signs),
/// 50 noiseless frames, 100 generations, a 500-s limit. Opt-in (`--only walker_identify`, ~5 min).
void walkerIdentify(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/walker_identify.csv",
                         "frames,generations,estimator,wall_s,within_1pct,median_error,worst_error,"
                         "worst_parameter,open_loop_1s_rms_m");
  const WalkerCase walker;
  Model start = walker.scene.model;
  mme::setValues(start, walker.refs, walker.off(0.01));
  mme::IdentifyOptions o = mme::identifyOptionsFor(s.preset);
  o.generations = s.quick ? 3 : 100;
  o.max_wall_time_s = s.quick ? 60.0 : 500.0;
  o.es.threads = s.threads;
  o.estimate_std = false;
  const auto began = std::chrono::steady_clock::now();
  const mme::IdentifyResult r = mme::identifyModel(start, walker.data, o);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  const WalkerScore score = scoreWalker(walker.scene.model, walker.data, r.values);
  std::fprintf(f, "%d,%d,%s,%.1f,%d,%.6g,%.6g,%s,%.6g\n", walker.frames, o.generations, mme::estimatorName(r.estimator),
               wall_s, score.within_1pct, score.median_error, score.worst_error, score.worst_name.c_str(),
               score.open_loop_rms_m);
  std::fclose(f);
  std::printf("walker_identify: %s, %.0f s: %d of %zu parameters within 1 %%, median %.3g %%, worst "
              "%.3g %% (%s); open loop after 1 s %.3g m RMS\n", mme::estimatorName(r.estimator), wall_s,
              score.within_1pct, walker.refs.size(), 100.0 * score.median_error, 100.0 * score.worst_error,
              score.worst_name.c_str(), score.open_loop_rms_m);
}

/// The model with every spring type's damping taken away (`free_damping` false) or made free
/// (true), values forgotten: the paper's "without muscles" and "with dampers" models.
Model dampingVariant(Model m, bool free_damping) {
  for (mme::BondType& type : m.bond_types) {
    if (type.kind != mme::BondKind::kSpring) continue;
    mme::Param& c = type.param(mme::kDamping);
    c = mme::Param{};
    if (free_damping) c.present = c.free = true;
  }
  return forgetFreeValues(m);
}

/// Fig. 5 of the paper (section 4.4): log cost against generations for the same bonds without
/// muscles (springs), with dampers, and with muscles, on the walker (its own known controllers,
/// the muscle-free parameters from the priors) and on the real recordings (structure chosen from
/// the markers first; every spring type a muscle reading its two nearest bonds, started from the
/// dampers' fit: activation 0). Each fit runs on the window's first
/// 80 % and is judged on the rest: the 10-frame open-loop prediction error beside the model-free
/// guesses. One cost for all (the paper's one-step cost), the whole generation budget each.
void figure5(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/fig5.csv",
                         "case,variant,generation,chart_generation,evaluations,log10_cost,wall_s");
  std::FILE* g = openCsv(s.out_dir + "/fig5_summary.csv",
                         "case,variant,parameters,fitted_frames,held_out_frames,cost_m2,"
                         "model_rms_10_m,constant_velocity_rms_10_m,constant_acceleration_rms_10_m,"
                         "gravity_only_rms_10_m,bounded,wall_s");
  const int generations = s.generations > 0 ? s.generations : (s.quick ? 10 : 100);
  struct Case {
    std::string name;
    Model structure;  // the passive bonds, values known where the case has them
    mme::Trajectory data;
  };
  std::vector<Case> cases;
  if (s.wantsFig5Case("walker")) {
    // The walking walker (80 substeps: its cost is ~100x a 1-substep scene's per frame): its
    // first 2 s (100 frames, about one and a half strides), 80 fitted, 20 held out.
    const mme::Scene walker = mme::makeScene("walker");
    cases.push_back({"walker", walker.model,
                     mme::simulateTrajectory(walker.model, std::min(walker.default_frames, 100),
                                             walker.model.frame_rate_hz)});
  }
  mme::StructureOptions so = structureOptions(s);
  for (const char* file : {"motion_capture_walk.trc", "subject01_walk1.trc", "arm26_elbow_flex.trc",
                           "Sample01_Eb015pi.c3d", "Sample02_dec_real.c3d", "Sample02_pc_int.c3d",
                           "Sample26_Walking_Hybrid_1_1.c3d"}) {
    if (s.quick && std::string(file) != "arm26_elbow_flex.trc") continue;
    if (!s.wantsFig5Case(file)) continue;
    mme::Trajectory data = mme::readTrajectoryFile(std::string(MME_TEST_DATA_DIR) + "/real/" + file);
    data = mme::sliceFrames(data, 0, std::min(data.numFrames(), 300));
    const mme::StructureResult r = mme::selectStructure(mme::markerModel(data), data, so);
    cases.push_back({file, r.model, data});
  }
  for (Case& c : cases) {
    // The split structure selection judges on (its default share: the last 20 %).
    const mme::HeldOutSplit split =
        mme::splitHeldOut(c.data, mme::StructureOptions().held_out_share, "fig5 " + c.name);
    const int fit_frames = split.fit_frames, held_frames = split.held_frames;
    const mme::Trajectory& fit = split.fit;
    const mme::Trajectory& held = split.held;
    mme::IdentifyOptions o = mme::identifyOptionsFor(s.preset);
    o.generations = generations;
    o.patience_generations = 0;  // every curve the whole budget long
    o.es.threads = s.threads;
    o.es.seed = s.seed;
    o.estimate_std = false;
    o.cost = mme::CostChoice::kShortTerm;  // the paper's cost, one scale for the three curves
    Model dampers_fit;
    int dampers_generations = 0;
    for (const char* variant : {"springs", "dampers", "muscles", "sensor_muscles"}) {
      const std::string v = variant;
      // A case whose truth has muscles (a walking walker) gets its own controllers, from the
      // priors; the others get muscles placed on the dampers' fit (muscle_placement.h), and
      // sensor muscles fitted on it by least squares (sensor_muscles.h; no search, no curve).
      const bool own_muscles = mme::muscleTypeCount(c.structure) > 0;
      Model fitted;
      size_t parameters = 0;
      double cost_m2 = NAN, wall_s = 0.0;
      int generations_run = 0;
      if (v == "sensor_muscles") {
        if (own_muscles) continue;
        mme::SensorMuscleOptions sm;
        sm.progress = [&c](const std::string& line) {
          std::printf("fig5: %s: %s\n", c.name.c_str(), line.c_str());
          std::fflush(stdout);
        };
        const auto began = std::chrono::steady_clock::now();
        const mme::SensorMuscleResult sr = mme::addSensorMuscles(dampers_fit, fit, sm);
        wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
        std::printf("fig5: %s: sensor muscles chosen: ridge %.0e, %d rollout round(s), activation "
                    "time constant %g s, %s anchors%s (the body travels %.2f body sizes)%s\n",
                    c.name.c_str(), sr.ridge, sr.candidates[sr.chosen].rollout_rounds,
                    sr.activation_time_s, sr.anchors ? "with" : "without",
                    !sr.anchors ? "" : sr.anchor_stiffness ? " with a stiffness of their own"
                                                           : " without a stiffness of their own",
                    sr.body_travel, sr.better_than_passive ? "" : " (not better than the passive model)");
        fitted = sr.model;
        parameters = mme::freeParameters(dampers_fit).size() + sr.unknowns;
        cost_m2 = sr.residual_rms_m * sr.residual_rms_m;
      } else {
        Model start;
        if (v != "muscles") {
          start = dampingVariant(mme::removeMuscles(c.structure), v == "dampers");
        } else if (own_muscles) {
          start = forgetFreeValues(c.structure);
        } else {
          start = mme::addMuscles(dampers_fit, &fit, mme::MusclePlacement{});
          if (mme::muscleTypeCount(start) == 0) {
            std::printf("fig5: %s: no spring type to turn into a muscle (the chosen structure has "
                        "none)\n", c.name.c_str());
            continue;
          }
        }
        const int offset = v == "muscles" && !own_muscles ? dampers_generations : 0;
        auto log = [&](const mme::Progress& p) {
          if (!p.message.empty()) return;
          // Placed muscles continue from the dampers' fit: on the chart, after its generations.
          const int chart = p.generation + offset;
          std::fprintf(f, "%s,%s,%d,%d,%llu,%.6f,%.3f\n", c.name.c_str(), variant, p.generation,
                       chart, static_cast<unsigned long long>(p.evaluations),
                       std::log10(std::max(p.best_cost, 1e-300)), p.wall_time_s);
        };
        const mme::IdentifyResult r = mme::identifyModel(start, fit, o, log);
        std::fflush(f);
        fitted = start;
        mme::setValues(fitted, r.parameters, r.values);
        if (v == "dampers") {
          dampers_fit = fitted;
          dampers_generations = r.generations;
        }
        parameters = r.parameters.size();
        cost_m2 = r.global_cost;
        wall_s = r.wall_time_s;
        generations_run = r.generations;
      }
      double rms[4] = {NAN, NAN, NAN, NAN};
      bool bounded = false;
      try {
        // The sensor muscles' anchors are fixed particles without markers: left unseen.
        std::vector<std::string> names;
        for (const mme::Particle& p : fitted.particles) names.push_back(p.name);
        const mme::PredictionReport pr = mme::evaluatePredictions(
            fitted, mme::remapMarkers(held, names, nullptr), {10}, 10.0, split.held_start);
        for (const mme::PredictionError& row : pr.rows) rms[static_cast<int>(row.predictor)] = row.rms_m;
        bounded = pr.rollout_bounded;
      } catch (const mme::InputError& e) {
        std::printf("fig5: %s %s: %s\n", c.name.c_str(), variant, e.what());
      }
      std::fprintf(g, "%s,%s,%zu,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%.2f\n", c.name.c_str(), variant,
                   parameters, fit_frames, held_frames, cost_m2, rms[0], rms[1],
                   rms[2], rms[3], bounded ? 1 : 0, wall_s);
      std::fflush(g);
      std::printf("fig5: %s %s: %zu parameters, cost %.4g m^2 after %d generations; 10 frames "
                  "ahead on held-out frames: model %.2f mm, constant velocity %.2f mm, constant "
                  "acceleration %.2f mm, gravity only %.2f mm; rollout %s; %.1f s\n",
                  c.name.c_str(), variant, parameters, cost_m2, generations_run,
                  1e3 * rms[0], 1e3 * rms[1], 1e3 * rms[2], 1e3 * rms[3],
                  bounded ? "bounded" : "UNBOUNDED", wall_s);
    }
  }
  std::fclose(f);
  std::fclose(g);
}

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
      else {
        std::fprintf(stderr, "usage: bench_paper [--quick] [--out-dir DIR] [--threads T] "
                             "[--only fig1,table1,table2,scaling,random18,defaults,accuracy,\n"
                             "        online,structure,structure_real,fig5,walker_oe,walker_identify]\n"
                             "       [--generations N] [--refine-start G] [--refine-period G]\n"
                             "       [--refine-evaluations E] [--refine ALGORITHM] [--seed S]\n"
                             "       [--fig5-cases walker,Sample01_Eb015pi.c3d,...] (default: all)\n"
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
    if (!s.only.empty() && s.wants("walker_oe")) walkerOutputError(s);  // opt-in only
    if (!s.only.empty() && s.wants("walker_identify")) walkerIdentify(s);  // opt-in only
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

// Fig. 5 of the paper (`--only fig5`): log cost against generations without muscles, with
// dampers, with muscles and with sensor muscles, on the walker and the real recordings, each
// fit judged on its held-out frames (fig5.csv, fig5_summary.csv). The structure, the muscles'
// placement, the searches, the sensor muscles and the judge are the offline pipeline's named
// steps (pipeline/identify_pipeline.h); the variants around them are the figure's.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common.h"
#include "experiments.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/muscles/muscle_placement.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "motion_model_estimation/pipeline/identify_pipeline.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace paper {
namespace {

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

/// One case of the figure: a recording (or the walker's simulation) and its passive bonds.
struct Fig5Case {
  std::string name;
  Model structure;  // the passive bonds, values known where the case has them
  mme::Trajectory data;
};

/// The open output files: fig5.csv (the curves) and fig5_summary.csv (one line per fit).
struct Fig5Files {
  std::FILE* curves;
  std::FILE* summary;
};

/// One fitted variant of a case: the model and what its fit cost.
struct VariantFit {
  Model fitted;
  size_t parameters = 0;
  double cost_m2 = NAN, wall_s = 0.0;
  int generations_run = 0;
};

/// What the variants of one case hand on: the dampers' fit, from which muscles are placed (and
/// after whose generations their curve continues on the chart).
struct DampersFit {
  Model model;
  int generations = 0;
};

/// The split every variant of a case is fitted and judged on (structure selection's default
/// share: the last 20 % held out).
mme::HeldOutSplit fig5Split(const mme::Trajectory& data, const std::string& name) {
  return mme::splitHeldOut(data, mme::StructureOptions().held_out_share, "fig5 " + name);
}

/// The cases --fig5-cases selects: the walking walker, then the real recordings with the
/// structure chosen from their markers.
std::vector<Fig5Case> fig5Cases(const Settings& s) {
  std::vector<Fig5Case> cases;
  if (s.wantsFig5Case("walker")) {
    // The walking walker (80 substeps: its cost is ~100x a 1-substep scene's per frame): its
    // first 2 s (100 frames, about one and a half strides), 80 fitted, 20 held out.
    const mme::Scene walker = mme::makeScene("walker");
    cases.push_back({"walker", walker.model,
                     mme::simulateTrajectory(walker.model, std::min(walker.default_frames, 100),
                                             walker.model.frame_rate_hz)});
  }
  const mme::PipelineOptions so = structureStep(s);
  for (const char* file : {"motion_capture_walk.trc", "subject01_walk1.trc", "arm26_elbow_flex.trc",
                           "Sample01_Eb015pi.c3d", "Sample02_dec_real.c3d", "Sample02_pc_int.c3d",
                           "Sample26_Walking_Hybrid_1_1.c3d"}) {
    if (s.quick && std::string(file) != "arm26_elbow_flex.trc") continue;
    if (!s.wantsFig5Case(file)) continue;
    mme::Trajectory data = mme::readTrajectoryFile(std::string(MME_TEST_DATA_DIR) + "/real/" + file);
    data = mme::sliceFrames(data, 0, std::min(data.numFrames(), 300));
    // Chosen on the fitted frames only: the held-out frames every variant is judged on ranked
    // no level.
    const mme::StructureResult r = selectStructureOnFitted(fig5Split(data, file), so);
    cases.push_back({file, r.model, data});
  }
  return cases;
}

/// The search's options: the preset with the whole budget, one cost for the three curves.
mme::IdentifyOptions fig5Options(const Settings& s, int generations) {
  mme::IdentifyOptions o = mme::identifyOptionsFor(s.preset);
  o.generations = generations;
  o.patience_generations = 0;  // every curve the whole budget long
  o.es.threads = s.threads;
  o.es.seed = s.seed;
  o.estimate_std = false;
  o.cost = mme::CostChoice::kShortTerm;  // the paper's cost, one scale for the three curves
  return o;
}

/// Sensor muscles fitted on the dampers' fit by least squares (the pipeline's sensor-muscle step;
/// no search, no curve). False when the data cannot feed them (said, and the variant skipped).
bool fitSensorMuscles(const Fig5Case& c, const Model& dampers_fit, const mme::Trajectory& fit,
                      VariantFit* out) {
  mme::PipelineOptions p;
  p.sensor_muscles = mme::SensorMuscleOptions{};
  p.say = [&c](const std::string& line) {
    std::printf("fig5: %s: %s\n", c.name.c_str(), line.c_str());
    std::fflush(stdout);
  };
  p.warn = p.say;
  mme::PipelineResult step;  // the step fits on the identified model: the dampers' fit
  step.identified.model = dampers_fit;
  step.model = dampers_fit;
  const auto began = std::chrono::steady_clock::now();
  mme::fitSensorMuscleStep(fit, p, &step);
  out->wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  if (!step.sensor_muscles) return false;
  const mme::SensorMuscleResult& sr = *step.sensor_muscles;
  if (sr.skipped || sr.chosen < 0)
    std::printf("fig5: %s: no sensor muscles: %s\n", c.name.c_str(), sr.not_kept_because.c_str());
  else
    std::printf("fig5: %s: sensor muscles chosen: ridge %.0e, %d rollout round(s), activation "
                "time constant %g s, %s anchors%s (the body travels %.2f body sizes)%s\n",
                c.name.c_str(), sr.ridge, sr.candidates[sr.chosen].rollout_rounds,
                sr.activation_time_s, sr.anchors ? "with" : "without",
                !sr.anchors ? "" : sr.anchor_stiffness ? " with a stiffness of their own"
                                                       : " without a stiffness of their own",
                sr.body_travel, sr.better_than_passive ? "" : " (not better than the passive model)");
  out->fitted = sr.model;  // judged even when not better than the passive model
  out->parameters = mme::freeParameters(dampers_fit).size() + sr.unknowns;
  out->cost_m2 = sr.residual_rms_m * sr.residual_rms_m;
  return true;
}

/// The start of a searched variant: springs or dampers from the structure, the case's own
/// muscles (values forgotten), or muscles placed on the dampers' fit. False when the chosen
/// structure has no spring type to turn into a muscle (said, and the variant skipped).
bool variantStart(const Fig5Case& c, const std::string& v, bool own_muscles, const Model& dampers_fit,
                  const mme::Trajectory& fit, Model* start) {
  if (v != "muscles") {
    *start = dampingVariant(mme::removeMuscles(c.structure), v == "dampers");
  } else if (own_muscles) {
    *start = forgetFreeValues(c.structure);
  } else {
    try {
      *start = mme::placeMuscles(dampers_fit, fit, mme::MusclePlacement{});
    } catch (const mme::InputError&) {
      std::printf("fig5: %s: no spring type to turn into a muscle (the chosen structure has "
                  "none)\n", c.name.c_str());
      return false;
    }
  }
  return true;
}

/// The search from `start`, its curve into fig5.csv (placed muscles after the dampers'
/// generations on the chart).
VariantFit searchVariant(const Fig5Case& c, const char* variant, const Model& start, int chart_offset,
                         const mme::Trajectory& fit, const mme::IdentifyOptions& o, std::FILE* f) {
  auto log = [&](const mme::Progress& p) {
    if (!p.message.empty()) return;
    // Placed muscles continue from the dampers' fit: on the chart, after its generations.
    const int chart = p.generation + chart_offset;
    std::fprintf(f, "%s,%s,%d,%d,%llu,%.6f,%.3f\n", c.name.c_str(), variant, p.generation,
                 chart, static_cast<unsigned long long>(p.evaluations),
                 std::log10(std::max(p.best_cost, 1e-300)), p.wall_time_s);
  };
  const mme::IdentifyResult r = mme::identifyPassive(start, fit, identifyStep(o, log));
  std::fflush(f);
  VariantFit out;
  out.fitted = start;
  mme::setValues(out.fitted, r.parameters, r.values);
  out.parameters = r.parameters.size();
  out.cost_m2 = r.global_cost;
  out.wall_s = r.wall_time_s;
  out.generations_run = r.generations;
  return out;
}

/// The fitted model on the held-out frames: the 10-frame open-loop prediction error of the model
/// and the model-free guesses (rms, by predictor), and whether its rollout stays bounded.
bool judgeHeldOut(const Fig5Case& c, const char* variant, const Model& fitted,
                  const mme::HeldOutSplit& split, double rms[4]) {
  bool bounded = false;
  try {
    // The sensor muscles' anchors are fixed particles without markers: left unseen.
    const mme::PredictionReport pr = mme::judgePredictions(fitted, split.held, split.held_start);
    for (const mme::PredictionError& row : pr.rows) rms[static_cast<int>(row.predictor)] = row.rms_m;
    bounded = pr.rollout_bounded;
  } catch (const mme::InputError& e) {
    std::printf("fig5: %s %s: %s\n", c.name.c_str(), variant, e.what());
  }
  return bounded;
}

/// One line of fig5_summary.csv and its report on stdout.
void writeVariantSummary(std::FILE* g, const Fig5Case& c, const char* variant, const VariantFit& v,
                         const mme::HeldOutSplit& split, const double rms[4], bool bounded) {
  std::fprintf(g, "%s,%s,%zu,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%.2f\n", c.name.c_str(), variant,
               v.parameters, split.fit_frames, split.held_frames, v.cost_m2, rms[0], rms[1],
               rms[2], rms[3], bounded ? 1 : 0, v.wall_s);
  std::fflush(g);
  std::printf("fig5: %s %s: %zu parameters, cost %.4g m^2 after %d generations; 10 frames "
              "ahead on held-out frames: model %.2f mm, constant velocity %.2f mm, constant "
              "acceleration %.2f mm, gravity only %.2f mm; rollout %s; %.1f s\n",
              c.name.c_str(), variant, v.parameters, v.cost_m2, v.generations_run,
              1e3 * rms[0], 1e3 * rms[1], 1e3 * rms[2], 1e3 * rms[3],
              bounded ? "bounded" : "UNBOUNDED", v.wall_s);
}

/// One variant of one case: fitted (or skipped when it does not apply), judged, written.
void runVariant(const Fig5Case& c, const char* variant, const mme::HeldOutSplit& split,
                const mme::IdentifyOptions& o, Fig5Files files, DampersFit* dampers) {
  const std::string v = variant;
  // A case whose truth has muscles (a walking walker) gets its own controllers, from the
  // priors; the others get muscles placed on the dampers' fit (muscle_placement.h), and
  // sensor muscles fitted on it by least squares (sensor_muscles.h; no search, no curve).
  const bool own_muscles = mme::muscleTypeCount(c.structure) > 0;
  VariantFit fit;
  if (v == "sensor_muscles") {
    if (own_muscles || !fitSensorMuscles(c, dampers->model, split.fit, &fit)) return;
  } else {
    Model start;
    if (!variantStart(c, v, own_muscles, dampers->model, split.fit, &start)) return;
    const int offset = v == "muscles" && !own_muscles ? dampers->generations : 0;
    fit = searchVariant(c, variant, start, offset, split.fit, o, files.curves);
    if (v == "dampers") {
      dampers->model = fit.fitted;
      dampers->generations = fit.generations_run;
    }
  }
  double rms[4] = {NAN, NAN, NAN, NAN};
  const bool bounded = judgeHeldOut(c, variant, fit.fitted, split, rms);
  writeVariantSummary(files.summary, c, variant, fit, split, rms, bounded);
}

}  // namespace

/// Fig. 5 of the paper (section 4.4): log cost against generations for the same bonds without
/// muscles (springs), with dampers, and with muscles, on the walker (its own known controllers,
/// the muscle-free parameters from the priors) and on the real recordings (structure chosen from
/// the markers first; every spring type a muscle reading its two nearest bonds, started from the
/// dampers' fit: activation 0). Each fit runs on the window's first
/// 80 % and is judged on the rest: the 10-frame open-loop prediction error beside the model-free
/// guesses. One cost for all (the paper's one-step cost), the whole generation budget each.
void figure5(const Settings& s) {
  const Fig5Files files{
      openCsv(s.out_dir + "/fig5.csv",
              "case,variant,generation,chart_generation,evaluations,log10_cost,wall_s"),
      openCsv(s.out_dir + "/fig5_summary.csv",
              "case,variant,parameters,fitted_frames,held_out_frames,cost_m2,"
              "model_rms_10_m,constant_velocity_rms_10_m,constant_acceleration_rms_10_m,"
              "gravity_only_rms_10_m,bounded,wall_s")};
  const int generations = s.generations > 0 ? s.generations : (s.quick ? 10 : 100);
  for (const Fig5Case& c : fig5Cases(s)) {
    const mme::HeldOutSplit split = fig5Split(c.data, c.name);
    const mme::IdentifyOptions o = fig5Options(s, generations);
    DampersFit dampers;
    for (const char* variant : {"springs", "dampers", "muscles", "sensor_muscles"})
      runVariant(c, variant, split, o, files, &dampers);
  }
  std::fclose(files.curves);
  std::fclose(files.summary);
}

}  // namespace paper

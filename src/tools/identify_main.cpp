// identify: offline identification of a trajectory file or bag (SPEC section 7).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>

#include "cli_args.h"
#include "trajectory_input.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/structure/marker_model.h"
#include "motion_model_estimation/identification/muscles/muscle_placement.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "motion_model_estimation/io/model_yaml.h"

namespace {

const char* kUsage =
    "usage: identify --model M.yaml --trajectory FILE(.trc|.c3d|.bag) [--topic T] --out OUT.yaml\n"
    "                [--method es] [--generations N] [--population P] [--window-frames W]\n"
    "                [--first-frame F] [--frames N] [--seed S] [--threads T]\n"
    "                [--compare-to-model] [--target-cost C] [--max-time-s S] [--quiet]\n"
    "                [--preset default|paper] [--patience G]\n"
    "                [--cost auto|short_term|output_error] [--segment-frames K]\n"
    "                [--grow-segments G]\n"
    "                [--refine bobyqa|newuoa|praxis|levenberg_marquardt] [--refine-start G]\n"
    "                [--refine-period G] [--select-structure]\n"
    "                [--add-muscles INPUTS] [--muscle-hidden H]\n"
    "                [--sensor-muscles SENSORS] [--muscle-neighbours K] [--rollout-rounds R]\n"
    "                [--muscle-anchors auto|0|1] [--anchor-stiffness 1|0|auto]\n"
    "                [--muscles-max-time-s S]\n"
    "--max-time-s bounds the structure selection (all its levels together: a cut selection\n"
    "chooses the best level judged so far) and then the passive identification,\n"
    "--muscles-max-time-s the sensor muscles' search after them (checked between its steps: a\n"
    "step under way and the final refits still run; see docs/muscles.md); 0, the default for both:\n"
    "no limit.\n";

std::string formatMetres(double m) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g m", m);
  return text;
}

int run(int argc, char** argv) {
  mme::CliArgs args(argc, argv,
                    {"model", "trajectory", "topic", "out", "method", "generations", "population",
                     "window-frames", "first-frame", "frames", "seed", "threads", "target-cost",
                     "max-time-s", "refine", "refine-start", "refine-period", "preset", "patience", "cost", "segment-frames",
                     "grow-segments", "add-muscles", "muscle-hidden", "sensor-muscles",
                     "muscle-neighbours", "rollout-rounds", "muscle-anchors", "anchor-stiffness",
                     "muscles-max-time-s"},
                    {"compare-to-model", "quiet", "help", "select-structure"});
  if (args.has("help")) {
    std::cout << kUsage;
    return 0;
  }
  for (const char* required : {"trajectory", "out"})
    if (!args.has(required)) throw mme::InputError(std::string("--") + required + " is required");
  if (!args.has("model") && !args.has("select-structure"))
    throw mme::InputError("--model is required (without it only --select-structure can start, from "
                          "the markers alone)");
  const std::string method = args.get("method", "es");
  if (method != "es") throw mme::InputError("--method '" + method + "' is unknown (available: es)");
  const std::string model_path = args.get("model");
  const std::string trajectory_path = args.get("trajectory");
  const std::string out_path = args.get("out");

  // The preset first (default: the measured best; paper: the paper's schedule), then the
  // options that override it.
  mme::Preset preset = mme::Preset::kDefault;
  if (args.has("preset") && !mme::parsePreset(args.get("preset"), &preset))
    throw mme::InputError("--preset '" + args.get("preset") + "' is unknown (available: " +
                          mme::presetNames() + ")");
  mme::IdentifyOptions options = mme::identifyOptionsFor(preset);
  options.patience_generations = static_cast<int>(
      args.getInt("patience", options.patience_generations, 0, 100000000));
  if (args.has("cost") && !mme::parseCostChoice(args.get("cost"), &options.cost))
    throw mme::InputError("--cost '" + args.get("cost") +
                          "' is unknown (available: auto, short_term or output_error)");
  options.output_error.segment_frames = static_cast<int>(
      args.getInt("segment-frames", options.output_error.segment_frames, 2, 100000));
  options.output_error.grow_segments = static_cast<int>(
      args.getInt("grow-segments", options.output_error.grow_segments, 0, 100000));
  options.generations = static_cast<int>(args.getInt("generations", 1000, 1, 100000000));
  options.es.population = static_cast<int>(args.getInt("population", 100, 2, 1000000));
  options.es.offspring = options.es.population;
  options.es.seed = static_cast<uint64_t>(args.getInt("seed", 1, 0, 0x7fffffffL));
  options.es.threads = static_cast<int>(args.getInt("threads", 1, 1, 256));
  if (args.has("refine") && !mme::parseRefineAlgorithm(args.get("refine"), &options.es.refine_algorithm))
    throw mme::InputError("--refine '" + args.get("refine") + "' is unknown (available: " +
                          mme::refineAlgorithmNames() + ")");
  options.es.refine_start_generation = static_cast<int>(
      args.getInt("refine-start", options.es.refine_start_generation, 0, 100000000));
  options.es.refine_period =
      static_cast<int>(args.getInt("refine-period", options.es.refine_period, 0, 100000000));
  {
    const std::string bad = mme::validateOptions(options.es);
    if (!bad.empty()) throw mme::InputError("--refine: " + bad);
  }
  options.target_cost = args.getDouble("target-cost", 0.0, 0.0, 1e300);
  options.max_wall_time_s = args.getDouble("max-time-s", 0.0, 0.0, 1e9);
  const bool compare = args.has("compare-to-model");
  const bool quiet = args.has("quiet");

  // Sensor muscles (sensor_muscles.h), checked before the identification so that a bad option
  // does not wait for it. On by default with --select-structure under the default preset (a
  // model chosen from the markers of a capture: where they are kept, on 4 of the 7 real
  // captures, they predict 10 frames ahead 2-8x better than the passive model, and they are
  // written only where they predict the held-out frames better);
  // off otherwise unless asked for. --sensor-muscles 0: none.
  const bool muscle_options_given =
      args.has("muscle-neighbours") || args.has("rollout-rounds") || args.has("muscle-anchors") ||
      args.has("anchor-stiffness");
  const bool sensor_default =
      muscle_options_given || (args.has("select-structure") && preset == mme::Preset::kDefault && !compare);
  mme::SensorMuscleOptions sensor_options;
  sensor_options.sensors = static_cast<int>(
      args.getInt("sensor-muscles", sensor_default ? sensor_options.sensors : 0, 0, mme::kMaxMuscleInputs));
  const bool sensor_muscles = sensor_options.sensors > 0;
  if (sensor_muscles) {
    if (compare)
      throw mme::InputError("--compare-to-model and --sensor-muscles do not go together (the "
                            "muscles are not the file's)");
    sensor_options.neighbours = static_cast<int>(
        args.getInt("muscle-neighbours", sensor_options.neighbours, 0, 64));
    sensor_options.rollout_rounds = static_cast<int>(
        args.getInt("rollout-rounds", sensor_options.rollout_rounds, 0, 20));
    // auto (the default): both layouts fitted, the one predicting the validation frames better
    // kept; 1: with anchors; 0: without.
    const std::string anchors = args.get("muscle-anchors", "auto");
    if (anchors != "auto" && anchors != "0" && anchors != "1")
      throw mme::InputError("--muscle-anchors must be auto, 0 or 1, got '" + anchors + "'");
    sensor_options.anchors = anchors != "0";
    sensor_options.anchors_by_validation = anchors == "auto";
    // The anchor muscles' own stiffness: 1 (the default) fitted; 0 held at 0; auto held at 0 for
    // a free body that travels over the data, fitted otherwise.
    const std::string stiffness = args.get("anchor-stiffness", "1");
    if (stiffness != "auto" && stiffness != "0" && stiffness != "1")
      throw mme::InputError("--anchor-stiffness must be auto, 0 or 1, got '" + stiffness + "'");
    sensor_options.anchor_stiffness = stiffness == "auto" ? mme::AnchorStiffness::kAuto
                                      : stiffness == "1"  ? mme::AnchorStiffness::kFitted
                                                          : mme::AnchorStiffness::kNone;
    // The muscles' own time limit (--max-time-s bounds the passive identification only): a
    // capture of ~40 markers takes 10-25 minutes there without one.
    sensor_options.max_time_s = args.getDouble("muscles-max-time-s", 0.0, 0.0, 1e9);
    sensor_options.progress = [quiet](const std::string& line) {
      if (!quiet) std::printf("identify: %s\n", line.c_str());
      std::fflush(stdout);
    };
  } else if (muscle_options_given) {
    throw mme::InputError("--muscle-neighbours, --rollout-rounds, --muscle-anchors and --anchor-stiffness need sensor "
                          "muscles (--sensor-muscles 0 turns them off)");
  } else if (args.has("muscles-max-time-s")) {
    throw mme::InputError("--muscles-max-time-s needs sensor muscles (on by default only with "
                          "--select-structure; --sensor-muscles SENSORS turns them on)");
  }

  if (compare && model_path.empty())
    throw mme::InputError("--compare-to-model needs --model (the values to compare with)");
  mme::Model model;
  if (!model_path.empty()) model = mme::loadModelFile(model_path);
  const mme::Trajectory data = mme::readToolTrajectory("identify", trajectory_path, args.get("topic"));
  if (model_path.empty()) {
    // No model: the markers are the particles (identification/structure/marker_model.h).
    model = mme::markerModel(data);
    std::printf("identify: no --model: the %zu markers of %s are the particles (1 kg each, free "
                "gravity); structure selection chooses every bond\n",
                model.particles.size(), trajectory_path.c_str());
  }
  const mme::Model reference = model;
  if (compare) {
    // The file's values are the truth to compare with, not initial guesses.
    for (const mme::ParamRef& ref : mme::freeParameters(model)) {
      mme::Param& p = mme::paramOf(model, ref);
      p.has_value = false;
    }
  }
  const mme::Trajectory trajectory =
      mme::fitTrajectoryToModel("identify", trajectory_path, data, args, &model);
  if (args.has("select-structure")) {
    // The structure from the markers first: the model file's bonds stay, candidates are added
    // and thinned (structure_selection.h); the chosen model is then identified as usual on
    // every frame, and the report of every candidate goes beside the output.
    if (compare)
      throw mme::InputError("--compare-to-model and --select-structure do not go together (the "
                            "selected bonds are not the file's)");
    mme::StructureOptions so;
    so.identify = options;
    so.max_wall_time_s = options.max_wall_time_s;
    so.progress = [&](const std::string& line) {
      if (!quiet) std::printf("%s\n", line.c_str());
      std::fflush(stdout);
    };
    const mme::StructureResult selected = mme::selectStructure(model, trajectory, so);
    const std::string report = mme::formatStructureReport(selected);
    std::printf("%s", report.c_str());
    const std::string report_path = out_path + ".structure.csv";
    mme::writeFileAtomically(report_path, mme::structureReportCsv(selected));
    std::printf("identify: wrote %s\n", report_path.c_str());
    model = selected.model;
  }
  if (args.has("add-muscles") || args.has("muscle-hidden")) {
    // Muscles on the passive model (muscle_placement.h): every spring type becomes a muscle type
    // whose bonds read their nearest bonds, starting silent from the passive values.
    if (compare)
      throw mme::InputError("--compare-to-model and --add-muscles do not go together (the muscles "
                            "are not the file's)");
    mme::MusclePlacement placement;
    placement.inputs = static_cast<int>(args.getInt("add-muscles", 2, 0, mme::kMaxMuscleInputs));
    placement.hidden = static_cast<int>(args.getInt("muscle-hidden", 0, 0, mme::kMaxMuscleHidden));
    model = mme::addMuscles(model, &trajectory, placement);
    const int muscles = mme::muscleTypeCount(model);
    int reads = 0;
    for (const mme::BondType& type : model.bond_types)
      if (type.kind == mme::BondKind::kMuscle) reads = type.network_inputs;
    if (muscles == 0)
      throw mme::InputError("--add-muscles: the model has no spring type that can become a muscle "
                            "(plain springs: no threshold, no cubic term, not an interaction)");
    std::printf("identify: %d spring type(s) became muscles reading %d bond(s) each, %d hidden "
                "unit(s)\n", muscles, reads, placement.hidden);
  }

  const bool tty = isatty(STDOUT_FILENO);
  double last_print_s = -1.0;
  auto progress = [&](const mme::Progress& p) {
    if (!p.message.empty()) {  // notices go to stderr even with --quiet
      std::fprintf(stderr, "%sidentify: %s\n", tty && !quiet ? "\n" : "", p.message.c_str());
      return;
    }
    if (quiet) return;
    const bool last = p.generation == options.generations;
    if (!last && p.wall_time_s - last_print_s < (tty ? 0.2 : 2.0)) return;
    last_print_s = p.wall_time_s;
    std::printf("%sgeneration %d/%d  evaluations %llu  cost %.6e  %.1f s%s", tty ? "\r" : "",
                p.generation, options.generations,
                static_cast<unsigned long long>(p.evaluations), p.best_cost, p.wall_time_s,
                tty ? "   " : "\n");
    std::fflush(stdout);
  };
  std::printf("identify: %d frames x %d markers at %g Hz, %zu free parameters, population %d, "
              "preset %s (refinement %s from generation %d, every %d)\n",
              trajectory.numFrames(), trajectory.numMarkers(), model.frame_rate_hz,
              mme::freeParameters(model).size(), options.es.population, mme::presetName(preset),
              mme::refineAlgorithmName(options.es.refine_algorithm),
              options.es.refine_start_generation, options.es.refine_period);
  const mme::IdentifyResult r = mme::identifyModel(model, trajectory, options, progress);
  if (tty && !quiet) std::printf("\n");

  std::printf("\n%-28s %16s %12s", "parameter", "value", "std");
  if (compare) std::printf(" %16s %10s", "true", "error %");
  std::printf("  %s\n", "flag");
  for (size_t k = 0; k < r.parameters.size(); ++k) {
    std::printf("%-28s %16.9g %12.3g", r.parameters[k].name.c_str(), r.values[k], r.std_devs[k]);
    if (compare) {
      const mme::Param& p = mme::paramOf(reference, r.parameters[k]);
      if (p.has_value) {
        const double err = p.value != 0.0 ? 100.0 * (r.values[k] - p.value) / std::abs(p.value)
                                          : std::nan("");
        std::printf(" %16.9g %10.4f", p.value, err);
      } else {
        std::printf(" %16s %10s", "-", "-");
      }
    }
    std::printf("  %s\n", mme::parameterFlagName(r.flags[k]));
  }
  std::printf("global cost %.6e m^2 over %d frames, %d generations, %llu evaluations, %.2f s\n",
              r.global_cost, r.frames, r.generations,
              static_cast<unsigned long long>(r.evaluations), r.wall_time_s);
  std::printf("estimator: %s (--cost %s; marker noise estimated from the data %.3g m%s), %d "
              "substep(s) per frame (stiffest mode omega*h %.3g)\n",
              r.estimator.c_str(), mme::costChoiceName(options.cost), r.noise_estimate_m,
              r.estimator == "output_error"
                  ? (", from the fit's residuals " + formatMetres(r.noise_std_m)).c_str() : "",
              r.substeps, r.stiffest_omega_h);
  std::printf("stopped: %s (last refinement: %s %s)\n", mme::identifyStopName(r.stop),
              mme::refineAlgorithmName(options.es.refine_algorithm),
              mme::refineStatusName(r.last_refine_status));

  mme::Model out_model = r.model;
  std::vector<std::string> notes = r.notes;
  std::optional<mme::SensorMuscleResult> fitted;
  if (sensor_muscles) {
    // Sensor muscles on the identified model (sensor_muscles.h): fitted by least squares, the
    // ridge chosen on the last 20 % of the frames; kept only where they predict those better.
    // The options were checked above, so what fails here is the data's (too few frames, no
    // pair seen together often enough, a body too large): the identified model is still
    // written, with a warning, rather than lost.
    try {
      fitted = mme::addSensorMuscles(r.model, trajectory, sensor_options);
    } catch (const mme::InputError& e) {
      std::fprintf(stderr, "identify: warning: no sensor muscles (%s): the passive model is written\n",
                   e.what());
      notes.push_back(std::string("sensor muscles: none (") + e.what() + ")");
    }
  }
  if (fitted) {
    const mme::SensorMuscleResult& sm = *fitted;
    char line[512];
    std::snprintf(line, sizeof(line),
                  "sensor muscles: %d sensors, %d muscles, ridge %.0e, %d rollout round(s), "
                  "activation time constant %.3g s, %s anchors; %d frames ahead on the last frames "
                  "%.3g m (passive %.3g m, constant velocity %.3g m), %.0f s%s%s%s",
                  sm.sensors, sm.muscles, sm.ridge, sm.candidates[sm.chosen].rollout_rounds,
                  sm.activation_time_s, sm.anchors ? "with" : "without", sensor_options.horizon_frames,
                  sm.validation_rms_m,
                  sm.passive_rms_m, sm.constant_velocity_rms_m, sm.wall_time_s,
                  sm.stopped_by_time ? " (stopped by --muscles-max-time-s: fewer candidates judged)" : "",
                  !sm.anchors ? ""
                  : sm.anchor_stiffness ? "; the anchor muscles with a stiffness of their own"
                                        : "; the anchor muscles without a stiffness of their own",
                  sm.better_than_passive ? "" : ": not better than the passive model, which is kept");
    std::printf("identify: %s\n", line);
    if (!sm.better_than_passive)
      std::fprintf(stderr, "identify: warning: the sensor muscles are not kept (%s): the passive "
                   "model is written\n", sm.not_kept_because.c_str());
    else
      out_model = sm.model;
    notes.push_back(line);
  }

  mme::IdentificationInfo info;
  info.method = r.estimator == "output_error" ? "es+output_error" : "es";
  info.global_cost = r.global_cost;
  info.frames = r.frames;
  info.generations = r.generations;
  info.wall_time_s = r.wall_time_s;
  size_t flagged = 0;
  for (size_t k = 0; k < r.parameters.size(); ++k) {
    if (std::isfinite(r.std_devs[k])) {
      info.std_names.push_back(r.parameters[k].name);
      info.std_values.push_back(r.std_devs[k]);
    }
    if (r.flags[k] != mme::ParameterFlag::kNone) {
      info.flags.emplace_back(r.parameters[k].name, mme::parameterFlagName(r.flags[k]));
      ++flagged;
    }
  }
  info.notes = notes;
  if (flagged > 0)
    std::fprintf(stderr, "identify: warning: %zu parameter(s) ended within 1 %% of a search bound "
                 "(flag column); the answer may lie beyond: give wider min/max in the model file\n",
                 flagged);
  mme::writeModelFile(out_path, out_model, &info);
  std::printf("identify: wrote %s\n", out_path.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return mme::runTool("identify", run, argc, argv); }

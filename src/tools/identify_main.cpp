// identify: offline identification of a trajectory file or bag (SPEC section 7): the command
// line parsed into the pipeline's options (pipeline/identify_pipeline.h), the pipeline run, its
// result printed and written.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli_args.h"
#include "tool_formats.h"
#include "trajectory_input.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/pipeline/identify_pipeline.h"
#include "motion_model_estimation/pipeline/result_checks.h"
#include "motion_model_estimation/pipeline/result_metadata.h"

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

/// The command line, parsed.
struct Command {
  mme::PipelineOptions pipeline;
  mme::Preset preset = mme::Preset::kDefault;
  std::string model_path, trajectory_path, out_path, topic;
  bool compare = false;  ///< the model file's values are the truth to compare with
  bool quiet = false;
};

/// The search's options: the preset first (default: the measured best; paper: the paper's
/// schedule), then the options that override it.
void parseSearchOptions(const mme::CliArgs& args, Command* c) {
  if (args.has("preset") && !mme::parsePreset(args.get("preset"), &c->preset))
    throw mme::InputError("--preset '" + args.get("preset") + "' is unknown (available: " +
                          mme::presetNames() + ")");
  mme::IdentifyOptions& options = c->pipeline.identify;
  options = mme::identifyOptionsFor(c->preset);
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
  const std::string bad = mme::validateOptions(options.es);
  if (!bad.empty()) throw mme::InputError("--refine: " + bad);
  options.target_cost = args.getDouble("target-cost", 0.0, 0.0, 1e300);
  options.max_wall_time_s = args.getDouble("max-time-s", 0.0, 0.0, 1e9);
}

/// Sensor muscles (sensor_muscles.h), checked before the run so that a bad option does not wait
/// for the identification. On by default with --select-structure under the default preset (a
/// model chosen from a capture's markers), off otherwise unless asked for; --sensor-muscles 0:
/// none. They are written only where they predict the held-out frames better.
void parseSensorMuscleOptions(const mme::CliArgs& args, Command* c) {
  const bool muscle_options_given = args.has("muscle-neighbours") || args.has("rollout-rounds") ||
                                    args.has("muscle-anchors") || args.has("anchor-stiffness");
  const bool on_by_default = muscle_options_given || (args.has("select-structure") &&
                                                      c->preset == mme::Preset::kDefault && !c->compare);
  mme::SensorMuscleOptions options;
  options.sensors = static_cast<int>(
      args.getInt("sensor-muscles", on_by_default ? options.sensors : 0, 0, mme::kMaxMuscleInputs));
  if (options.sensors == 0) {
    if (muscle_options_given)
      throw mme::InputError("--muscle-neighbours, --rollout-rounds, --muscle-anchors and --anchor-stiffness need sensor "
                            "muscles (--sensor-muscles 0 turns them off)");
    if (args.has("muscles-max-time-s"))
      throw mme::InputError("--muscles-max-time-s needs sensor muscles (on by default only with "
                            "--select-structure; --sensor-muscles SENSORS turns them on)");
    return;
  }
  if (c->compare)
    throw mme::InputError("--compare-to-model and --sensor-muscles do not go together (the "
                          "muscles are not the file's)");
  options.neighbours = static_cast<int>(args.getInt("muscle-neighbours", options.neighbours, 0, 64));
  options.rollout_rounds = static_cast<int>(args.getInt("rollout-rounds", options.rollout_rounds, 0, 20));
  // auto (the default): both layouts fitted, the one predicting the validation frames better
  // kept; 1: with anchors; 0: without.
  const std::string anchors = args.get("muscle-anchors", "auto");
  if (anchors != "auto" && anchors != "0" && anchors != "1")
    throw mme::InputError("--muscle-anchors must be auto, 0 or 1, got '" + anchors + "'");
  options.anchors = anchors != "0";
  options.anchors_by_validation = anchors == "auto";
  // The anchor muscles' own stiffness: 1 (the default) fitted; 0 held at 0; auto held at 0 for
  // a free body that travels over the data, fitted otherwise.
  const std::string stiffness = args.get("anchor-stiffness", "1");
  if (stiffness != "auto" && stiffness != "0" && stiffness != "1")
    throw mme::InputError("--anchor-stiffness must be auto, 0 or 1, got '" + stiffness + "'");
  options.anchor_stiffness = stiffness == "auto" ? mme::AnchorStiffness::kAuto
                             : stiffness == "1"  ? mme::AnchorStiffness::kFitted
                                                 : mme::AnchorStiffness::kNone;
  options.max_time_s = args.getDouble("muscles-max-time-s", 0.0, 0.0, 1e9);
  c->pipeline.sensor_muscles = options;
}

Command parseCommand(const mme::CliArgs& args) {
  Command c;
  for (const char* required : {"trajectory", "out"})
    if (!args.has(required)) throw mme::InputError(std::string("--") + required + " is required");
  if (!args.has("model") && !args.has("select-structure"))
    throw mme::InputError("--model is required (without it only --select-structure can start, from "
                          "the markers alone)");
  const std::string method = args.get("method", "es");
  if (method != "es") throw mme::InputError("--method '" + method + "' is unknown (available: es)");
  c.model_path = args.get("model");
  c.trajectory_path = args.get("trajectory");
  c.out_path = args.get("out");
  c.topic = args.get("topic");
  c.compare = args.has("compare-to-model");
  c.quiet = args.has("quiet");
  parseSearchOptions(args, &c);
  parseSensorMuscleOptions(args, &c);
  if (c.compare && c.model_path.empty())
    throw mme::InputError("--compare-to-model needs --model (the values to compare with)");
  c.pipeline.select_structure = args.has("select-structure");
  if (c.compare && c.pipeline.select_structure)
    throw mme::InputError("--compare-to-model and --select-structure do not go together (the "
                          "selected bonds are not the file's)");
  if (args.has("add-muscles") || args.has("muscle-hidden")) {
    // Muscles on the passive model (muscle_placement.h): every spring type becomes a muscle type
    // whose bonds read their nearest bonds, starting silent from the passive values.
    if (c.compare)
      throw mme::InputError("--compare-to-model and --add-muscles do not go together (the muscles "
                            "are not the file's)");
    mme::MusclePlacement placement;
    placement.inputs = static_cast<int>(args.getInt("add-muscles", 2, 0, mme::kMaxMuscleInputs));
    placement.hidden = static_cast<int>(args.getInt("muscle-hidden", 0, 0, mme::kMaxMuscleHidden));
    c.pipeline.muscles = placement;
  }
  return c;
}

/// The generation line: in place on a terminal (5 per second), a line every 2 s otherwise;
/// notices (a widened bound, ...) to stderr even with --quiet.
std::function<void(const mme::Progress&)> progressPrinter(const Command& c) {
  const bool tty = isatty(STDOUT_FILENO);
  const bool quiet = c.quiet;
  const int generations = c.pipeline.identify.generations;
  auto last_print_s = std::make_shared<double>(-1.0);
  return [=](const mme::Progress& p) {
    if (!p.message.empty()) {
      std::fprintf(stderr, "%sidentify: %s\n", tty && !quiet ? "\n" : "", p.message.c_str());
      return;
    }
    if (quiet) return;
    const bool last = p.generation == generations;
    if (!last && p.wall_time_s - *last_print_s < (tty ? 0.2 : 2.0)) return;
    *last_print_s = p.wall_time_s;
    std::printf("%sgeneration %d/%d  evaluations %llu  cost %.6e  %.1f s%s", tty ? "\r" : "",
                p.generation, generations, static_cast<unsigned long long>(p.evaluations),
                p.best_cost, p.wall_time_s, tty ? "   " : "\n");
    std::fflush(stdout);
  };
}

/// How the run talks while it goes: steps' lines and warnings, the structure's report kept as
/// soon as it is chosen, the identification's opening line, the generations.
void connectOutput(Command* c) {
  const bool quiet = c->quiet;
  mme::PipelineOptions& p = c->pipeline;
  p.say = [quiet](const std::string& line) {
    if (!quiet) std::printf("identify: %s\n", line.c_str());
    std::fflush(stdout);
  };
  p.warn = [](const std::string& line) {
    std::fprintf(stderr, "identify: warning: %s\n", line.c_str());
  };
  const std::string report_path = c->out_path + ".structure.csv";
  p.structure_chosen = [report_path](const mme::StructureResult& selected) {
    std::printf("%s", mme::formatStructureReport(selected).c_str());
    mme::writeFileAtomically(report_path, mme::structureReportCsv(selected));
    std::printf("identify: wrote %s\n", report_path.c_str());
  };
  const Command* command = c;
  p.identification_starts = [command](const mme::Model& model, const mme::Trajectory& trajectory) {
    const mme::IdentifyOptions& o = command->pipeline.identify;
    std::printf("identify: %d frames x %d markers at %g Hz, %zu free parameters, population %d, "
                "preset %s (refinement %s from generation %d, every %d)\n",
                trajectory.numFrames(), trajectory.numMarkers(), model.frame_rate_hz,
                mme::freeParameters(model).size(), o.es.population, mme::presetName(command->preset),
                mme::refineAlgorithmName(o.es.refine_algorithm), o.es.refine_start_generation,
                o.es.refine_period);
  };
  p.progress = progressPrinter(*c);
}

/// The table of identified values with their units (from the catalogue); a std that could not
/// be determined is "-", explained under the table rather than printed as nan.
void printParameterTable(const mme::IdentifyResult& r, const mme::Model& reference, bool compare) {
  std::printf("\n%-28s %16s %12s %-10s", "parameter", "value", "std", "unit");
  if (compare) std::printf(" %16s %10s", "true", "error %");
  std::printf("  %s\n", "flag");
  bool std_missing = false;
  for (size_t k = 0; k < r.parameters.size(); ++k) {
    std::printf("%-28s %16.9g", r.parameters[k].name.c_str(), r.values[k]);
    if (std::isfinite(r.std_devs[k])) std::printf(" %12.3g", r.std_devs[k]);
    else std::printf(" %12s", "-");
    std_missing = std_missing || !std::isfinite(r.std_devs[k]);
    std::printf(" %-10s", mme::parameterUnit(r.model, r.parameters[k]).c_str());
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
  if (std_missing)
    std::printf("std '-': not determined: %s\n",
                !r.std_missing_reason.empty()
                    ? r.std_missing_reason.c_str()
                    : "the data do not determine the parameter (its information is singular: "
                      "it moves nothing the markers show), or it is a threshold never crossed");
  if (mme::unitMasses(r.model))
    std::printf("masses: 1 kg per marker (not measured): stiffness, damping and gain are per "
                "kilogram of marker\n");
}

void printSummary(const mme::IdentifyResult& r, const Command& c) {
  const mme::IdentifyOptions& options = c.pipeline.identify;
  std::printf("global cost %.6e m^2 over %d frames, %d generations, %llu evaluations, %.2f s\n",
              r.global_cost, r.frames, r.generations,
              static_cast<unsigned long long>(r.evaluations), r.wall_time_s);
  std::printf("estimator: %s (--cost %s; marker noise estimated from the data %.3g m%s), %d "
              "substep(s) per frame (stiffest mode omega*h %.3g)\n",
              mme::estimatorName(r.estimator), mme::costChoiceName(options.cost), r.noise_estimate_m,
              r.estimator == mme::Estimator::kOutputError
                  ? (", from the fit's residuals " + formatMetres(r.noise_std_m)).c_str() : "",
              r.substeps, r.stiffest_omega_h);
  std::printf("stopped: %s (last refinement: %s %s)\n", mme::identifyStopName(r.stop),
              mme::refineAlgorithmName(options.es.refine_algorithm),
              mme::refineStatusName(r.last_refine_status));
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
  Command c = parseCommand(args);
  connectOutput(&c);

  mme::Model model;
  if (!c.model_path.empty()) model = mme::loadModelFile(c.model_path);
  if (!c.model_path.empty() && model.particles.empty())
    throw mme::InputError(c.model_path + ": the model has no particles: nothing to identify (list "
                          "the markers under particles:, or leave out --model with "
                          "--select-structure to start from the capture's markers)");
  const mme::Trajectory data = mme::readToolTrajectory("identify", c.trajectory_path, c.topic);
  if (c.model_path.empty()) {
    model = mme::startingModel(data);
    std::printf("identify: no --model: the %zu markers of %s are the particles (1 kg each, free "
                "gravity); structure selection chooses every bond\n",
                model.particles.size(), c.trajectory_path.c_str());
  }
  const mme::Model reference = model;
  if (c.compare)  // the file's values are the truth to compare with, not initial guesses
    for (const mme::ParamRef& ref : mme::freeParameters(model)) mme::paramOf(model, ref).has_value = false;
  const mme::Trajectory trajectory =
      mme::fitTrajectoryToModel("identify", c.trajectory_path, data, args, &model);

  const mme::PipelineResult result = mme::runPipeline(model, trajectory, c.pipeline);
  if (isatty(STDOUT_FILENO) && !c.quiet) std::printf("\n");
  printParameterTable(result.identified, reference, c.compare);
  printSummary(result.identified, c);
  if (!result.sensor_muscle_summary.empty())
    std::printf("identify: %s\n", result.sensor_muscle_summary.c_str());

  std::fflush(stdout);  // the warnings come after the table, never inside it
  std::vector<std::string> checks = mme::identifiedModelWarnings(result.model, trajectory);
  if (result.structure)
    for (const std::string& line : mme::chosenStructureWarnings(*result.structure)) checks.push_back(line);
  for (const std::string& line : checks) std::fprintf(stderr, "identify: warning: %s\n", line.c_str());
  const mme::IdentifyResult& r = result.identified;
  const mme::IdentificationInfo info = mme::identificationInfo(r, result.notes);
  if (!info.flags.empty())
    std::fprintf(stderr, "identify: warning: %zu parameter(s) ended within 1 %% of a search bound "
                 "(flag column); the answer may lie beyond: give wider min/max in the model file\n",
                 info.flags.size());
  mme::writeModelFile(c.out_path, result.model, &info);
  std::printf("identify: wrote %s\n", c.out_path.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mme::registerToolFormats();
  return mme::runTool("identify", run, argc, argv);
}

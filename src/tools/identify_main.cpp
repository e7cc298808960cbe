// identify: offline identification of a trajectory file or bag (SPEC section 7): the command
// line parsed into the pipeline's options (pipeline/identify_pipeline.h), the pipeline run, its
// result printed and written.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>
#include <thread>

#include "cli_args.h"
#include "identify_cli.h"
#include "tool_formats.h"
#include "trajectory_input.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/pipeline/identify_pipeline.h"
#include "motion_model_estimation/pipeline/result_checks.h"
#include "motion_model_estimation/pipeline/result_metadata.h"

namespace {

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
  options.islands.islands = static_cast<int>(args.getInt("islands", 1, 1, 1024));
  if (options.islands.islands == 1 &&
      (args.has("migration-period") || args.has("migrants") || args.has("island-processes")))
    throw mme::InputError("--migration-period, --migrants and --island-processes need --islands N with N >= 2");
  options.islands.processes = args.has("island-processes");
  options.islands.migration_period_generations = static_cast<int>(
      args.getInt("migration-period", options.islands.migration_period_generations, 1, 100000000));
  options.islands.migrants = static_cast<int>(
      args.getInt("migrants", options.islands.migrants, 1, options.es.population));
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
/// for the identification. The default is auto: the muscles are fitted after the passive model
/// only where the gain gate finds something to gain (SensorMuscleOptions::skip_without_gain; on
/// a passive scene it stops them in seconds, on human motion they predict several times better)
/// and written only where they predict the held-out frames better. `off` (or 0) gives a plain
/// passive model; a number of sensors forces the search. With --compare-to-model (the muscles
/// are not the file's) and --preset paper (the paper's method) they are off unless asked for.
void parseSensorMuscleOptions(const mme::CliArgs& args, Command* c) {
  const bool muscle_options_given = args.has("muscle-neighbours") || args.has("rollout-rounds") ||
                                    args.has("muscle-anchors") || args.has("anchor-stiffness");
  const bool asked = args.has("sensor-muscles");
  const bool off_by_default = c->compare || c->preset == mme::Preset::kPaper;
  const std::string choice = args.get("sensor-muscles", off_by_default ? "off" : "auto");
  mme::SensorMuscleOptions options;
  // auto: the default sensors, the search started only where the gain gate finds something to
  // gain; a number forces the search with that many.
  const bool automatic = choice == "auto";
  options.skip_without_gain = automatic;
  if (!automatic && choice != "off" && choice.find_first_not_of("0123456789") != std::string::npos)
    throw mme::InputError("--sensor-muscles must be auto, off or a number of sensors (0.." +
                          std::to_string(mme::kMaxMuscleInputs) + "), got '" + choice + "'");
  if (choice == "off")
    options.sensors = 0;
  else if (!automatic)
    options.sensors = static_cast<int>(args.getInt("sensor-muscles", options.sensors, 0, mme::kMaxMuscleInputs));
  if (options.sensors == 0) {
    if (muscle_options_given)
      throw mme::InputError("--muscle-neighbours, --rollout-rounds, --muscle-anchors and --anchor-stiffness need sensor "
                            "muscles (--sensor-muscles off turns them off)");
    if (args.has("muscles-max-time-s"))
      throw mme::InputError("--muscles-max-time-s needs sensor muscles (--sensor-muscles off turns "
                            "them off)");
    return;
  }
  if (c->compare && (asked || muscle_options_given || args.has("muscles-max-time-s")))
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
  parseSensorMuscleOptions(args, &c);  // after c.compare: it turns the default off
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

// ------------------------------------------------------------------ interruption and heartbeat

/// Ctrl-C / SIGTERM. Before the passive model is written the first signal raises the pipeline's
/// cancel flag (every step ends with its best so far and the model is written); once it is
/// written (the sensor muscles run), or at a second signal, the run ends at once: the file on
/// disk is then the passive model, or nothing was promised.
std::atomic<bool> g_cancel{false};
std::atomic<int> g_signal{0};
std::atomic<bool> g_passive_written{false};
char g_out_path[1024] = "";

void writeStderr(const char* text) {
  const ssize_t ignored = write(STDERR_FILENO, text, std::strlen(text));
  (void)ignored;
}

void onInterrupt(int signo) {
  if (g_passive_written.load() || g_cancel.load()) {
    writeStderr(g_passive_written.load()
                    ? "\nidentify: interrupted: stopped at once; the passive model written before is in "
                    : "\nidentify: interrupted again: stopped at once, nothing written to ");
    writeStderr(g_out_path);
    writeStderr("\n");
    _exit(128 + signo);
  }
  g_signal.store(signo);
  g_cancel.store(true);
  writeStderr("\nidentify: interrupted: ending the step under way and writing the best model so "
              "far (Ctrl-C again to stop at once)\n");
}

void installInterruptHandlers(const std::string& out_path) {
  std::snprintf(g_out_path, sizeof(g_out_path), "%s", out_path.c_str());
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

/// When the run last printed a line, and a thread that prints a heartbeat line when a step has
/// been silent for kHeartbeatS (a structure level, an output-error fit or a muscle step can
/// run for minutes without a line of its own); silent itself with --quiet (`enabled` false).
class Heartbeat {
 public:
  static constexpr double kHeartbeatS = 15.0;
  explicit Heartbeat(bool enabled)
      : enabled_(enabled), start_(Clock::now()), last_(start_), thread_([this] { loop(); }) {}
  ~Heartbeat() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  /// A line was printed: `what` (when not empty) names the step under way.
  void printed(const std::string& what = "") {
    std::lock_guard<std::mutex> lock(mutex_);
    last_ = Clock::now();
    if (!what.empty()) step_ = what;
  }

 private:
  using Clock = std::chrono::steady_clock;
  void loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!stop_) {
      wake_.wait_for(lock, std::chrono::seconds(1));
      if (stop_) break;
      const double silent_s = std::chrono::duration<double>(Clock::now() - last_).count();
      if (!enabled_ || silent_s < kHeartbeatS) continue;
      const double total_s = std::chrono::duration<double>(Clock::now() - start_).count();
      std::printf("identify: still working (%.0f s in all, %.0f s since the last line%s%s)\n", total_s,
                  silent_s, step_.empty() ? "" : "; last: ", step_.c_str());
      std::fflush(stdout);
      last_ = Clock::now();
    }
  }
  const bool enabled_;
  Clock::time_point start_, last_;
  std::string step_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::thread thread_;
};

// ------------------------------------------------------------------ progress

/// "about 40 s left" from the generations' pace so far, capped by --max-time-s; the search may
/// stop sooner (convergence), hence "at most".
std::string timeLeft(const mme::Progress& p, int generations, double max_time_s) {
  if (p.generation <= 0) return "";
  double left_s = p.wall_time_s / p.generation * (generations - p.generation);
  if (max_time_s > 0.0) left_s = std::min(left_s, std::max(0.0, max_time_s - p.wall_time_s));
  char text[64];
  std::snprintf(text, sizeof(text), ", at most ~%.0f s left", left_s);
  return text;
}

/// The generation line: in place on a terminal (5 per second), a line every 2 s otherwise, with
/// an estimate of the time left; notices (a widened bound, ...) to stderr even with --quiet.
std::function<void(const mme::Progress&)> progressPrinter(const Command& c, Heartbeat* heartbeat) {
  const bool tty = isatty(STDOUT_FILENO);
  const bool quiet = c.quiet;
  const int generations = c.pipeline.identify.generations;
  const double max_time_s = c.pipeline.identify.max_wall_time_s;
  auto last_print_s = std::make_shared<double>(-1.0);
  return [=](const mme::Progress& p) {
    if (!p.message.empty()) {
      std::fflush(stdout);
      std::fprintf(stderr, "%sidentify: %s\n", tty && !quiet ? "\n" : "", p.message.c_str());
      heartbeat->printed();
      return;
    }
    if (quiet) return;
    const bool last = p.generation == generations;
    if (!last && p.wall_time_s - *last_print_s < (tty ? 0.2 : 2.0)) return;
    *last_print_s = p.wall_time_s;
    std::printf("%sgeneration %d/%d  evaluations %llu  cost %.6e  %.1f s%s%s", tty ? "\r" : "",
                p.generation, generations, static_cast<unsigned long long>(p.evaluations),
                p.best_cost, p.wall_time_s, timeLeft(p, generations, max_time_s).c_str(),
                tty ? "   " : "\n");
    std::fflush(stdout);
    heartbeat->printed("generation " + std::to_string(p.generation));
  };
}

/// The output error's iterations, a line every 5 s at most (a fit can run for minutes): the
/// iteration of the stage under way and the time it leaves at its pace so far (a stage may end
/// sooner, on convergence or the time limit).
std::function<void(int, int, double)> outputErrorPrinter(const Command& c, Heartbeat* heartbeat) {
  using Clock = std::chrono::steady_clock;
  auto last_print = std::make_shared<Clock::time_point>(Clock::now());
  auto stage_start_s = std::make_shared<double>(0.0);
  const bool quiet = c.quiet;
  return [=](int iteration, int max_iterations, double elapsed_s) {
    if (iteration == 1) *stage_start_s = elapsed_s;  // the pace is measured from here
    const double since_print_s = std::chrono::duration<double>(Clock::now() - *last_print).count();
    if (quiet || iteration == 1 || since_print_s < 5.0) return;
    *last_print = Clock::now();
    const double per_iteration_s = (elapsed_s - *stage_start_s) / std::max(1, iteration - 1);
    std::printf("identify: output error: iteration %d/%d, %.0f s, at most ~%.0f s left in this "
                "stage\n", iteration, max_iterations, elapsed_s,
                per_iteration_s * std::max(0, max_iterations - iteration));
    std::fflush(stdout);
    heartbeat->printed("output error iteration " + std::to_string(iteration));
  };
}

// ------------------------------------------------------------------ the model written

/// The file's identification block for `result`, with the kind of model and why in it.
mme::IdentificationInfo fileInfo(const mme::PipelineResult& result, const std::string& kind,
                                 const std::string& why) {
  mme::IdentificationInfo info = mme::identificationInfo(result.identified, result.notes);
  info.model_kind = kind;
  info.notes.push_back(kind + " model: " + why);
  return info;
}

/// Why the passive model is the answer, in words, for the closing line and the file.
std::string whyPassive(const mme::PipelineResult& result, const Command& c) {
  if (result.cancelled) return "interrupted before the sensor muscles";
  if (c.pipeline.sensor_muscles) {
    if (!result.sensor_muscles) return "sensor muscles failed on these data (see the warning above)";
    if (result.sensor_muscles->skipped) return "sensor muscles " + result.sensor_muscles->not_kept_because;
    return "sensor muscles not kept (" + result.sensor_muscles->not_kept_because + ")";
  }
  std::string why = "sensor muscles not tried (--sensor-muscles auto or 16 fits them)";
  if (result.structure) {
    // The held-out judgement the structure step already made: the chosen level against the
    // model-free guesses, 10 frames ahead.
    for (const mme::StructureCandidate& cand : result.structure->candidates) {
      if (!cand.chosen || !std::isfinite(cand.held_out_rms_m[2])) continue;
      const double cv = result.structure->guess_rms_m[0][2], ca = result.structure->guess_rms_m[1][2];
      char text[240];
      std::snprintf(text, sizeof(text), "; on the held-out frames it predicts 10 frames ahead in "
                    "%.3g mm (constant velocity %.3g mm, constant acceleration %.3g mm)%s",
                    1e3 * cand.held_out_rms_m[2], 1e3 * cv, 1e3 * ca,
                    cand.held_out_rms_m[2] > std::min(cv, ca)
                        ? ": a guess predicts better, sensor muscles may help" : "");
      why += text;
    }
  }
  return why;
}

/// The kind of the model the identification gives before sensor muscles: passive, or with the
/// muscles --add-muscles placed on its springs.
std::string baseKind(const mme::PipelineResult& result) {
  return result.muscle_types > 0 ? "placed_muscles" : "passive";
}
std::string baseKindWords(const mme::PipelineResult& result) {
  return result.muscle_types > 0 ? "a model with muscles on its springs" : "a passive model";
}

std::string modelSize(const mme::Model& model) {
  const auto count = [](size_t n, const char* one, const char* many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
  };
  return count(model.particles.size(), "particle", "particles") + ", " +
         count(model.bonds.size(), "bond", "bonds");
}

/// How the run talks while it goes: steps' lines and warnings, the structure's report kept as
/// soon as it is chosen, the identification's opening line, the generations, and the passive
/// model written as soon as it is identified.
void connectOutput(Command* c, Heartbeat* heartbeat) {
  const bool quiet = c->quiet;
  mme::PipelineOptions& p = c->pipeline;
  p.say = [quiet, heartbeat](const std::string& line) {
    if (!quiet) std::printf("identify: %s\n", line.c_str());
    std::fflush(stdout);
    heartbeat->printed(line);
  };
  p.warn = [heartbeat](const std::string& line) {
    std::fflush(stdout);
    std::fprintf(stderr, "identify: warning: %s\n", line.c_str());
    heartbeat->printed();
  };
  const std::string report_path = c->out_path + ".structure.csv";
  p.structure_chosen = [report_path, heartbeat](const mme::StructureResult& selected) {
    std::printf("%s", mme::formatStructureReport(selected).c_str());
    mme::writeFileAtomically(report_path, mme::structureReportCsv(selected));
    std::printf("identify: wrote %s\n", report_path.c_str());
    heartbeat->printed();
  };
  const Command* command = c;
  p.identification_starts = [command, heartbeat](const mme::Model& model, const mme::Trajectory& trajectory) {
    const mme::IdentifyOptions& o = command->pipeline.identify;
    std::printf("identify: %d frames x %d markers at %g Hz, %zu free parameters, population %d, "
                "preset %s (refinement %s from generation %d, every %d)\n",
                trajectory.numFrames(), trajectory.numMarkers(), model.frame_rate_hz,
                mme::freeParameters(model).size(), o.es.population, mme::presetName(command->preset),
                mme::refineAlgorithmName(o.es.refine_algorithm), o.es.refine_start_generation,
                o.es.refine_period);
    if (o.islands.islands > 1)
      std::printf("identify: %d islands of population %d %s (migration every %d "
                  "generations, %d migrant(s) each, %s)\n",
                  o.islands.islands, o.es.population,
                  o.islands.processes ? "in processes of their own" : "in this process",
                  o.islands.migration_period_generations,
                  o.islands.migrants, mme::migrationTopologyName(o.islands.topology));
    heartbeat->printed("the passive identification");
  };
  p.passive_identified = [command, heartbeat](const mme::PipelineResult& result) {
    mme::IdentificationInfo info = fileInfo(result, baseKind(result), result.cancelled
                                                                   ? "interrupted: the best so far"
                                                                   : "identified, sensor muscles not (yet) fitted");
    mme::writeModelFile(command->out_path, result.model, &info);
    g_passive_written.store(true);
    if (command->pipeline.sensor_muscles && !result.cancelled) {
      std::printf("identify: wrote %s (%s) to %s; the sensor muscles replace it if they predict "
                  "better (Ctrl-C keeps it)\n", baseKindWords(result).c_str(),
                  modelSize(result.model).c_str(), command->out_path.c_str());
      heartbeat->printed("the sensor muscles");
    }
  };
  p.progress = progressPrinter(*c, heartbeat);
  p.identify.output_error.progress = outputErrorPrinter(*c, heartbeat);
  p.cancel = &g_cancel;
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
  if (r.island_evaluations.size() > 1) {
    std::printf("islands: %zu, %d migration(s), best island %d; per island evaluations "
                "(immigrants accepted):", r.island_evaluations.size(), r.migrations, r.best_island);
    for (size_t i = 0; i < r.island_evaluations.size(); ++i)
      std::printf(" %llu (%llu)", static_cast<unsigned long long>(r.island_evaluations[i]),
                  static_cast<unsigned long long>(r.island_immigrants_accepted[i]));
    std::printf("\n");
  }
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


/// The frames used, both ways: --first-frame counts the file's frames from 0, while a file's own
/// frame numbers (a TRC's Frame# column) often start at 1.
void printFramesUsed(const mme::CliArgs& args, const mme::Trajectory& data, const mme::Trajectory& used) {
  const long first = args.getInt("first-frame", 0, 0, 100000000);
  const long last = first + used.numFrames() - 1;
  std::printf("identify: frames %ld..%ld of %d used (counted from 0)%s\n", first, last, data.numFrames(),
              mme::fileFrameNumbers(data, first, last).c_str());
}

/// What to do with the written model: judge it on the frames after the ones used (when the
/// file has more), and see it in rviz.
std::string nextSteps(const mme::CliArgs& args, const Command& c, const mme::Trajectory& data,
                      const mme::Trajectory& used) {
  const long after = args.getInt("first-frame", 0, 0, 100000000) + used.numFrames();
  std::string judge;
  if (after + 10 < data.numFrames())
    judge = "judge it on frames it did not see: evaluate --model " + c.out_path + " --trajectory " +
            c.trajectory_path + " --first-frame " + std::to_string(after) + " --history 20; ";
  else
    judge = "(every frame of the file was used: identify on fewer, --frames N, to keep some for "
            "evaluate) ";
  return "identify: next: " + judge + "see it in rviz: " + mme::rvizCommand(c.out_path, c.trajectory_path);
}

/// The closing lines: which kind of model was written and why, and what to do next; the exit
/// code (128 + the signal when interrupted).
int finish(const mme::PipelineResult& result, const Command& c, const std::string& next) {
  const bool muscles_kept = result.sensor_muscles && result.sensor_muscles->better_than_passive &&
                            !result.sensor_muscle_summary.empty() && !result.cancelled;
  if (muscles_kept) {
    const mme::SensorMuscleResult& sm = *result.sensor_muscles;
    char why[200];
    std::snprintf(why, sizeof(why), "they predict %d frames ahead in %.3g mm against %.3g mm passive",
                  c.pipeline.sensor_muscles->horizon_frames, 1e3 * sm.validation_rms_m, 1e3 * sm.passive_rms_m);
    const mme::IdentificationInfo info = fileInfo(result, "sensor_muscles", why);
    mme::writeModelFile(c.out_path, result.model, &info);
    std::printf("identify: wrote sensor muscles (%d sensors, %d muscles; %s) to %s: %s\n", sm.sensors,
                sm.muscles, modelSize(result.model).c_str(), c.out_path.c_str(), why);
  } else {
    const std::string why = whyPassive(result, c);
    const mme::IdentificationInfo info = fileInfo(result, baseKind(result), why);
    mme::writeModelFile(c.out_path, result.model, &info);
    std::printf("identify: wrote %s (%s) to %s: %s\n", baseKindWords(result).c_str(),
                modelSize(result.model).c_str(), c.out_path.c_str(), why.c_str());
  }
  if (!c.quiet) std::printf("%s\n", next.c_str());
  if (!result.cancelled) return 0;
  std::printf("identify: interrupted: %s holds the best model found before the interruption "
              "(exit %d)\n", c.out_path.c_str(), 128 + g_signal.load());
  return 128 + g_signal.load();
}

int run(int argc, char** argv) {
  const mme::CliSpec spec = mme::identifyCliSpec();
  if (mme::printHelpIfAsked(argc, argv, spec)) return 0;
  const mme::CliArgs args(argc, argv, spec);
  Command c = parseCommand(args);
  Heartbeat heartbeat(!c.quiet);
  connectOutput(&c, &heartbeat);

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
  printFramesUsed(args, data, trajectory);

  installInterruptHandlers(c.out_path);
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
  return finish(result, c, nextSteps(args, c, data, trajectory));
}

}  // namespace

int main(int argc, char** argv) {
  mme::registerToolFormats();
  return mme::runTool("identify", run, argc, argv);
}

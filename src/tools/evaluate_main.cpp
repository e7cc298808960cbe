// evaluate: how well a model predicts a trajectory K frames ahead, open loop, next to three
// guesses that need no model (the held-out judge of identification and structure choices).
#include <algorithm>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "cli_args.h"
#include "tool_formats.h"
#include "trajectory_input.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"
#include "motion_model_estimation/io/model_yaml.h"

namespace {

mme::CliSpec evaluateCliSpec() {
  mme::CliSpec s;
  s.tool = "evaluate";
  s.synopsis = "--model M.yaml --trajectory FILE(.trc|.c3d|.bag) [options]";
  s.purpose =
      "How well a model predicts a capture K frames ahead, open loop from every frame, next to "
      "three guesses that need no model (constant velocity, constant acceleration, gravity "
      "only): the held-out judge of an identified model. A model that loses to a guess "
      "explains less than the markers' own motion.";
  s.groups = {
      {"Input",
       {{"model", "M.yaml", "", "An identified model, every free parameter with a value (required)."},
        {"trajectory", "FILE", "", "The capture: TRC, C3D or bag (required)."},
        {"topic", "T", "the bag's only MarkerFrame topic", "The bag topic to read."}}},
      {"Frames",
       {{"first-frame", "F", "0",
         "The first frame judged, counted from 0 (not by the file's Frame# column, which often starts at 1)."},
        {"frames", "N", "every frame from --first-frame on", "How many frames to judge."},
        {"history", "H", "0",
         "The H frames before --first-frame are read as history: no prediction starts there, "
         "but they place a marker hidden at a start (e.g. the frames the model was fitted on)."},
        {"horizons", "LIST", "1,5,10", "Comma-separated prediction horizons [frames]."}}},
      {"Output",
       {{"csv", "OUT.csv", "none", "Also write the table as CSV (columns horizon,predictor,rms_m)."}}},
  };
  s.examples = {
      "evaluate --model capture_model.yaml --trajectory capture.trc",
      "evaluate --model arm_id.yaml --trajectory arm.trc --first-frame 600 --history 100 --horizons 1,10,50 --csv arm.csv",
  };
  s.next_step =
      "simulate --model M.yaml --frames N --out play.trc plays the model; a model that loses to a "
      "guess may need --select-structure or sensor muscles (identify --help).";
  return s;
}

/// One line per horizon at which a guess that needs no model predicts better than the model
/// (empty: the model wins everywhere): the model then does not capture the motion.
std::vector<std::string> modelLosesWarnings(const mme::PredictionReport& report) {
  std::vector<std::string> lines;
  for (const mme::PredictionError& model : report.rows) {
    if (model.predictor != mme::Predictor::kModel) continue;
    std::string beaten_by;
    for (const mme::PredictionError& guess : report.rows) {
      if (guess.horizon != model.horizon || guess.predictor == mme::Predictor::kModel ||
          !(guess.rms_m < model.rms_m))
        continue;
      char part[96];
      std::snprintf(part, sizeof(part), "%s%s %.3g mm", beaten_by.empty() ? "" : ", ",
                    mme::predictorName(guess.predictor), guess.rms_m * 1e3);
      beaten_by += part;
    }
    if (beaten_by.empty()) continue;
    char line[512];
    std::snprintf(line, sizeof(line),
                  "%d frame(s) ahead the model (%.3g mm) predicts worse than a guess that needs no "
                  "model (%s): it does not capture this motion (another structure, sensor muscles, "
                  "or a model identified on this capture may)",
                  model.horizon, model.rms_m * 1e3, beaten_by.c_str());
    lines.push_back(line);
  }
  return lines;
}

int run(int argc, char** argv) {
  const mme::CliSpec spec = evaluateCliSpec();
  if (mme::printHelpIfAsked(argc, argv, spec)) return 0;
  const mme::CliArgs args(argc, argv, spec);
  for (const char* required : {"model", "trajectory"})
    if (!args.has(required)) throw mme::InputError(std::string("--") + required + " is required");
  const std::vector<int> horizons = mme::parseCountList(args.get("horizons", "1,5,10"), "--horizons", 100000, "1,5,10");
  const std::string model_path = args.get("model");
  mme::Model model = mme::loadModelFile(model_path);
  if (model.particles.empty())
    throw mme::InputError(model_path + ": the model has no particles: nothing to evaluate");
  for (const mme::ParamRef& ref : mme::freeParameters(model))
    if (!mme::paramOf(model, ref).has_value)
      throw mme::InputError(model_path + ": free parameter '" + ref.name +
                            "' has no value (evaluate needs an identified model, e.g. identify's --out)");
  const int history = static_cast<int>(args.getInt("history", 0, 0, 100000000));
  int history_kept = 0;
  int model_only = 0;
  const mme::Trajectory trajectory =
      mme::loadModelTrajectory("evaluate", args.get("trajectory"), args.get("topic"), args, &model,
                               history, &history_kept, &model_only);
  mme::PredictionReport report;
  try {
    report = mme::evaluatePredictions(model, trajectory, horizons, 10.0, std::max(history_kept, 2));
  } catch (const mme::InputError& e) {
    if (history_kept > 0 || args.getInt("first-frame", 0, 0, 100000000) == 0) throw;
    throw mme::InputError(std::string(e.what()) +
                          " (--history H reads the H frames before --first-frame to place them)");
  }

  // The model's particles without a marker in the file (anchors) are no markers of the capture.
  const std::string points_of_the_model_only =
      model_only > 0 ? " (and " + std::to_string(model_only) +
                           " fixed particle(s) of the model without a marker, e.g. anchors)"
                     : "";
  std::printf("evaluate: %d frames x %d markers%s at %g Hz (%d of them history), %d prediction "
              "starts (%ld particle starts filled from their neighbours)\n",
              trajectory.numFrames(), trajectory.numMarkers() - model_only,
              points_of_the_model_only.c_str(), model.frame_rate_hz, history_kept, report.starts,
              report.filled);
  std::printf("%-8s %-22s %14s %10s\n", "horizon", "predictor", "rms_m", "samples");
  std::ostringstream csv;
  csv << "horizon,predictor,rms_m\n";
  for (const mme::PredictionError& row : report.rows) {
    std::printf("%-8d %-22s %14.6g %10ld\n", row.horizon, mme::predictorName(row.predictor),
                row.rms_m, row.samples);
    char line[96];
    std::snprintf(line, sizeof(line), "%d,%s,%.9g\n", row.horizon, mme::predictorName(row.predictor), row.rms_m);
    csv << line;
  }
  std::printf("rollout of %d frames from the first start: %s\n", report.rollout_frames,
              report.rollout_bounded ? "bounded" : "UNBOUNDED (the model blows up or drifts away)");
  std::fflush(stdout);  // the warnings come after the table, never inside it
  for (const std::string& line : modelLosesWarnings(report))
    std::fprintf(stderr, "evaluate: warning: %s\n", line.c_str());
  if (args.has("csv")) {
    mme::writeFileAtomically(args.get("csv"), csv.str());
    std::printf("evaluate: wrote %s\n", args.get("csv").c_str());
  }
  std::printf("evaluate: next: see it in rviz: %s\n",
              mme::rvizCommand(model_path, args.get("trajectory")).c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mme::registerToolFormats();
  return mme::runTool("evaluate", run, argc, argv);
}

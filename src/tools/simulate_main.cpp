// simulate: writes the trajectory of a model file or built-in scene as TRC or bag (SPEC 7).
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "cli_args.h"
#include "tool_formats.h"
#include "trajectory_input.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/pipeline/identify_pipeline.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace {

/// Marker noise of 1 cm or more is no capture system's: most likely millimetres given as metres.
constexpr double kImplausibleNoise_m = 0.01;

/// The model's initial state from frame --start-frame of the capture --trajectory (its markers
/// matched to the particles by name; a particle without a marker keeps the model's state).
void startFromCapture(const mme::CliArgs& args, mme::Model* model) {
  const std::string path = args.get("trajectory");
  const mme::Trajectory data = mme::readToolTrajectory("simulate", path, args.get("trajectory-topic"));
  std::vector<std::string> names, missing;
  for (const mme::Particle& p : model->particles) names.push_back(p.name);
  const mme::Trajectory matched = mme::remapMarkers(data, names, &missing);
  if (missing.size() == names.size())
    throw mme::InputError(path + ": none of the model's particles is a marker of the capture");
  const int frame = static_cast<int>(args.getInt("start-frame", 0, 0, matched.numFrames() - 1));
  mme::startAtFrame(matched, frame, model);
  std::printf("simulate: starting from frame %d of %s (counted from 0%s), %zu of %zu particles "
              "placed from it\n", frame, path.c_str(), mme::fileFrameNumbers(data, frame, frame).c_str(),
              names.size() - missing.size(), names.size());
}

mme::CliSpec simulateCliSpec() {
  mme::CliSpec s;
  s.tool = "simulate";
  s.synopsis = "(--model M.yaml | --scene NAME) --out FILE(.trc|.bag) [options]";
  s.purpose =
      "Plays a model file or a built-in scene forward and writes the markers' trajectory, with "
      "optional noise: test data with a known answer, or what an identified model does from "
      "the particles' initial state in the file (identify writes its first used frame) or from "
      "a frame of a capture (--trajectory, --start-frame).";
  s.groups = {
      {"Model",
       {{"model", "M.yaml", "none (give --model or --scene)", "The model file to play (every free parameter needs a value)."},
        {"scene", "NAME", "none (give --model or --scene)", "A built-in scene instead (e.g. paper_object; see docs/scenes.md)."},
        {"trajectory", "FILE", "none",
         "A capture (TRC, C3D or bag) whose frame --start-frame gives the initial state: each "
         "particle seen there starts at its marker's position, with the velocity that lands one "
         "simulated frame on the next frame."},
        {"trajectory-topic", "T", "the bag's only MarkerFrame topic", "The bag topic of --trajectory."},
        {"start-frame", "F", "0",
         "The frame of --trajectory to start from, counted from 0 (not by the file's Frame# column, which often starts at 1)."}}},
      {"Output",
       {{"out", "FILE", "", "The trajectory to write: .trc or .bag (required)."},
        {"frames", "N", "100 (a scene: its own length)", "Frames to write."},
        {"rate-hz", "HZ", "the model's frame_rate_hz", "Frame rate [Hz]."},
        {"noise-std", "METRES", "0", "Gaussian noise added to every coordinate [m, whatever --units says: 0.0001 is 0.1 mm]."},
        {"seed", "S", "1", "Seed of the noise."},
        {"units", "mm|cm|m", "mm", "Units of a TRC output."},
        {"topic", "T", "markers", "Topic of a bag output."},
        {"truth-out", "TRUTH.yaml", "none", "Also write the model played (its values are the truth)."},
        {"model-out", "MODEL.yaml", "none",
         "Also write the model as identification should get it: free values removed."}}},
  };
  s.examples = {
      "simulate --scene paper_object --frames 200 --noise-std 0.001 --out object.trc --model-out object_free.yaml",
      "simulate --model identified.yaml --frames 500 --out play.trc",
      "simulate --model identified.yaml --trajectory capture.trc --start-frame 300 --frames 100 --out play.trc",
  };
  s.next_step =
      "identify --model MODEL.yaml --trajectory FILE --out id.yaml identifies the written data; "
      "evaluate --model M.yaml --trajectory FILE compares a model with them.";
  return s;
}

int run(int argc, char** argv) {
  const mme::CliSpec spec = simulateCliSpec();
  if (mme::printHelpIfAsked(argc, argv, spec)) return 0;
  const mme::CliArgs args(argc, argv, spec);
  if (args.has("model") == args.has("scene"))
    throw mme::InputError("give exactly one of --model or --scene");
  if (!args.has("out")) throw mme::InputError("--out is required");
  mme::Model model;
  int default_frames = 100;
  if (args.has("model")) {
    model = mme::loadModelFile(args.get("model"));
    if (model.particles.empty())
      throw mme::InputError(args.get("model") + ": the model has no particles: nothing to simulate");
  } else {
    mme::Scene scene = mme::makeScene(args.get("scene"));
    model = scene.model;
    default_frames = scene.default_frames;
  }
  for (const mme::ParamRef& ref : mme::freeParameters(model)) {
    const mme::Param& p = mme::paramOf(model, ref);
    if (!p.has_value)
      throw mme::InputError(args.get("model") + ": free parameter '" + ref.name +
                            "' has no value to simulate with");
  }
  const int frames = static_cast<int>(args.getInt("frames", default_frames, 1, 10000000));
  const double rate_hz = args.getDouble("rate-hz", model.frame_rate_hz, 1e-6, 1e6);
  if (!(rate_hz > 0.0))
    throw mme::InputError("the model has no frame_rate_hz: give --rate-hz");
  model.frame_rate_hz = rate_hz;
  if (args.has("start-frame") && !args.has("trajectory"))
    throw mme::InputError("--start-frame needs --trajectory (the capture to start from)");
  if (args.has("trajectory")) startFromCapture(args, &model);
  const double noise_std_m = args.getDouble("noise-std", 0.0, 0.0, 1e3);
  // --noise-std is in metres whatever --units says: 0.1 meant as millimetres is 10 cm of noise.
  if (noise_std_m >= kImplausibleNoise_m)
    std::fprintf(stderr,
                 "simulate: warning: --noise-std %g is in metres (whatever --units): %g mm of noise "
                 "per coordinate, where a capture system's is 0.1-2 mm; for %g mm give --noise-std "
                 "%g\n",
                 noise_std_m, noise_std_m * 1e3, noise_std_m, noise_std_m * 1e-3);
  const long seed = args.getInt("seed", 1, 0, 0x7fffffffL);
  const std::string out = args.get("out");
  const std::string ext = mme::fileExtension(out);
  if (ext != ".trc" && ext != ".bag")
    throw mme::InputError(out + ": --out must end in .trc or .bag");

  const auto start = std::chrono::steady_clock::now();
  mme::Trajectory trajectory = mme::simulateTrajectory(model, frames, rate_hz);
  const std::string bad = trajectory.validate();
  if (!bad.empty())
    throw mme::InputError("the simulation diverged (" + bad +
                          "): lower the frame period or raise substeps");
  mme::addGaussianNoise(&trajectory, noise_std_m, static_cast<uint64_t>(seed));
  mme::TrajectoryWriteOptions write;
  write.topic = args.get("topic", "markers");
  write.frame_id = model.frame_id;
  write.units = args.get("units", "mm");
  mme::writeTrajectory(out, trajectory, write);
  if (args.has("truth-out")) mme::writeModelFile(args.get("truth-out"), model);
  if (args.has("model-out")) {
    mme::Model blank = model;
    for (const mme::ParamRef& ref : mme::freeParameters(blank)) {
      mme::Param& p = mme::paramOf(blank, ref);
      p.has_value = false;
    }
    mme::writeModelFile(args.get("model-out"), blank);
  }
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("simulate: %d frames x %d markers at %g Hz, noise %g m -> %s (%.3f s)\n", frames,
              trajectory.numMarkers(), rate_hz, noise_std_m, out.c_str(), wall_s);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mme::registerToolFormats();
  return mme::runTool("simulate", run, argc, argv);
}

// simulate: writes the trajectory of a model file or built-in scene as TRC or bag (SPEC 7).
#include <chrono>
#include <cstdio>
#include <iostream>

#include "cli_args.h"
#include "tool_formats.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace {

/// Marker noise of 1 cm or more is no capture system's: most likely millimetres given as metres.
constexpr double kImplausibleNoise_m = 0.01;

const char* kUsage =
    "usage: simulate (--model M.yaml | --scene NAME) --frames N --out FILE(.trc|.bag)\n"
    "                [--noise-std METRES] [--seed S] [--truth-out TRUTH.yaml]\n"
    "                [--rate-hz HZ] [--topic T] [--units mm|cm|m] [--model-out MODEL.yaml]\n"
    "--model-out writes the model as identification should get it: free values removed.\n";

int run(int argc, char** argv) {
  mme::CliArgs args(argc, argv,
                    {"model", "scene", "frames", "out", "noise-std", "seed", "truth-out",
                     "rate-hz", "topic", "units", "model-out"},
                    {"help"});
  if (args.has("help")) {
    std::cout << kUsage;
    return 0;
  }
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

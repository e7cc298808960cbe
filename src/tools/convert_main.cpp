// convert: a capture from one trajectory format to another (TRC, C3D or bag in; bag or TRC out),
// e.g. a recording made into a bag that estimator_node replays (~bag) at its real rate; and the
// particles-only model of a capture (--particles-out), what structure selection starts from.
#include <cstdio>
#include <string>

#include "cli_args.h"
#include "tool_formats.h"
#include "trajectory_input.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/structure/marker_model.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/io/trajectory_io.h"

namespace {

mme::CliSpec convertCliSpec() {
  mme::CliSpec s;
  s.tool = "convert";
  s.synopsis = "--trajectory IN(.trc|.c3d|.bag) (--out OUT(.bag|.trc) | --particles-out MODEL.yaml) [options]";
  s.purpose =
      "A capture from one trajectory format to another (frame times, frame numbers and the rate "
      "kept; gaps stay occluded samples), e.g. a recording made into a bag that estimator_node "
      "replays; and the capture's particles-only model (a particle per marker, 1 kg, free "
      "gravity), what structure selection starts from. Prints the frames, the occluded share "
      "and the observed extent [m] (a check of the units).";
  s.groups = {
      {"Input",
       {{"trajectory", "IN", "", "The capture: TRC, C3D or bag (required)."},
        {"topic", "T", "the bag's only MarkerFrame topic", "The input bag's topic."},
        {"first-frame", "F", "0", "The first frame kept, counted from 0 (not by the file's Frame# column, which often starts at 1)."},
        {"frames", "N", "every frame from --first-frame on", "How many frames to keep."}}},
      {"Output",
       {{"out", "OUT", "none (then --particles-out is required)", "The converted capture: .bag or .trc."},
        {"out-topic", "T", "markers", "The output bag's topic."},
        {"frame-id", "F", "world", "The output bag's frame id (and the particles model's)."},
        {"units", "mm|cm|m", "mm", "The output TRC's units."},
        {"particles-out", "MODEL.yaml", "none", "Also write the capture's particles-only model."}}},
  };
  s.examples = {
      "convert --trajectory capture.c3d --out capture.bag",
      "convert --trajectory capture.trc --particles-out capture_particles.yaml",
  };
  s.next_step =
      "identify --trajectory IN --select-structure --out model.yaml identifies a model of the "
      "capture (identify --help).";
  return s;
}

int run(int argc, char** argv) {
  const mme::CliSpec spec = convertCliSpec();
  if (mme::printHelpIfAsked(argc, argv, spec)) return 0;
  const mme::CliArgs args(argc, argv, spec);
  if (!args.has("trajectory")) throw mme::InputError("--trajectory is required");
  if (!args.has("out") && !args.has("particles-out"))
    throw mme::InputError("--out is required (or --particles-out)");
  const std::string in = args.get("trajectory");
  const std::string out = args.get("out");
  // Bad output options before the (possibly long) read.
  mme::TrajectoryWriteOptions write;
  write.topic = args.get("out-topic", "markers");
  write.frame_id = args.get("frame-id", "world");
  write.units = args.get("units", "mm");
  if (!out.empty()) {
    const std::string ext = mme::fileExtension(out);
    if (ext != ".bag" && ext != ".trc") throw mme::InputError(out + ": --out must end in .bag or .trc");
    if (ext == ".bag" && args.has("units"))
      throw mme::InputError("--units is for a TRC output (a bag holds metres)");
    if (ext == ".trc" && (args.has("out-topic") || args.has("frame-id")))
      throw mme::InputError("--out-topic and --frame-id are for a bag output");
    if (write.units != "mm" && write.units != "cm" && write.units != "m")
      throw mme::InputError("--units '" + write.units + "' is unknown (mm, cm or m)");
    if (write.topic.empty() || write.frame_id.empty())
      throw mme::InputError("--out-topic and --frame-id cannot be empty");
  }

  mme::Trajectory data = mme::readToolTrajectory("convert", in, args.get("topic"));
  const int total = data.numFrames();
  const int first = static_cast<int>(args.getInt("first-frame", 0, 0, total - 1));
  const int count = static_cast<int>(args.getInt("frames", total - first, 1, total - first));
  data = mme::sliceFrames(data, first, count);

  const size_t samples = static_cast<size_t>(data.numFrames()) * data.numMarkers();
  const size_t occluded = data.countOccluded();
  std::printf("convert: %s: %d frames x %d markers at %g Hz, times %.6g .. %.6g s, %zu of %zu "
              "samples occluded (%.1f %%)\n",
              in.c_str(), data.numFrames(), data.numMarkers(), data.frame_rate_hz, data.times_s.front(),
              data.times_s.back(), occluded, samples, samples ? 100.0 * occluded / samples : 0.0);
  Eigen::Vector3d lo, hi;
  if (mme::observedBounds(data, &lo, &hi))
    std::printf("convert: observed extent [m]: x %.4f %.4f y %.4f %.4f z %.4f %.4f\n", lo.x(), hi.x(),
                lo.y(), hi.y(), lo.z(), hi.z());
  else
    std::printf("convert: warning: no observed sample (every sample occluded)\n");

  if (!out.empty()) {
    mme::writeTrajectory(out, data, write);
    if (mme::fileExtension(out) == ".bag")
      std::printf("convert: wrote %s (topic '%s', frame '%s')\n", out.c_str(), write.topic.c_str(),
                  write.frame_id.c_str());
    else
      std::printf("convert: wrote %s (%s)\n", out.c_str(), write.units.c_str());
  }
  if (args.has("particles-out")) {
    mme::Model particles = mme::markerModel(data);
    particles.frame_id = write.frame_id;
    mme::writeModelFile(args.get("particles-out"), particles);
    std::printf("convert: wrote %s (%zu particles, free gravity, no bonds)\n",
                args.get("particles-out").c_str(), particles.particles.size());
  }
  std::printf("convert: next: a model of the capture: identify --select-structure --trajectory %s "
              "--out MODEL.yaml\n", mme::absolutePath(in).c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mme::registerToolFormats();
  return mme::runTool("convert", run, argc, argv);
}

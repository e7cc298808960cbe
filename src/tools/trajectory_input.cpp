#include "trajectory_input.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/trajectory_io.h"

namespace mme {

namespace {

/// "a, b, c" (the first 60, then how many more): both sides of a name mismatch in one line.
std::string nameList(const std::vector<std::string>& names) {
  const size_t shown = std::min<size_t>(names.size(), 60);
  std::string out;
  for (size_t k = 0; k < shown; ++k) out += (k > 0 ? ", " : "") + names[k];
  if (names.empty()) out = "none";
  if (shown < names.size()) out += " and " + std::to_string(names.size() - shown) + " more";
  return out;
}

}  // namespace

std::string fileFrameNumbers(const Trajectory& data, long first, long last) {
  if (first < 0 || last < first || static_cast<size_t>(last) >= data.frame_numbers.size()) return "";
  const unsigned long a = data.frame_numbers[first], b = data.frame_numbers[last];
  return "; the file's Frame# " + std::to_string(a) + (a == b ? "" : ".." + std::to_string(b));
}

Trajectory readToolTrajectory(const char* tool, const std::string& path, const std::string& topic) {
  std::vector<std::string> warnings;
  Trajectory data = readTrajectory(path, topic, &warnings);
  for (const std::string& warning : warnings) std::fprintf(stderr, "%s: warning: %s\n", tool, warning.c_str());
  return data;
}

Trajectory loadModelTrajectory(const char* tool, const std::string& path, const std::string& topic,
                               const CliArgs& args, Model* model, int history, int* history_kept,
                               int* model_only) {
  return fitTrajectoryToModel(tool, path, readToolTrajectory(tool, path, topic), args, model, history,
                              history_kept, model_only);
}

Trajectory fitTrajectoryToModel(const char* tool, const std::string& path, const Trajectory& data,
                                const CliArgs& args, Model* model, int history, int* history_kept,
                                int* model_only) {
  std::vector<std::string> names;
  for (const Particle& p : model->particles) names.push_back(p.name);
  std::vector<std::string> missing;
  Trajectory trajectory = remapMarkers(data, names, &missing);
  // A fixed particle needs no marker (it stays where the model holds it: sensor muscles'
  // anchors, a ground point); a free one does.
  std::vector<std::string> missing_free;
  for (const std::string& name : missing)
    if (!model->particles[model->particleIndex(name)].fixed) missing_free.push_back(name);
  if (!missing_free.empty())
    throw InputError(path + ": marker '" + missing_free[0] + "' of the model is not in the trajectory (" +
                     std::to_string(missing_free.size()) + " missing: " + nameList(missing_free) +
                     "); the file's markers: " + nameList(data.marker_names) +
                     "; the model's particles: " + nameList(names) +
                     " (a model file's particle names must be the capture's marker names)");
  if (model_only) *model_only = static_cast<int>(missing.size());
  const int total = trajectory.numFrames();
  const int first = static_cast<int>(args.getInt("first-frame", 0, 0, total - 1));
  // More frames than the file holds after --first-frame: all of them, said (a README command
  // written for long captures still runs on a short one).
  long count = args.getInt("frames", total - first, 1, 100000000);
  if (count > total - first) {
    std::printf("%s: --frames %ld: %s has %d frames from frame %d on; all %d used\n", tool, count,
                path.c_str(), total - first, first, total - first);
    count = total - first;
  }
  if (args.has("window-frames"))
    count = std::min<long>(count, args.getInt("window-frames", count, 1, 100000000));
  const int before = std::min(std::max(history, 0), first);
  if (history_kept) *history_kept = before;
  trajectory = sliceFrames(trajectory, first - before, static_cast<int>(count) + before);
  if (model->frame_rate_hz <= 0.0) model->frame_rate_hz = trajectory.frame_rate_hz;
  if (!(model->frame_rate_hz > 0.0)) throw InputError(path + ": no frame rate in the data or the model");
  if (trajectory.frame_rate_hz > 0 &&
      std::abs(trajectory.frame_rate_hz - model->frame_rate_hz) > 1e-6 * model->frame_rate_hz)
    std::fprintf(stderr, "%s: warning: data at %g Hz, model at %g Hz; using the model's\n", tool,
                 trajectory.frame_rate_hz, model->frame_rate_hz);
  return trajectory;
}

}  // namespace mme

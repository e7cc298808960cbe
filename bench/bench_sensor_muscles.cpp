// The sensor-muscle step alone, on a passive model and a capture: its wall time, its size
// (sensors, muscles, parameters, fitted samples) and how it predicts its validation frames.
//
//   bench_sensor_muscles --model PASSIVE.yaml --trajectory FILE [--first-frame F] [--frames N]
//                        [--sensors S] [--force] [--select] [--held-out] [--quiet]
//   bench_sensor_muscles --random-object [--force] [--quiet]
//
// --random-object: the noiseless 18-marker random object (scenes/random_object.h), 300 frames
// simulated, its true model as the passive one, the first 240 frames fitted. --force: the search
// runs even where the gain gate would skip it (SensorMuscleOptions::skip_without_gain off).
// PASSIVE.yaml is a passive model of FILE's markers (e.g. what identify writes before its muscle
// step); the frames are those identify fitted. --select: with the grouped selection of muscles
// and sensors (SensorMuscleOptions::select_groups, off by default; --no-select: off). --held-out: the written model and
// the passive one also predict 10 frames ahead on the recording's frames after the fitted ones
// (at most 1400, the fitted ones as history), as bench_paper's stages judge them. Prints the
// muscle step's progress lines (each with the seconds since the step started), then one line "muscles_s=... parameters=... samples=... kept=..."
// to compare builds in the same run.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/scenes/random_object.h"

namespace {

struct Args {
  std::string model, trajectory;
  int first_frame = 0, frames = -1, sensors = 16;
  bool quiet = false, force = false, random_object = false, no_select = false, select = false, held_out = false;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int k = 1; k < argc; ++k) {
    const std::string key = argv[k];
    const auto value = [&]() -> std::string {
      if (k + 1 >= argc) throw std::runtime_error(key + " needs a value");
      return argv[++k];
    };
    if (key == "--model") a.model = value();
    else if (key == "--trajectory") a.trajectory = value();
    else if (key == "--first-frame") a.first_frame = std::atoi(value().c_str());
    else if (key == "--frames") a.frames = std::atoi(value().c_str());
    else if (key == "--sensors") a.sensors = std::atoi(value().c_str());
    else if (key == "--quiet") a.quiet = true;
    else if (key == "--force") a.force = true;
    else if (key == "--no-select") a.no_select = true;
    else if (key == "--select") a.select = true;
    else if (key == "--held-out") a.held_out = true;
    else if (key == "--random-object") a.random_object = true;
    else throw std::runtime_error("unknown option " + key);
  }
  if (!a.random_object && (a.model.empty() || a.trajectory.empty())) throw std::runtime_error("--model and --trajectory are required");
  return a;
}

/// `model`'s RMS error 10 frames ahead [m] on `whole` from frame `first_start` on.
double heldOutRmsM(const mme::Model& model, const mme::Trajectory& whole, int first_start) {
  std::vector<std::string> names;
  for (const mme::Particle& p : model.particles) names.push_back(p.name);
  const mme::PredictionReport report =
      mme::evaluatePredictions(model, mme::remapMarkers(whole, names, nullptr), {10}, 10.0, first_start);
  for (const mme::PredictionError& row : report.rows)
    if (row.predictor == mme::Predictor::kModel) return row.rms_m;
  return NAN;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Args a = parse(argc, argv);
    mme::Model passive;
    mme::Trajectory data, whole;
    if (a.random_object) {
      passive = mme::makeRandomObject(mme::RandomObjectSpec());
      data = mme::sliceFrames(mme::simulateTrajectory(passive, 300, passive.frame_rate_hz), 0, 240);
    } else {
      passive = mme::loadModelFile(a.model);
      data = mme::readTrajectoryFile(a.trajectory);
      const int frames = a.frames > 0 ? a.frames : data.numFrames() - a.first_frame;
      whole = mme::sliceFrames(data, a.first_frame, std::min(data.numFrames() - a.first_frame, frames + 1400));
      data = mme::sliceFrames(data, a.first_frame, frames);
    }
    std::vector<std::string> names, missing;
    for (const mme::Particle& p : passive.particles) names.push_back(p.name);
    data = mme::remapMarkers(data, names, &missing);
    mme::SensorMuscleOptions o;
    o.sensors = a.sensors;
    o.skip_without_gain = !a.force;
    o.select_groups = a.select && !a.no_select;
    // Each progress line with the seconds since the step started: where the time goes.
    const auto start = std::chrono::steady_clock::now();
    if (!a.quiet)
      o.progress = [start](const std::string& line) {
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("[%7.1f s] %s\n", s, line.c_str());
        std::fflush(stdout);
      };
    const mme::SensorMuscleResult r = mme::addSensorMuscles(passive, data, o);
    std::printf("muscles_s=%.2f sensors=%d muscles=%d parameters=%zu selected_sensors=%d selected_muscles=%d "
                "selected_parameters=%zu samples=%zu validation_mm=%.3f "
                "passive_mm=%.3f constant_velocity_mm=%.3f kept=%d why=\"%s\"\n",
                r.wall_time_s, r.sensors, r.muscles, r.unknowns, r.selected_sensors, r.selected_muscles,
                r.selected_parameters, r.rows, 1e3 * r.validation_rms_m,
                1e3 * r.passive_rms_m, 1e3 * r.constant_velocity_rms_m, r.better_than_passive ? 1 : 0,
                r.not_kept_because.c_str());
    if (a.held_out && whole.numFrames() > data.numFrames()) {
      std::printf("held_out_frames=%d held_out_mm=%.3f passive_held_out_mm=%.3f\n",
                  whole.numFrames() - data.numFrames(), 1e3 * heldOutRmsM(r.model, whole, data.numFrames()),
                  1e3 * heldOutRmsM(passive, whole, data.numFrames()));
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_sensor_muscles: %s\n", e.what());
    return 2;
  }
}

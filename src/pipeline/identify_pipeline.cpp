#include "motion_model_estimation/pipeline/identify_pipeline.h"

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/structure/marker_model.h"

namespace mme {

namespace {

void say(const PipelineOptions& options, const std::string& line) {
  if (options.say) options.say(line);
}

void warn(const PipelineOptions& options, const std::string& line) {
  if (options.warn) options.warn(line);
}

/// One line on a sensor-muscle fit: what was chosen, its size against the samples it was fitted
/// on, how it predicts, whether it is kept; or why the search did not run.
std::string sensorMuscleSummary(const SensorMuscleResult& sm, const SensorMuscleOptions& options) {
  char line[800];
  if (sm.skipped || sm.chosen < 0) {
    std::snprintf(line, sizeof(line), "sensor muscles: %s (%.1f s)", sm.not_kept_because.c_str(),
                  sm.wall_time_s);
    return line;
  }
  // After the grouped selection: the parameters left, and what it kept of the layout.
  char selected[160] = "";
  const bool pruned = sm.selected_muscles < sm.muscles || sm.selected_sensors < sm.sensors;
  if (pruned)
    std::snprintf(selected, sizeof(selected), " (the layout's %zu before the grouped selection, which kept %d "
                  "sensors and %d muscles)", sm.unknowns, sm.selected_sensors, sm.selected_muscles);
  std::snprintf(line, sizeof(line),
                "sensor muscles: %d sensors, %d muscles, ridge %.0e, %zu parameters on %zu samples%s, "
                "%d rollout round(s), activation time constant %.3g s, %s anchors; %d frames ahead on "
                "the last frames %.3g m (passive %.3g m, constant velocity %.3g m), %.0f s%s%s%s",
                sm.sensors, sm.muscles, sm.ridge,
                pruned ? sm.selected_parameters : sm.unknowns, sm.rows, selected,
                sm.candidates[sm.chosen].rollout_rounds,
                sm.activation_time_s, sm.anchors ? "with" : "without", options.horizon_frames,
                sm.validation_rms_m, sm.passive_rms_m, sm.constant_velocity_rms_m, sm.wall_time_s,
                sm.stopped_by_time ? " (stopped by --muscles-max-time-s: fewer candidates judged)" : "",
                !sm.anchors ? ""
                : sm.anchor_stiffness ? "; the anchor muscles with a stiffness of their own"
                                      : "; the anchor muscles without a stiffness of their own",
                sm.better_than_passive ? "" : ": not better than the passive model, which is kept");
  return line;
}

}  // namespace

std::string validateOptions(const PipelineOptions& options) {
  std::string bad = validateOptions(options.identify);
  if (!bad.empty()) return bad;
  if (options.muscles) {
    if (options.muscles->inputs < 0 || options.muscles->inputs > kMaxMuscleInputs)
      return "muscles: inputs must be 0.." + std::to_string(kMaxMuscleInputs);
    if (options.muscles->hidden < 0 || options.muscles->hidden > kMaxMuscleHidden)
      return "muscles: hidden units must be 0.." + std::to_string(kMaxMuscleHidden);
  }
  if (options.sensor_muscles &&
      (options.sensor_muscles->sensors < 1 || options.sensor_muscles->sensors > kMaxMuscleInputs))
    return "sensor muscles: sensors must be 1.." + std::to_string(kMaxMuscleInputs);
  return "";
}

Model startingModel(const Trajectory& data) { return markerModel(data); }

StructureResult chooseStructure(const Model& model, const Trajectory& trajectory,
                                const PipelineOptions& options,
                                std::function<void(const StructureCandidate&)> on_first_level) {
  StructureOptions so;
  so.identify = options.identify;
  so.max_wall_time_s = options.identify.max_wall_time_s;
  so.progress = options.say;
  so.on_first_level = std::move(on_first_level);
  return selectStructure(model, trajectory, so);
}

Model placeMuscles(const Model& model, const Trajectory& trajectory, const MusclePlacement& placement) {
  Model placed = addMuscles(model, &trajectory, placement);
  if (muscleTypeCount(placed) == 0)
    throw InputError("muscles: the model has no spring type that can become a muscle (plain "
                     "springs: no threshold, no cubic term, not an interaction)");
  return placed;
}

IdentifyResult identifyPassive(const Model& model, const Trajectory& trajectory,
                               const PipelineOptions& options) {
  return identifyModel(model, trajectory, options.identify, options.progress);
}

void fitSensorMuscleStep(const Trajectory& trajectory, const PipelineOptions& options,
                         PipelineResult* result) {
  // The options were checked before the run, so what fails here is the data's (too few frames,
  // no pair seen together often enough, a body too large): the passive model stays the answer,
  // with a warning, rather than the run being lost.
  SensorMuscleOptions sensor_options = *options.sensor_muscles;
  if (!sensor_options.progress) sensor_options.progress = options.say;
  sensor_options.threads = std::max(sensor_options.threads, options.identify.es.threads);
  try {
    result->sensor_muscles = addSensorMuscles(result->identified.model, trajectory, sensor_options);
  } catch (const InputError& e) {
    warn(options, std::string("no sensor muscles (") + e.what() + "): the passive model is written");
    result->notes.push_back(std::string("sensor muscles: none (") + e.what() + ")");
    return;
  }
  const SensorMuscleResult& sm = *result->sensor_muscles;
  result->sensor_muscle_summary = sensorMuscleSummary(sm, sensor_options);
  result->notes.push_back(result->sensor_muscle_summary);
  if (sm.better_than_passive)
    result->model = sm.model;
  else if (!sm.skipped)
    warn(options, "the sensor muscles are not kept (" + sm.not_kept_because +
                      "): the passive model is written");
}

void deferredOutputErrorStep(const Trajectory& trajectory, const PipelineOptions& options,
                             PipelineResult* result) {
  say(options, "the sensor muscles do not replace the passive model: the deferred output error runs");
  const size_t known = result->identified.notes.size();
  result->identified = runDeferredOutputError(result->identified, trajectory, options.identify, options.progress);
  const std::vector<std::string>& notes = result->identified.notes;
  result->notes.insert(result->notes.end(), notes.begin() + static_cast<std::ptrdiff_t>(known), notes.end());
  if (result->identified.estimator != Estimator::kOutputError) return;
  result->model = result->identified.model;
  startAtFrame(trajectory, 0, &result->model);
}

void startAtFrame(const Trajectory& trajectory, int frame, Model* model) {
  if (frame < 0 || frame >= trajectory.numFrames())
    throw InputError("start frame " + std::to_string(frame) + " is outside the data's " +
                     std::to_string(trajectory.numFrames()) + " frames (counted from 0)");
  const double rate_hz = model->frame_rate_hz > 0.0 ? model->frame_rate_hz : trajectory.frame_rate_hz;
  const int n = std::min<int>(trajectory.numMarkers(), static_cast<int>(model->particles.size()));
  std::vector<int> aimed;  // particles whose next frame is seen: their velocity lands on it
  for (int i = 0; i < n; ++i) {
    Particle& p = model->particles[i];
    if (p.fixed || trajectory.isOccluded(frame, i)) continue;
    p.position_m = trajectory.position(frame, i);
    if (frame + 1 < trajectory.numFrames() && !trajectory.isOccluded(frame + 1, i) && rate_hz > 0.0) {
      p.velocity_mps = (trajectory.position(frame + 1, i) - p.position_m) * rate_hz;
      aimed.push_back(i);
    }
  }
  if (aimed.empty() || !(rate_hz > 0.0) || !validateModel(*model).empty()) return;
  // The frame difference is not the velocity the integrator needs (semi-implicit Euler moves by
  // h (v + h a)): corrected so that one simulated frame lands on the next data frame, which then
  // makes a model that is the truth replay its data. Kept only when every correction is finite
  // (a model whose values are not all set, or one that blows up, keeps the frame difference).
  std::vector<Eigen::Vector3d> velocity_mps(aimed.size());
  for (size_t k = 0; k < aimed.size(); ++k) velocity_mps[k] = model->particles[aimed[k]].velocity_mps;
  try {
    Simulator sim(*model);
    for (int round = 0; round < 4; ++round) {
      State s = sim.initialState();
      for (size_t k = 0; k < aimed.size(); ++k) s.v_mps[aimed[k]] = velocity_mps[k];
      sim.stepFrame(&s, 1.0 / rate_hz);
      for (size_t k = 0; k < aimed.size(); ++k)
        velocity_mps[k] += (trajectory.position(frame + 1, aimed[k]) - s.x_m[aimed[k]]) * rate_hz;
    }
  } catch (const std::exception&) {
    return;
  }
  for (const Eigen::Vector3d& v : velocity_mps)
    if (!v.allFinite()) return;
  for (size_t k = 0; k < aimed.size(); ++k) model->particles[aimed[k]].velocity_mps = velocity_mps[k];
}

PredictionReport judgePredictions(const Model& model, const Trajectory& data, int first_judged_frame,
                                  int horizon_frames) {
  std::vector<std::string> names;
  names.reserve(model.particles.size());
  for (const Particle& p : model.particles) names.push_back(p.name);
  // The rollout runs 10x the judged frames: long enough to show a model that drifts away.
  return evaluatePredictions(model, remapMarkers(data, names, nullptr), {horizon_frames}, 10.0,
                             first_judged_frame);
}

PipelineResult runPipeline(const Model& model, const Trajectory& trajectory,
                           const PipelineOptions& options) {
  const std::string bad = validateOptions(options);
  if (!bad.empty()) throw InputError(bad);
  PipelineResult result;
  PipelineOptions steps = options;  // the cancel flag reaches every step through identify
  if (options.cancel) steps.identify.cancel = options.cancel;
  auto cancelled = [&options] { return options.cancel && options.cancel->load(); };
  Model current = model;
  if (options.select_structure) {
    result.structure = chooseStructure(current, trajectory, steps);
    current = result.structure->model;
    if (options.structure_chosen) options.structure_chosen(*result.structure);
  }
  if (options.muscles) {
    current = placeMuscles(current, trajectory, *options.muscles);
    result.muscle_types = muscleTypeCount(current);
    int reads = 0;
    for (const BondType& type : current.bond_types)
      if (type.kind == BondKind::kMuscle) reads = type.network_inputs;
    say(options, std::to_string(result.muscle_types) + " spring type(s) became muscles reading " +
                     std::to_string(reads) + " bond(s) each, " +
                     std::to_string(options.muscles->hidden) + " hidden unit(s)");
  }
  if (options.identification_starts) options.identification_starts(current, trajectory);
  PipelineOptions passive = steps;  // the output error waits for the muscles where it cannot pay
  passive.identify.defer_output_error_on_misfit = options.sensor_muscles && options.output_error_after_muscles;
  result.identified = identifyPassive(current, trajectory, passive);
  result.model = result.identified.model;
  startAtFrame(trajectory, 0, &result.model);
  result.notes = result.identified.notes;
  result.cancelled = cancelled();
  if (options.passive_identified) options.passive_identified(result);
  if (options.sensor_muscles && !result.cancelled) {
    fitSensorMuscleStep(trajectory, steps, &result);
    startAtFrame(trajectory, 0, &result.model);
  }
  const bool muscles_kept = result.sensor_muscles && result.sensor_muscles->better_than_passive;
  if (result.identified.output_error_deferred && !muscles_kept && !cancelled())
    deferredOutputErrorStep(trajectory, steps, &result);
  result.cancelled = cancelled();
  return result;
}

}  // namespace mme

// addSensorMuscles: the options and inputs checked, then one layout fitted (sensor_muscle_fit.h)
// or, with the anchors judged by validation, both layouts and the better one kept.
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fit_budget.h"
#include "gain_gate.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"
#include "sensor_anchors.h"
#include "sensor_muscle_fit.h"

namespace mme {

namespace {

using sensor_muscles::Budget;
using sensor_muscles::fitSensorMuscles;
using sensor_muscles::say;

/// Unknowns at most: the normal matrix is stored as its coupled blocks, but its sparse factor
/// fills in and a solve's time grows with it.
constexpr size_t kMaxUnknowns = 14000;

bool finiteAtLeast(double value, double least) { return value >= least && std::isfinite(value); }

/// The layout's options: sensors, neighbours, anchors' distance, seen share, unknowns.
void checkLayoutOptions(const SensorMuscleOptions& o) {
  if (o.sensors < 1 || o.sensors > kMaxMuscleInputs)
    throw InputError("sensor muscles: sensors must be 1.." + std::to_string(kMaxMuscleInputs) +
                     ", got " + std::to_string(o.sensors));
  if (o.neighbours < 0 || o.neighbours > 64)
    throw InputError("sensor muscles: neighbours must be 0..64, got " + std::to_string(o.neighbours));
}

/// The one-step fit's options: windows, ridges, validation, horizon, gain margin.
void checkFitOptions(const SensorMuscleOptions& o) {
  if (o.windows_frames.empty()) throw InputError("sensor muscles: no candidate window");
  for (int w : o.windows_frames)
    if (w < 1 || w > 100)
      throw InputError("sensor muscles: every window must be 1..100 frames, got " + std::to_string(w));
  if (o.ridges.empty()) throw InputError("sensor muscles: no candidate ridge");
  for (double r : o.ridges)
    if (!(r > 0.0) || !std::isfinite(r))
      throw InputError("sensor muscles: every ridge must be a finite number > 0");
  if (!(o.validation_fraction > 0.0 && o.validation_fraction < 0.5))
    throw InputError("sensor muscles: the validation fraction must be in (0, 0.5)");
  if (o.horizon_frames < 1) throw InputError("sensor muscles: the horizon must be >= 1 frame");
  if (!finiteAtLeast(o.gain_margin, 1.0))
    throw InputError("sensor muscles: the gain margin must be a finite number >= 1");
}

/// The rollout rounds' options.
void checkRolloutOptions(const SensorMuscleOptions& o) {
  if (o.rollout_rounds < 0 || o.rollout_rounds > 20)
    throw InputError("sensor muscles: rollout rounds must be 0..20, got " + std::to_string(o.rollout_rounds));
  if (o.rollout_lower_ridges < 0 || o.rollout_lower_ridges > 20)
    throw InputError("sensor muscles: rollout_lower_ridges must be 0..20, got " +
                     std::to_string(o.rollout_lower_ridges));
  if (o.rollout_stride_frames < 1)
    throw InputError("sensor muscles: the rollout stride must be >= 1 frame, got " +
                     std::to_string(o.rollout_stride_frames));
  if (!finiteAtLeast(o.rollout_correction_frames, 0.0))
    throw InputError("sensor muscles: the rollout correction time must be a finite number >= 0 frames");
}

/// The remaining options, in the order their errors are reported.
void checkOtherOptions(const SensorMuscleOptions& o) {
  if (!finiteAtLeast(o.anchor_distance_extents, 1.0))
    throw InputError("sensor muscles: the anchors' distance must be a finite number >= 1 extent");
  for (double tau_frames : o.activation_times_frames)
    if (!finiteAtLeast(tau_frames, 0.0))
      throw InputError("sensor muscles: the activation time constants must be finite numbers >= 0 "
                       "frames, got " + std::to_string(tau_frames));
  if (!(o.min_seen_share >= 0.0 && o.min_seen_share <= 1.0))
    throw InputError("sensor muscles: min_seen_share must be in [0, 1]");
  if (!finiteAtLeast(o.max_time_s, 0.0))
    throw InputError("sensor muscles: the time limit must be a finite number >= 0 s (0: none)");
  if (o.threads < 1 || o.threads > 256)
    throw InputError("sensor muscles: threads must be 1..256, got " + std::to_string(o.threads));
  if (o.max_unknowns < 1 || o.max_unknowns > kMaxUnknowns)
    throw InputError("sensor muscles: max_unknowns must be 1.." + std::to_string(kMaxUnknowns) + ", got " +
                     std::to_string(o.max_unknowns));
}

/// The passive model and the data fit each other, and every parameter has a value.
void checkModelAndData(const Model& passive, const Trajectory& data) {
  if (!(passive.frame_rate_hz > 0.0)) throw InputError("sensor muscles: the model has no frame rate");
  const int n = static_cast<int>(passive.particles.size());
  if (data.numMarkers() != n)
    throw InputError("sensor muscles: the data have " + std::to_string(data.numMarkers()) +
                     " markers, the model " + std::to_string(n) + " particles");
  for (int i = 0; i < n; ++i)
    if (data.marker_names[i] != passive.particles[i].name)
      throw InputError("sensor muscles: marker " + std::to_string(i) + " is '" + data.marker_names[i] +
                       "', the model's particle '" + passive.particles[i].name + "'");
  for (const ParamRef& ref : freeParameters(passive))
    if (!paramOf(passive, ref).has_value)
      throw InputError("sensor muscles: the passive model's '" + ref.name +
                       "' has no value (identify it first)");
}

void checkInputs(const Model& passive, const Trajectory& data, const SensorMuscleOptions& o) {
  checkLayoutOptions(o);
  checkFitOptions(o);
  checkRolloutOptions(o);
  checkOtherOptions(o);
  checkModelAndData(passive, data);
  if (!finiteAtLeast(o.selection_tolerance, 0.0))
    throw InputError("sensor muscles: the selection tolerance must be a finite number >= 0");
  if (o.selection_max_solves < 1 || o.selection_max_solves > 100)
    throw InputError("sensor muscles: selection_max_solves must be 1..100, got " +
                     std::to_string(o.selection_max_solves));
  if (!(o.travel_body_sizes > 0.0) || !std::isfinite(o.travel_body_sizes))
    throw InputError("sensor muscles: travel_body_sizes must be a finite number > 0");
}

/// The layout without anchors is kept: it predicts the validation frames better (a kept fit
/// first).
bool withoutAnchorsBetter(const SensorMuscleResult& with, const SensorMuscleResult& without,
                          const SensorMuscleOptions& o) {
  const bool plain_better =
      (without.better_than_passive && !with.better_than_passive) ||
      (without.better_than_passive == with.better_than_passive &&
       without.validation_rms_m < with.validation_rms_m);
  char line[200];
  std::snprintf(line, sizeof(line), "sensor muscles: %s anchors (validation %.2f mm, %s %.2f mm)",
                plain_better ? "without" : "with", 1e3 * (plain_better ? without : with).validation_rms_m,
                plain_better ? "with them" : "without them",
                1e3 * (plain_better ? with : without).validation_rms_m);
  say(o, line);
  return plain_better;
}

/// Both layouts, judged on the same validation frames: the anchors' extra unknowns fit noise on
/// a small body whose controller lives between its particles, and push along the world where a
/// walk's accelerations live. A layout too large to fit (max_unknowns) or without a usable fit
/// leaves the other.
SensorMuscleResult fitBothLayouts(const Model& passive, const Trajectory& data, const Model& anchored,
                                  const Trajectory& anchored_data, const std::vector<char>& anchor,
                                  const SensorMuscleOptions& o, Budget& budget) {
  std::optional<SensorMuscleResult> with, without;
  try {
    say(o, "sensor muscles: with anchors");
    with = fitSensorMuscles(anchored, anchored_data, anchor, o, budget);
    with->anchors = true;
  } catch (const InputError& e) {
    say(o, std::string("sensor muscles: with anchors: ") + e.what());
  }
  if (with && budget.stops(o, "fit without anchors (the fit with them is kept)")) return std::move(*with);
  say(o, "sensor muscles: without anchors");
  try {
    without = fitSensorMuscles(passive, data, std::vector<char>(passive.particles.size(), 0), o, budget);
  } catch (const InputError& e) {
    if (!with) throw;
    say(o, std::string("sensor muscles: without anchors: ") + e.what());
  }
  if (!with) return std::move(*without);
  if (!without) return std::move(*with);
  return withoutAnchorsBetter(*with, *without, o) ? std::move(*without) : std::move(*with);
}

/// The result of a search the gate skipped: the passive model, the reason, what was measured.
SensorMuscleResult skippedResult(const Model& passive, const sensor_muscles::GainVerdict& v) {
  SensorMuscleResult r;
  r.model = passive;
  r.skipped = true;
  r.not_kept_because = "not fitted: " + v.why_not;
  r.validation_rms_m = v.passive_rms_m;
  r.passive_rms_m = v.passive_rms_m;
  r.constant_velocity_rms_m = v.constant_velocity_rms_m;
  r.noise_m = v.noise_m;
  return r;
}

}  // namespace

SensorMuscleResult addSensorMuscles(const Model& passive, const Trajectory& data,
                                    const SensorMuscleOptions& o) {
  checkInputs(passive, data, o);
  Budget budget(o.max_time_s);
  const auto timed = [&](SensorMuscleResult r) {
    r.wall_time_s = budget.elapsedS();
    r.stopped_by_time = budget.stopped();
    return r;
  };
  double noise_m = 0.0;
  if (o.skip_without_gain) {
    const sensor_muscles::GainVerdict verdict = sensor_muscles::judgeGain(passive, data, o);
    noise_m = verdict.noise_m;
    if (!verdict.worth_fitting) {
      say(o, "sensor muscles: " + skippedResult(passive, verdict).not_kept_because);
      return timed(skippedResult(passive, verdict));
    }
  }
  const auto noted = [&](SensorMuscleResult r) {
    r.noise_m = noise_m;
    return r;
  };
  const size_t n = passive.particles.size();
  if (!o.anchors) return noted(timed(fitSensorMuscles(passive, data, std::vector<char>(n, 0), o, budget)));
  // The anchor muscles' own stiffness: kAuto decided here, once for both layouts.
  const double travel = bodyTravel(passive, data);
  const SensorMuscleOptions resolved = sensor_muscles::resolveAnchorStiffness(passive, travel, o);
  const bool anchor_stiffness = resolved.anchor_stiffness == AnchorStiffness::kFitted;
  const auto tagged = [&](SensorMuscleResult r) {
    r.anchor_stiffness = r.anchors && anchor_stiffness;
    r.body_travel = travel;
    return noted(timed(std::move(r)));
  };
  Model anchored = passive;
  Trajectory anchored_data = data;
  const std::vector<char> anchor =
      sensor_muscles::addAnchors(&anchored, &anchored_data, o.anchor_distance_extents);
  if (o.anchors_by_validation)
    return tagged(fitBothLayouts(passive, data, anchored, anchored_data, anchor, resolved, budget));
  SensorMuscleResult with = fitSensorMuscles(anchored, anchored_data, anchor, resolved, budget);
  with.anchors = true;
  return tagged(std::move(with));
}

}  // namespace mme

// Whether a sensor-muscle search can gain anything on a scene, judged before any muscle is
// placed: the muscles fit the passive model's one-step residual, so where that residual is only
// the markers' noise, or where the passive model already predicts the validation frames as well
// as a perfect model could from noisy starts, the search would only fit noise (and cost the
// whole run's time to learn so).
#pragma once

#include <string>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"

namespace mme::sensor_muscles {

/// What the gate measured and what it decided.
struct GainVerdict {
  bool worth_fitting = true;
  std::string why_not;                   ///< the reason in words when not worth fitting
  double noise_m = 0.0;                  ///< estimateMarkerNoise of the data [m]
  double prediction_floor_m = 0.0;       ///< predictionNoiseFloor at the validation horizon [m]
  double passive_rms_m = 0.0;            ///< the passive model's validation error [m]
  double constant_velocity_rms_m = 0.0;  ///< the constant-velocity guess's there [m]
  double one_step_rms_m = 0.0;           ///< the passive one-step residual per coordinate [m]
};

/// The RMS 3-D error [m] a perfect model makes `horizon_frames` ahead when it starts from
/// positions with white noise `noise_m` per coordinate and the frame difference as velocity,
/// and is compared with a noisy frame: per coordinate the start's error grows as
/// (H + 1) e_t - H e_{t-1}, plus the judged frame's own e.
double predictionNoiseFloor(double noise_m, int horizon_frames);

/// The passive model's one-step residual x(t+1) - 2 x(t) + x(t-1) - h^2 F/m, RMS per coordinate
/// over the free particles and frames where every particle is seen at t-1 and t and the
/// particle at t+1 [m] (0 when no frame qualifies). White marker noise alone gives sqrt(6) sigma.
double passiveOneStepRms(const Model& passive, const Trajectory& data);

/// The gate on checked inputs (addSensorMuscles checked them).
GainVerdict judgeGain(const Model& passive, const Trajectory& data, const SensorMuscleOptions& o);

}  // namespace mme::sensor_muscles

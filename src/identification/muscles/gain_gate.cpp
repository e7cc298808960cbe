#include "gain_gate.h"

#include <cmath>
#include <cstdio>
#include <vector>

#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "sensor_muscle_fit.h"
#include "validation_judge.h"

namespace mme::sensor_muscles {

namespace {

/// The one-step residual counts as noise up to this multiple of what white noise alone gives
/// (sqrt(6) sigma): the noise estimate is itself a median over the data, and a residual that
/// small leaves the muscles nothing they could learn from one frame to the next.
constexpr double kResidualOverNoise = 1.5;

/// Every particle seen at frame t.
bool allSeen(const Trajectory& data, int t) {
  for (int i = 0; i < data.numMarkers(); ++i)
    if (data.isOccluded(t, i)) return false;
  return true;
}

}  // namespace

double predictionNoiseFloor(double noise_m, int horizon_frames) {
  const double h = horizon_frames;
  return noise_m * std::sqrt(3.0 * ((h + 1.0) * (h + 1.0) + h * h + 1.0));
}

double passiveOneStepRms(const Model& passive, const Trajectory& data) {
  const int n = data.numMarkers();
  const double h = 1.0 / passive.frame_rate_hz;
  Simulator sim(passive);
  State state;
  std::vector<Eigen::Vector3d> forces;
  double sum2 = 0.0;
  size_t count = 0;
  for (int t = 1; t + 1 < data.numFrames(); ++t) {
    if (!allSeen(data, t - 1) || !allSeen(data, t)) continue;
    state.x_m.resize(n);
    state.v_mps.resize(n);
    for (int i = 0; i < n; ++i) {
      state.x_m[i] = data.position(t, i);
      state.v_mps[i] = (data.position(t, i) - data.position(t - 1, i)) / h;
    }
    sim.computeForces(state, &forces);
    for (int i = 0; i < n; ++i) {
      const Particle& p = passive.particles[i];
      if (p.fixed || data.isOccluded(t + 1, i)) continue;
      const Eigen::Vector3d r = data.position(t + 1, i) - 2.0 * data.position(t, i) + data.position(t - 1, i) -
                                h * h * forces[i] / p.mass_kg;
      sum2 += r.squaredNorm();
      count += 3;
    }
  }
  return count > 0 ? std::sqrt(sum2 / static_cast<double>(count)) : 0.0;
}

GainVerdict judgeGain(const Model& passive, const Trajectory& data, const SensorMuscleOptions& o) {
  GainVerdict v;
  const int validation_start = validationStart(data.numFrames(), o);
  const ValidationJudge judge(data, o.horizon_frames, validation_start);
  v.passive_rms_m = std::nan("");
  judge.judge(passive, &v.passive_rms_m, &v.constant_velocity_rms_m, nullptr);
  v.noise_m = estimateMarkerNoise(data);
  v.prediction_floor_m = predictionNoiseFloor(v.noise_m, o.horizon_frames);
  v.one_step_rms_m = passiveOneStepRms(passive, data);
  char why[320] = "";
  if (v.passive_rms_m <= v.prediction_floor_m) {
    std::snprintf(why, sizeof(why), "the passive model predicts the validation frames %d frames ahead to "
                  "%.3g m, within the %.3g m a perfect model makes from starts with the markers' noise "
                  "(%.3g m)", o.horizon_frames, v.passive_rms_m, v.prediction_floor_m, v.noise_m);
  } else if (v.one_step_rms_m <= kResidualOverNoise * std::sqrt(6.0) * v.noise_m) {
    std::snprintf(why, sizeof(why), "the passive model's one-step residual (%.3g m per coordinate) is "
                  "the markers' noise (%.3g m gives %.3g m): nothing is left for muscles to explain",
                  v.one_step_rms_m, v.noise_m, std::sqrt(6.0) * v.noise_m);
  }
  v.why_not = why;
  v.worth_fitting = v.why_not.empty();
  return v;
}

}  // namespace mme::sensor_muscles

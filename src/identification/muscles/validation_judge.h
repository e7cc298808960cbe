// How the sensor muscles are judged: open-loop predictions `horizon` frames ahead on the held-out
// last frames, against the passive model and the constant-velocity guess (docs/muscles.md,
// *Kept only when better*).
#pragma once

#include <string>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"

namespace mme::sensor_muscles {

class ValidationJudge {
 public:
  /// Judges on the frames from `validation_start` on; `data` must outlive this.
  ValidationJudge(const Trajectory& data, int horizon_frames, int validation_start);

  /// `model`'s RMS prediction error [m] horizon frames ahead on the validation frames (`rms_m`),
  /// the constant-velocity guess's (`constant_velocity_rms_m`, may be null) and whether its
  /// rollout stayed bounded (may be null). A value not reported is left as it was.
  void judge(const Model& model, double* rms_m, double* constant_velocity_rms_m, bool* bounded) const;

  /// judge() on the model `build` returns, without the constant-velocity guess; nothing is
  /// reported when building or judging it throws InputError.
  template <typename Build>
  void judgeBuilt(const Build& build, double* rms_m, bool* bounded) const;

 private:
  const Trajectory& data_;
  std::vector<int> horizons_;
  int validation_start_;
};

template <typename Build>
void ValidationJudge::judgeBuilt(const Build& build, double* rms_m, bool* bounded) const {
  try {
    judge(build(), rms_m, nullptr, bounded);
  } catch (const InputError&) {
  }
}

/// Fills result->better_than_passive and not_kept_because for the chosen fit, whose validation
/// error is in result->validation_rms_m: kept when its candidate's validation rollout and its
/// refit's rollouts stayed bounded and it is below the passive model's error by 1 % of the larger
/// of that and the constant-velocity guess's (the guess gives the motion's scale).
void decideKept(bool candidate_bounded, bool refit_bounded, size_t refits_tried, SensorMuscleResult* result);

}  // namespace mme::sensor_muscles

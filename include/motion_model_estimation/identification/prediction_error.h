// The held-out judge of a model: how well it predicts the markers K frames ahead, open loop,
// next to three guesses that need no model (constant velocity, constant acceleration from the last
// three frames, free fall under the model's gravity). A model that cannot beat an extrapolation
// has not explained the motion.
#pragma once

#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// The predictors compared, by their CSV names.
enum class Predictor { kModel, kConstantVelocity, kConstantAcceleration, kGravityOnly };
const char* predictorName(Predictor predictor);  ///< "model", "constant_velocity", ...

struct PredictionError {
  int horizon = 0;                 ///< K [frames]
  Predictor predictor = Predictor::kModel;
  double rms_m = 0.0;              ///< RMS per coordinate over every predicted sample observed [m]
  long samples = 0;                ///< observed samples compared (x, y, z each count once)
};

struct PredictionReport {
  std::vector<PredictionError> rows;  ///< per horizon, the four predictors in enum order
  int starts = 0;                     ///< start frames used (x(t-2), x(t-1), x(t) all observed)
  /// A rollout of the model from the first start, `rollout_frames` long, stays finite and within
  /// 10x the data's extent around its centre.
  bool rollout_bounded = false;
  int rollout_frames = 0;
};

/// Every prediction starts at a frame t where every particle is seen at t-2, t-1 and t: the model
/// from x(t) with v = (x(t) - x(t-1)) / h (the paper's start), the guesses from the same frames;
/// each is compared with the observed x(t + K) of every free particle. `model` carries every free
/// value; `trajectory` has its particles as markers. Throws InputError on unusable input (no
/// frame rate, horizons < 1, too few frames for a start).
PredictionReport evaluatePredictions(const Model& model, const Trajectory& trajectory,
                                     const std::vector<int>& horizons,
                                     double rollout_factor = 10.0);

}  // namespace mme

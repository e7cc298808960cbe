// The held-out judge of a model: how well it predicts the markers K frames ahead, open loop,
// next to three guesses that need no model (constant velocity, constant acceleration from the last
// three frames, free fall under the model's gravity). A model that cannot beat an extrapolation
// has not explained the motion.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/observations.h"
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
  int starts = 0;                     ///< start frames used
  /// Particle start states filled from neighbours (the particle unseen at the start, or not
  /// seen in the 3 frames before it), summed over the starts.
  long filled = 0;
  /// A rollout of the model from the first start, `rollout_frames` long, stays finite and within
  /// 10x the data's extent around its centre.
  bool rollout_bounded = false;
  int rollout_frames = 0;
};

/// Where a rollout must stay: every free particle finite and within kExtents x the free
/// particles' bounding-box diagonal (over some frames of the data) of that box's centre. Fixed
/// particles stay where they are (anchors may lie far away, a floor) and are not judged.
/// evaluatePredictions bounds its long rollout by it; fits that judge their own rollouts use it
/// too, so that "left the data" means one thing.
struct RolloutBound {
  static constexpr double kExtents = 10.0;
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();  ///< the box's centre [m]
  double extent_m = 1e-3;  ///< the box's diagonal [m] (at least 1 mm; 1 mm when nothing is seen)
  /// The box of `model`'s free particles where `obs` sees them in frames [first_frame, end_frame).
  static RolloutBound of(const Model& model, const Observations& obs, int first_frame,
                         int end_frame);
  /// Every free particle of `model` at `x_m` finite and within kExtents x extent_m of the centre.
  bool holds(const Model& model, const std::vector<Eigen::Vector3d>& x_m) const;
};

/// Where free particle i is at frame t, from the frames up to t only: seen there, its observation;
/// else the rigid motion (least squares, Kabsch) of its nearest free neighbours (up to 4) from the
/// latest frame s < t where it was seen to t, applied to x_i(s): the "rigid body fill" of
/// motion-capture software (markers on one segment move together). False when no earlier frame
/// has at least 3 neighbours seen both then and at t, off one line. With `later_frames_too`
/// (for fitting, where the whole recording is known), frames after t are tried as well, the
/// nearest first (t-1, t+1, t-2, t+2, ...): a marker hidden from the recording's start is placed.
bool fillFromNeighbours(const Observations& obs, const Model& model, int t, int i,
                        Eigen::Vector3d* position_m, bool later_frames_too = false);

/// A prediction starts at every frame t >= max(first_start, 2) where every free particle has a
/// start state: seen at t, x(t) with v = (x(t) - x(t-j)) / (j h) for the latest frame t-j at most
/// 3 back where it is seen (j = 1, the paper's start, wherever the particle is seen at t-1);
/// otherwise filled by fillFromNeighbours, the velocity from its positions at t-1 and t. Frames
/// before first_start are history only (held-out frames judged after the fitted ones: the fitted
/// frames place a marker hidden throughout the held-out part). A particle is scored at x(t + K)
/// when it is seen there and at t-2, t-1 and t (so that every guess is defined, and never from a
/// filled start), with the same samples for every predictor. The rollout runs rollout_factor x
/// the judged frames (from first_start - 2) from the first start, bounded by their extent (the
/// free particles': fixed ones stay put, seen or not, and may lie far away, like anchors).
/// `model` carries every free value; `trajectory` has its particles as markers. Throws
/// InputError on unusable input (no frame rate, horizons < 1, no start).
PredictionReport evaluatePredictions(const Model& model, const Trajectory& trajectory,
                                     const std::vector<int>& horizons,
                                     double rollout_factor = 10.0, int first_start = 2);

}  // namespace mme

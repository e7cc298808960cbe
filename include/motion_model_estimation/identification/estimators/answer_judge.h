// One yardstick for every estimator's answer before it replaces another: the open-loop
// prediction error K frames ahead on the frames the answers were fitted to (evaluatePredictions'
// model row, the figure the structure levels and the sensor muscles are judged by on held-out
// frames). The one-step cost favours the one-step answer and the output-error cost the
// output-error answer; a prediction judged the same way for both favours neither, and a model
// that blows up scores infinity instead of a huge but finite cost.
#pragma once

#include <string>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// Frames ahead the judge predicts: the held-out figures' horizon, and the output error's default
/// segment length (the motion it fits is K frames of the model's own).
constexpr int kJudgeHorizonFrames = 10;

/// A candidate within this share above the standing answer's figure still replaces it: equal
/// within the judged frames' sampling noise (an estimator made for noisy data, the output error,
/// is not thrown out for a difference the noise decides).
constexpr double kJudgeTolerance = 0.01;

/// The judged figure of `model` (every free value set, its substeps the integrator) on
/// `trajectory` (its particles as markers): the RMS per coordinate [m] of its open-loop
/// predictions horizon_frames ahead from every frame that can start one. +infinity when a
/// prediction is not finite or the figure is over 1000 times the data's extent (the free
/// particles' bounding-box diagonal): the model blew up. NaN when nothing can be judged (too few
/// frames, no frame to start from, a model that cannot be simulated).
double judgedPredictionRms_m(const Model& model, const Trajectory& trajectory,
                             int horizon_frames = kJudgeHorizonFrames);

/// Whether a candidate judged `candidate_rms_m` replaces the standing answer judged
/// `standing_rms_m` (both from judgedPredictionRms_m on the same frames): a candidate that blew
/// up (infinite) never does; a finite one does when the standing one is not finite or it is at
/// most (1 + kJudgeTolerance) times the standing one's; when neither can be judged (NaN) the
/// candidate does (nothing says it is worse), when only the candidate cannot it does not.
bool replacesStanding(double candidate_rms_m, double standing_rms_m);

/// An output-error residual at most this many times the markers' noise is "at the noise".
constexpr double kAtNoiseFactor = 1.5;

/// Whether an output-error answer (judged `output_error_rms_m`, its residuals
/// `residual_std_m` RMS per coordinate) replaces the one-step answer (judged `one_step_rms_m`)
/// on data whose marker noise is `noise_std_m`: when the judge says it predicts no worse
/// (replacesStanding), and also when its residuals are at the noise (kAtNoiseFactor) and its
/// prediction stays finite. There the output error explains the data as far as the noise lets
/// anything (it is the estimator made for noisy data, the one-step answer is biased by noise),
/// while the judge's predictions start from noisy positions and velocities and so measure the
/// noise as much as the model: at a millimetre on a 100 Hz object a biased one-step answer can
/// damp the noise and be judged better.
bool outputErrorReplacesOneStep(double output_error_rms_m, double one_step_rms_m,
                                double residual_std_m, double noise_std_m);

/// "3.21 mm" style figure for messages ("blew up" for infinity, "not judged" for NaN).
std::string formatJudged(double rms_m);

}  // namespace mme

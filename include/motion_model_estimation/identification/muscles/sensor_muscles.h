// Sensor muscles: muscles that read the body's posture, fitted by least squares. Muscles on the
// passive bonds read near-rigid marker pairs, which carry almost nothing of a gait's phase; these
// read "sensor" bonds instead (the pairs of particles whose distance varies most, springs of zero
// stiffness that only measure), sit on the body's bonds, between near particles and from every
// particle to three fixed anchors far along x, y and z, and are fitted in closed form (Newton's
// law is linear in their parameters once the activation is linearised), the ridge and the extras
// (rollout equations, activation time constant, anchors or not) chosen on held-out last frames.
// They are written, every parameter fixed, only where they predict those frames better than the
// passive model. The method and what it measured on real recordings: docs/muscles.md
// (section "Sensor muscles").
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// The anchor muscles' own stiffness (SensorMuscleOptions::anchor_stiffness).
enum class AnchorStiffness { kAuto, kFitted, kNone };

struct SensorMuscleOptions {
  int sensors = 16;          ///< sensor bonds every muscle reads (1..kMaxMuscleInputs)
  /// Muscles from each particle to its nearest particles, by mean distance over the data
  /// (0..64); they hold the body's shape over long rollouts.
  int neighbours = 2;
  /// Anchor muscles: three fixed anchor particles far along x, y and z, and a muscle from every
  /// free particle to each (a push along a world axis driven by the posture).
  bool anchors = true;
  /// With `anchors`: fit without them too and keep the layout whose fit predicts the validation
  /// frames better (a kept fit first; see addSensorMuscles). At most doubles the work.
  bool anchors_by_validation = true;
  /// With `anchors`: whether the anchor muscles have a stiffness of their own (which ties the
  /// body to where it was recorded). kAuto: held at 0 when the passive model has no fixed
  /// particle and the body travels (bodyTravel >= travel_body_sizes), fitted otherwise.
  AnchorStiffness anchor_stiffness = AnchorStiffness::kFitted;
  /// kAuto's threshold [body sizes]: the body travels when its markers' median range over the
  /// data is at least this many body sizes (bodyTravel).
  double travel_body_sizes = 0.5;
  /// The anchors' distance from the data's centre, in bounding-box diagonals of the data.
  double anchor_distance_extents = 20.0;
  /// Candidate windows [frames, 1..100]: each equation sums the one-step equations of
  /// 2 window - 1 frames with triangle weights window - |j|; 1 is the plain one-step equation.
  std::vector<int> windows_frames = {1};
  /// Candidate ridges, relative to the mean diagonal of the normal matrix (scaled columns),
  /// judged in this order (the largest first: their fits stay near the data, so a search cut by
  /// max_time_s keeps the steadier ones). The choice does not depend on the order: bounded
  /// first, then the lowest validation error.
  std::vector<double> ridges = {10.0, 3.0, 1.0, 0.3, 1e-1, 1e-2, 1e-3, 1e-4};
  double validation_fraction = 0.2;  ///< last share of the frames that judges the candidates
  int horizon_frames = 10;           ///< the validation's open-loop horizon [frames]
  /// Every muscle's own stiffness and damping held >= 0 (a muscle is then a tether with a
  /// controller, and the closed loop stays bounded at smaller ridges).
  bool nonnegative_own_spring = true;
  double gain_margin = 10.0;  ///< gain = margin x the largest linear activation over the data [1]
  /// Candidate activation time constants [frames], each tried on the chosen candidate's
  /// validation fit (0 or none: the activation is the excitation at once).
  std::vector<double> activation_times_frames = {3.0, 10.0, 30.0, 100.0};
  /// Rounds of rollout equations (Data as Demonstrator; 0..20, 0: none): each runs the current
  /// fit open loop and adds the equations at the postures its predictions reached.
  int rollout_rounds = 3;
  /// Rounds also start from this many ridges below the best one-step candidate's (0..20): the
  /// rollout rows hold the fit near the data as a ridge does.
  int rollout_lower_ridges = 2;
  int rollout_stride_frames = 2;  ///< a rollout of the rounds starts every this many frames
  /// The rollout equations' target: the data's acceleration plus a critically damped return to
  /// the data with this time constant [frames] (0: the data's acceleration alone).
  double rollout_correction_frames = 10.0;
  /// A pair is a sensor or a neighbour muscle only when both particles are seen together in at
  /// least this share of the frames [0, 1].
  double min_seen_share = 0.9;
  /// The linear unknowns at most (muscles x (2 sensors + 3), 1..14000): the normal matrix is
  /// stored as its coupled blocks, but its sparse factor fills in and the solves slow down. A layout above it reads fewer sensors, the
  /// most varying pairs kept, until it fits; when even one sensor is too many, InputError (with
  /// anchors_by_validation, the other layout is kept).
  size_t max_unknowns = 14000;
  /// Wall-time limit of the fit [s] (0: none), checked between steps (a step under way
  /// finishes). Once spent, no further window, ridge, rollout round, activation time constant
  /// or second layout is started (one candidate is always judged); the final refits run as
  /// without a limit (the best candidate judged so far refitted on every frame and checked, and
  /// up to 3 next ones while a refit leaves the data). So the fit overruns the limit by the step
  /// under way and the refits, and its result then depends on the machine's load
  /// (SensorMuscleResult::stopped_by_time says when the limit cut the search).
  double max_time_s = 0.0;
  /// Grouped selection (docs/muscles.md, *Grouped selection*): after the one-step candidates,
  /// the muscles and sensors the best one's equations do not support are removed by backward
  /// elimination by group, priced like structure selection's units (the residual's rise against
  /// the Bayesian information criterion's price of the parameters removed), and the selection is
  /// adopted when its fit predicts the validation frames within selection_tolerance of the fit
  /// without it (the smaller model wins a near tie, as among structure levels). The written model
  /// then has the kept muscles and sensors only. Off by default: on the real walks measured its
  /// price removed far more than the validation frames bore, and it was not adopted.
  bool select_groups = false;
  double selection_tolerance = 0.02;  ///< relative, >= 0
  int selection_max_solves = 24;      ///< ridge solves the elimination may run (1..100)
  /// Skip the search where it cannot gain: the passive model already predicts the validation
  /// frames within what a perfect model makes from starts with the markers' noise, or its
  /// one-step residual (what the muscles fit) is only the markers' noise. The result then has
  /// `skipped` set, the passive model and the reason (not_kept_because).
  bool skip_without_gain = true;
  /// Threads that accumulate the equations (1..256; the pipeline gives the identification's):
  /// the sums, and so the result, are the same bit for bit whatever the count.
  int threads = 1;
  std::function<void(const std::string&)> progress;  ///< one line per step (may be empty)
};

/// One (window, ridge) candidate and how it predicted the validation frames.
struct SensorMuscleCandidate {
  int window_frames = 1;
  double ridge = 0.0;
  double validation_rms_m = std::numeric_limits<double>::quiet_NaN();  ///< NaN: failed
  bool bounded = false;  ///< its validation rollout stayed bounded
  int rollout_rounds = 0;  ///< rounds of rollout equations (SensorMuscleOptions::rollout_rounds)
  int rollout_starts = 0;  ///< the rollouts its last round ran (0 without rounds)
};

struct SensorMuscleResult {
  Model model;                ///< the passive model with sensors and fitted muscles
  int sensors = 0, muscles = 0;
  size_t unknowns = 0;        ///< linear unknowns (muscles x (2 sensors + 3))
  size_t rows = 0;            ///< equations of the final fit (3 per particle and frame)
  /// After the grouped selection (the layout's figures when none was adopted): the muscles and
  /// sensors written and the unknowns left free (not dropped, not held at 0 by the layout),
  /// to be read against `rows`, the samples they are fitted on.
  int selected_muscles = 0, selected_sensors = 0;
  size_t selected_parameters = 0;
  /// The candidates judged: windows x ridges in the options' order, then the rollout rounds.
  std::vector<SensorMuscleCandidate> candidates;
  int chosen = -1;            ///< the chosen candidate
  int window_frames = 1;      ///< its window
  double ridge = 0.0;         ///< its relative ridge
  double activation_time_s = 0.0;        ///< its muscles' activation time constant (0: none)
  bool anchors = false;                  ///< the model has the anchors and their muscles
  /// With anchors: their muscles' own stiffness was fitted (false: held at 0).
  bool anchor_stiffness = false;
  double body_travel = 0.0;              ///< bodyTravel of the data (body sizes)
  double validation_rms_m = 0.0;         ///< its validation RMS horizon ahead (with it)
  double passive_rms_m = 0.0;            ///< the passive model on the same validation frames
  double constant_velocity_rms_m = 0.0;  ///< the constant-velocity guess there
  /// The chosen fit predicted the validation frames better than the passive model (by 1 % of
  /// the larger of its and the constant-velocity guess's errors: a fit of the residue of a
  /// passive model that already explains the data is not kept), its rollout
  /// bounded, and its refit on every frame stays bounded over rollouts from the validation
  /// start and from 8 frames spread over the data (10x validation / (1 - validation_fraction)
  /// frames), within 10 extents of the validation frames' box (a refit that does not is
  /// replaced by the next candidate, up to 4 tried); when false, keep the passive model.
  bool better_than_passive = false;
  /// Why better_than_passive is false, in words (empty when it is true).
  std::string not_kept_because;
  /// The final fit's residual per frame, a h^2 [m] (a window's row divided by window^2).
  double residual_rms_m = 0.0;
  /// SensorMuscleOptions::max_time_s was spent before every step was run (the choice was made
  /// among fewer candidates, or a layout was not fitted).
  bool stopped_by_time = false;
  double wall_time_s = 0.0;  ///< the fit's wall time [s]
  /// SensorMuscleOptions::skip_without_gain found nothing to gain: no muscle was placed, `model`
  /// is the passive model and not_kept_because says why.
  bool skipped = false;
  double noise_m = 0.0;  ///< the markers' estimated noise per coordinate (estimateMarkerNoise) [m]
};

/// How far the body travels over the data, in body sizes: the median over the free particles of
/// the diagonal of the box each one's seen positions span, over the median over frames of the
/// diagonal of the box the free particles seen in that frame span (0 when nothing is seen).
double bodyTravel(const Model& model, const Trajectory& data);

/// Places and fits sensor muscles on `passive` (its values are the passive forces; every
/// parameter it needs must have a value). `data` has the model's particles as markers, in the
/// model's order. Throws InputError on unusable input (options out of range, too few frames or
/// sensors, no usable equation).
SensorMuscleResult addSensorMuscles(const Model& passive, const Trajectory& data,
                                    const SensorMuscleOptions& options = {});

}  // namespace mme

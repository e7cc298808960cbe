// Sensor muscles (real gait): muscles that read the body's posture, fitted by least
// squares.
//
// Muscles placed on the passive bonds and reading their nearest bonds (muscle_placement.h) read
// near-rigid marker pairs, whose elongations carry almost nothing of a gait's phase; their
// prediction of real walks stays where the passive model's is. Here the muscles read *sensor*
// bonds instead: the S pairs of particles whose distance varies most over the data (a wrist to a
// hip, an ankle to the other ankle: what changes through a stride), each a spring of zero
// stiffness (it exerts nothing, it only measures) whose rest length is the pair's mean length.
// Every muscle reads all S sensors (2S network inputs: elongations and their speeds), linear
// (hidden 0), and has its own type: its own network, stiffness and damping. Muscles sit on the
// model's two-particle bonds with an elongation, on the sensor pairs, between every particle
// and its `neighbours` nearest (mean distance over the data; 2 by default), and from every
// particle to each anchor (below), so that every particle can be pushed in three directions.
//
// Anchors (`anchors`, on by default, and with `anchors_by_validation` the layout without them
// fitted too, the one predicting the validation frames better kept): muscles between the body's
// particles push along lines
// that turn with the body, but a walk's accelerations live in the world (the body rises and
// falls, the feet swing forward and land). So three fixed particles, `anchor_x`, `anchor_y` and
// `anchor_z`, are added at the data's centre plus `anchor_distance_extents` x the data's extent
// along each axis (far away: the line from any marker to an anchor is that axis within a few
// degrees), and every free particle gets a muscle to each: with its sensor-reading network it
// is a push along a world axis driven by the posture. Anchors are never sensors (their distance
// to a marker is the marker's absolute position along the axis: no posture). An anchor muscle's
// own stiffness pulls the body back to where it was recorded: right for a body held in place (an
// arm on a fixed shoulder, a walk on a treadmill), and on a walk across the room it both helps
// (where the walk starts and stops is a place) and harms (the model walks on beyond the data and,
// tied back, comes apart a few metres later). `anchor_stiffness`: fitted by default; kAuto holds
// it at 0 when the body is free (the passive model has no fixed particle) and travels over the
// data (bodyTravel: its markers' median range at least `travel_body_sizes` x the body's median
// size); kNone always. Measured: see the option. A model with them
// needs no anchor markers in the data (fixed particles stay where the model holds them).
// Measured on bench_paper fig5's split, 10 frames ahead held out: see docs/muscles.md. On a small
// body whose controller lives between its particles they fit the markers' noise instead
// (muscleObject, 0.3 mm: 9.8 mm held out with them, 4.7 without): hence the choice.
//
// With the activation linearised (a = gain tanh(y) ~ gain y, y linear in the network's
// parameters), a muscle's tension k e + c s + gain y is linear in (k, c, gain w2, gain b2), and so
// is Newton's law written on every observed frame with the passive model's forces known:
//   m_i a_i - F_passive,i(x, v) = sum over muscles at i of +-(k e + c s + gain y) u
// (accelerations and velocities from frame differences, as in the paper's one-step prediction).
// This is a ridge-regularised linear least-squares problem (the columns scaled to unit RMS, the
// ridge relative to the mean diagonal of the normal matrix), solved in closed form: no search
// over thousands of network weights. Each muscle's own stiffness k and damping c are held >= 0
// (an active set: negative ones fixed at 0 and the rest solved again): a muscle is then a tether
// plus a controller, and the closed loop stays bounded at ridges where, left free, negative
// springs took it off the data (motion_capture_walk: bounded from ridge 1e-3 instead of 0.3,
// 13.34 mm 10 frames ahead held out instead of 17.95). Optionally (windows_frames) each equation
// sums the one-step equations of frames t - W + 1 .. t + W - 1 with weights W - |j|, whose left
// side is then x(t + W) - 2 x(t) + x(t - W) (more signal against the markers' noise; measured no
// better). The window and ridge are chosen by holding out the data's last
// `validation_fraction`: each candidate is fitted on the frames before and judged by the
// open-loop prediction `horizon_frames` ahead on the held-out ones (evaluatePredictions, its
// rollout bounded first); the chosen one is refitted on every frame, and that refit is run open
// loop from the validation start and from 8 frames spread over the data, 10x the frames a
// held-out test of the same share would judge were these data its fitted part (validation
// frames / (1 - validation_fraction)): when one of those rollouts leaves the validation frames'
// box (10 of its extents from its centre, as a held-out test bounds by its own frames; a refit
// can, where the validation fit did not), the next candidate is refitted instead (up to 4).
// The gain is then set to `gain_margin` times the largest linear activation over the fitted
// frames and the weights divided by it, so tanh stays within 0.4 % of linear where the data
// went (and bounds the activation beyond).
//
// Activation dynamics (`activation_times_frames`): a posture-driven muscle cannot tell a drive
// that changes in time (an arm moved by excitations), which the constant-acceleration guess
// simply carries on. So the chosen candidate's validation fit is judged again with each
// candidate activation time constant on every muscle: a start's activations then come from the
// data's last frames (evaluatePredictions, Simulator::estimateActivations) and fade to the
// network's excitation. The bounded one with the lowest validation error is kept when it beats
// the fit without (arm26: 0.76 -> 0.28 mm 10 frames ahead held out, below the constant-
// acceleration guess's 0.50; on noisy walks none is kept: a start's acceleration is the markers'
// noise over h^2), and the final refit is built with it (a fallback candidate gets its own).
//
// Rollout equations (Data as Demonstrator, Venkatraman, Hebert and Bagnell 2015): the one-step
// fit learns where the data go from where the data are, but a prediction 10 frames ahead runs
// from where its own errors took it, and with noisy markers the one-step equations are biased
// (the noise is in the regressors and, over h^2, in the accelerations). So, after the one-step
// fit, `rollout_rounds` rounds each run the current model open loop horizon_frames - 1 frames
// from every `rollout_stride_frames`-th frame (a marker unseen at t-1 or t placed by the rigid
// motion of its neighbours from the nearest frame where it was seen, earlier or later: captures
// whose markers come into view one by one keep their rollouts; a rollout stops when a prediction
// leaves its marker by more than the data's extent), and at every
// predicted frame t + k add the equation at the predicted posture and speeds whose target is the
// data's acceleration at t + k plus a critically damped return to the data, time constant
// `rollout_correction_frames` (a return in one step asks for drift / h^2: high-gain feedback
// that took the rollouts off the data when tried); the fit is solved again on all rows gathered
// (the ridge relative to the one-step rows' mean diagonal). The rounds start from the best
// window-1 candidate, from the next `rollout_lower_ridges` ridges below its ridge (the rollout
// rows regularise as the ridge does) and, when another ridge had a lower validation error with
// an unbounded rollout, from that one too. Each round is a candidate judged like the others;
// the chosen round count is run again on every frame for the final fit.
//
// The muscles' and sensors' parameters are written fixed (identified here, not by the search).
// Frames where a sensor is unseen, and particles whose bond partners are unseen, drop out.
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
  /// Muscles from each particle to its nearest particles (0..64). 2 by default: with them the
  /// body holds its shape over long rollouts at lower ridges, whose rounds predict better
  /// (measured on bench_paper fig5's split, 10 frames ahead held out, with rollout_lower_ridges:
  /// Sample01 18.25 -> 15.05 mm, subject01 13.18 -> 9.15, motion_capture_walk 7.03 -> 6.93,
  /// Sample26 10.05 -> 9.97, arm26 0.28 unchanged; on Sample01 without them every refit of the
  /// lower ridges left the data within the 10x rollout, the body coming apart after ~5 s), at
  /// 3-4x the fit's time on the walks (more unknowns, more rounds; fig5 beside a CI run:
  /// motion_capture_walk 1421 s, subject01 832 s, against 426 s and 195 s alone before).
  int neighbours = 2;
  /// Anchor muscles (see above): three fixed anchor particles far along x, y and z, and a muscle
  /// from every free particle to each.
  bool anchors = true;
  /// With `anchors`: fit without them too and keep the layout whose fit predicts the
  /// validation frames better (a kept fit first; see addSensorMuscles). Doubles the work at most
  /// (the layout without anchors has fewer muscles).
  bool anchors_by_validation = true;
  /// With `anchors`: whether the anchor muscles have a stiffness of their own (see the header).
  /// kAuto: held at 0 when the passive model has no fixed particle and the body travels
  /// (bodyTravel >= travel_body_sizes), fitted otherwise. Measured on bench_paper fig5's split
  /// (10 frames ahead held out, fitted -> held at 0): the three walks across the room
  /// motion_capture_walk 6.93 -> 5.22 mm, Sample01 15.05 -> 18.83, Sample26 9.97 -> 10.44; the
  /// treadmill walk subject01 9.15 -> 10.42; arm26 0.28 -> 0.36 mm with an unbounded rollout. So
  /// fitted by default; without it identify's model of motion_capture_walk stays bounded over a
  /// 1000-frame rollout (with it, it leaves the data between 500 and 600 frames), which the live
  /// node's `stable` asks for (10x its 100-frame window).
  AnchorStiffness anchor_stiffness = AnchorStiffness::kFitted;
  /// kAuto's threshold: the body travels when its markers' median range over the data is at
  /// least this many body sizes (the real recordings' first 300 frames: the walks across the
  /// room 1.18-1.68, the treadmill walk 0.14, the arm 0.004).
  double travel_body_sizes = 0.5;
  /// The anchors' distance from the data's centre, in bounding-box diagonals of the data.
  double anchor_distance_extents = 20.0;
  /// Candidate windows [frames]: each equation sums the one-step equations of 2 window - 1
  /// frames with triangle weights (see above); 1 is the plain one-step equation. Measured on
  /// the real recordings (bench_paper fig5's split): 5 and 10 did not predict better than 1
  /// (motion_capture_walk: 3 to 10 left the 10x rollout unbounded; subject01 34.11 against 34.24
  /// mm, Sample01 28.88 against 28.68 mm), so the default is 1 alone.
  std::vector<int> windows_frames = {1};
  /// Candidate ridges, relative to the mean diagonal of the normal matrix (scaled columns),
  /// judged in this order: the largest first, whose fits stay near the data, so that a time
  /// limit (max_time_s) that stops the search early leaves the steadier candidates judged (the
  /// choice does not depend on the order: bounded first, then the lowest validation error).
  std::vector<double> ridges = {10.0, 3.0, 1.0, 0.3, 1e-1, 1e-2, 1e-3, 1e-4};
  double validation_fraction = 0.2;  ///< last share of the frames that chooses the ridge
  int horizon_frames = 10;           ///< the validation's open-loop horizon
  /// Every muscle's own stiffness and damping >= 0 (a muscle is then a tether with a
  /// controller: with negative ones the closed loop leaves the data within the 10x rollout).
  bool nonnegative_own_spring = true;
  double gain_margin = 10.0;         ///< gain = margin x the largest linear activation [1]
  /// Candidate activation time constants [frames] (see above; 0 or none: the activation is the
  /// excitation at once), each tried on the chosen candidate's validation fit.
  std::vector<double> activation_times_frames = {3.0, 10.0, 30.0, 100.0};
  /// Rounds of rollout equations (Data as Demonstrator, see above; 0: none). Measured on
  /// bench_paper fig5's split: motion_capture_walk 13.34 -> 12.62 mm 10 frames ahead held out,
  /// subject01 34.24 -> 29.02, Sample01 28.68 -> 27.72, Sample26 and arm26 unchanged (no round
  /// won their validation); each round costs about one more one-step fit.
  int rollout_rounds = 3;
  /// Rounds also start from this many ridges below the best one-step candidate's (see the
  /// header: the rollout rows hold the fit near the data as a ridge does). Sample01 (fig5's
  /// split): ridge 1 after a round (3 was the best one step) predicts 15.05 mm held out.
  int rollout_lower_ridges = 2;
  int rollout_stride_frames = 2;  ///< starts of the rollout equations, every this many frames
  /// The rollout equations' target: the data's acceleration plus a critically damped return to
  /// the data with this time constant [frames] (0: the data's acceleration alone).
  double rollout_correction_frames = 10.0;
  /// A pair is a sensor or a neighbour muscle only when both particles are seen together in at
  /// least this share of the frames.
  double min_seen_share = 0.9;
  /// The linear unknowns at most (muscles x (2 sensors + 3), 1..14000): the normal matrix and
  /// its factor are two dense squares of this size (2 x 1.6 GB at 14000; a solve there is
  /// ~10^12 flops, up to 6 per ridge). A layout above it reads fewer sensors, the most varying
  /// pairs kept, until it fits (a capture of ~65 markers or more with the anchors, ~100
  /// without); when even one sensor is too many, InputError (with anchors_by_validation, the
  /// other layout is kept).
  size_t max_unknowns = 14000;
  /// Wall-time limit of the search [s] (0: none). On a capture of ~40 markers the fit takes
  /// 10-25 minutes (two layouts of several thousand unknowns, 8 ridges, rounds of rollouts),
  /// whatever bounded the passive identification before it. Checked between steps (a step under
  /// way finishes: one solve of a large body takes tens of seconds): once spent, no further
  /// ridge, rollout round, activation time constant or second layout is started (one candidate
  /// is always judged), and the final refits run as without a limit: the best candidate judged
  /// so far refitted on every frame and checked, and when it leaves the data the next ones (up
  /// to 4 in all; a refit that leaves is common, and the next one is what gives a model). So
  /// the fit overruns the limit by the step under way plus 1-4 refits (each about one
  /// candidate's time). Its result then depends on the machine's load
  /// (SensorMuscleResult::stopped_by_time says when it cut the search).
  double max_time_s = 0.0;
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
  std::vector<SensorMuscleCandidate> candidates;  ///< windows x ridges, in the options' order
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

// One layout's sensor-muscle fit (docs/muscles.md, *Fit*), in steps that share a FitRun:
//   1. judgeOneStepCandidates (ridge_search.cpp): the one-step fit on the frames before the
//      validation frames, per window and ridge, each judged on the validation frames;
//   1b. selectGroups (group_selection_step.cpp): the muscles and sensors the best one-step fit's
//      data support (group_selection.h), adopted when the selected fit predicts the validation
//      frames as well; every later fit then holds the dropped ones at 0;
//   2. judgeRolloutRounds (rollout_rounds.cpp): rounds of rollout equations from the best
//      candidates, each round a candidate of its own;
//   3. refitOnEveryFrame (final_refit.cpp): the best candidate refitted on every frame, with its
//      activation time constant (activation_time.cpp), checked by long rollouts, the next
//      candidates tried when it leaves the data; the result.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "fit_budget.h"
#include "group_selection.h"
#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"
#include "muscle_equations.h"
#include "muscle_least_squares.h"
#include "rollout_equations.h"
#include "sensor_layout.h"
#include "validation_judge.h"

namespace mme::sensor_muscles {

/// addSensorMuscles on a checked model and data (anchors added when asked: `anchor` flags them).
SensorMuscleResult fitSensorMuscles(const Model& passive, const Trajectory& data,
                                    const std::vector<char>& anchor, const SensorMuscleOptions& o,
                                    Budget& budget);

/// The first validation frame: the data's last validation_fraction held out. Throws InputError
/// when too few frames are left on either side.
int validationStart(int frames, const SensorMuscleOptions& o);

/// What the steps of one layout's fit share: the inputs, the equations, the judge, and the
/// candidates judged so far with their fits.
struct FitRun {
  FitRun(const Model& passive, const Trajectory& data, const std::vector<char>& anchor,
         const SensorMuscleOptions& o, Budget& budget, int validation_start);
  FitRun(const FitRun&) = delete;
  FitRun& operator=(const FitRun&) = delete;

  /// The model carrying theta, its gains from frames [0, t_end) (buildMuscleModel).
  Model build(const Eigen::VectorXd& theta, int t_end, double activation_time_s = 0.0) const;
  /// solveRidge with this layout's sign constraints.
  bool solve(const System& sys, double ridge, Eigen::VectorXd* theta, double reference_diagonal = 0.0) const;
  /// Appends a judged candidate and its fit (empty: its solve failed); it becomes the best when
  /// it beats the best so far (candidateBeats). Returns its index.
  int addCandidate(const SensorMuscleCandidate& c, Eigen::VectorXd theta);
  /// The validation's progress-line tail: "N frames ahead on the last M frames".
  int validationFrames() const { return frames - validation_start; }

  const Model& passive;
  const Trajectory& data;
  const SensorMuscleOptions& o;
  Budget& budget;
  const int frames;
  const int validation_start;
  const Layout layout;
  const MuscleEquations equations;
  const RolloutEquations rollouts;
  const ValidationJudge judge;
  /// SensorMuscleOptions::threads - 1 workers for the equations' accumulation (null: 1 thread).
  std::unique_ptr<ThreadPool> pool;
  SignConstraints constraints;  ///< with the selection's dropped columns once one is adopted
  GroupSelection selection;     ///< the adopted selection (empty: none)

  SensorMuscleResult result;            ///< result.candidates: every candidate judged so far
  std::vector<Eigen::VectorXd> thetas;  ///< per candidate, its validation fit (empty: the solve failed)
  int best = -1;                        ///< the best candidate so far (-1: none)
  System best_sys;  ///< the one-step equations of the best candidate's window before the validation
};

/// A candidate beats `best` (null: none yet): its validation error finite, bounded where the best
/// is not, else as bounded and with a lower error.
bool candidateBeats(const SensorMuscleCandidate& c, const SensorMuscleCandidate* best);

/// The candidate of one window and ridge, fitted on `sys` and judged; `theta` its fit (empty
/// when the solve failed).
SensorMuscleCandidate judgeRidge(const FitRun& run, const System& sys, int window, double ridge,
                                 Eigen::VectorXd* theta);

/// A one-step candidate's progress line.
void sayCandidate(const FitRun& run, const SensorMuscleCandidate& c);

/// Step 1: the one-step candidates (windows x ridges). Throws InputError when no frame gives an
/// equation or no candidate gives a model.
void judgeOneStepCandidates(FitRun& run);

/// Step 1b: grouped selection of muscles and sensors on the best candidate's equations at its
/// ridge (SensorMuscleOptions::select_groups); when adopted, the candidates of the best one's
/// window are fitted and judged again with it.
void selectGroups(FitRun& run);

/// Step 2: rounds of rollout equations from the best window-1 candidate, from the ridges below it
/// and from the lowest-error one (docs/muscles.md, *Rollout equations*).
void judgeRolloutRounds(FitRun& run);

/// Called after each round with its number, its fit and its rollouts.
using RoundCallback = std::function<void(int round, const Eigen::VectorXd& theta, const RolloutCount& count)>;

/// `rounds` rounds of rollout equations from the one-step fit theta on `data_rows` at a relative
/// ridge (kept relative to those rows' mean diagonal as rollout rows are added), the gains from
/// frames [0, gain_t_end), starts before `start_end`. `budgeted`: a round after the first is not
/// started once the time limit is spent. False when a solve fails.
bool runRounds(FitRun& run, const System& data_rows, double ridge, Eigen::VectorXd theta, int gain_t_end,
               int start_end, int rounds, bool budgeted, const RoundCallback& each);

/// A candidate's activation time constant and the validation error with it.
struct Activation {
  double time_s = 0.0;
  double validation_rms_m = 0.0;
};

/// Candidate `index`'s validation fit run with each of the options' activation time constants
/// (its starts' activations estimated from the data, evaluatePredictions): the bounded one with
/// the lowest error (time 0, none, when none beats the fit without).
Activation chooseActivation(FitRun& run, int index);

/// Step 3: the chosen candidate refitted on every frame and checked; fills run.result.
void refitOnEveryFrame(FitRun& run);

}  // namespace mme::sensor_muscles

// The sensor muscles' rollout equations (Data as Demonstrator, Venkatraman, Hebert and Bagnell
// 2015; docs/muscles.md, *Rollout equations*): the model's own open-loop predictions, and the
// equations written where they went; and the check that a model stays near the data when run
// open loop from frames spread over the data.
#pragma once

#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/observations.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"
#include "muscle_equations.h"

namespace mme::sensor_muscles {

/// Starts and rollouts of one round of rollout equations.
struct RolloutCount {
  int starts = 0;   ///< rollouts run
  int filled = 0;   ///< of which a particle was placed from its neighbours (startState)
  int stopped = 0;  ///< rollouts stopped early: non-finite, or farther from the data than
                    ///< the data's extent (their later rows would only carry the blow-up)
};

/// How one round's rollouts run.
struct RolloutSettings {
  int horizon_frames = 10;           ///< each rollout runs horizon_frames - 1 frames
  int stride_frames = 2;             ///< a rollout starts every this many frames
  double correction_frames = 10.0;   ///< the target's return to the data [frames] (0: none)
};

class RolloutEquations {
 public:
  /// `equations` (and what it refers to) must outlive this.
  explicit RolloutEquations(const MuscleEquations& equations);

  /// Adds the equations of `model`'s own open-loop predictions: from every stride-th start t in
  /// [start_begin, start_end) where every particle can be placed (startState), the model runs
  /// horizon - 1 frames; at each predicted frame t + k the equation is written at the predicted
  /// posture and speeds, its target the data's acceleration at t + k plus a critically damped
  /// return to the data. The one-step fit learns where the data go from where the data are;
  /// these rows teach it where to go from where its own errors take it.
  /// `pool` (may be null) shares out the rows' accumulation (MuscleEquations::addPiecesBatch):
  /// the same sums whatever the threads.
  RolloutCount accumulate(const Model& model, const RolloutSettings& settings, int start_begin, int start_end,
                          System* sys, ThreadPool* pool = nullptr) const;

  /// The state a rollout starts from at frame t: a particle seen at t - 1 and t at its position
  /// there, its velocity their difference; one unseen at either placed by the rigid motion of its
  /// nearest neighbours from the nearest frame where it was seen, earlier or later
  /// (fillFromNeighbours; `filled` counts these), as evaluatePredictions fills its starts; a
  /// fixed one where the model holds it when unseen. False when a particle cannot be placed.
  bool startState(int t, State* state, int* filled) const;

  /// Whether `model` stays near the data when run open loop `rollout_frames` long from `starts`
  /// frames spread evenly over the data (startState's states): within the RolloutBound of the
  /// frames from `box_first_frame` on, as evaluatePredictions bounds its one rollout by the
  /// frames it judges. A model's instability can depend on where it starts; the held-out test
  /// starts where the data end.
  bool boundedFromEverywhere(const Model& model, int starts, int rollout_frames, int box_first_frame) const;

 private:
  /// Scratch of one rollout's equations.
  struct Scratch {
    std::vector<Eigen::Vector3d> before, next;
    std::vector<uint8_t> occluded;
  };

  /// Runs one rollout from frame t (state at t), adding its frames' pieces to `batch`; false
  /// when it was stopped.
  bool rollOne(Simulator* sim, int t, const RolloutSettings& settings, State* state, Scratch* scratch,
               std::vector<FramePieces>* batch) const;
  /// Every particle finite and, where seen at `frame`, within the data's extent of its marker.
  bool nearData(int frame, const State& state) const;
  /// The target frame after `state` (at data frame `frame`): per particle seen in the data's
  /// frames around it, the position the data's acceleration plus the return would reach.
  void targetFrame(int frame, const State& state, double correction_frames, Scratch* scratch) const;

  const MuscleEquations& eq_;
  const Model& passive_;
  const Trajectory& data_;
  const Observations obs_;  ///< the data as the neighbour fill reads them
  RolloutBound bound_;      ///< the free particles' box over the data (its diagonal: the data's extent)
  int n_;
  double h_;
};

}  // namespace mme::sensor_muscles

#include "rollout_equations.h"

#include <algorithm>

namespace mme::sensor_muscles {

RolloutEquations::RolloutEquations(const MuscleEquations& equations)
    : eq_(equations), passive_(equations.passive()), data_(equations.data()),
      obs_(prepareObservations(passive_, data_)), n_(equations.particles()), h_(equations.framePeriodS()) {
  bound_ = RolloutBound::of(passive_, obs_, 0, data_.numFrames());
}

RolloutCount RolloutEquations::accumulate(const Model& model, const RolloutSettings& settings, int start_begin,
                                          int start_end, System* sys, ThreadPool* pool) const {
  sizeSystem(eq_.pattern(), sys);
  Simulator sim(model);
  const int last = std::min(start_end, data_.numFrames() - settings.horizon_frames);  // exclusive
  RolloutCount count;
  Scratch scratch;
  State state;
  std::vector<FramePieces> batch;  // the rollouts' rows, added in their order
  for (int t = std::max(start_begin, 1); t < last; t += settings.stride_frames) {
    int filled = 0;
    if (!startState(t, &state, &filled)) continue;
    ++count.starts;
    if (filled > 0) ++count.filled;
    if (!rollOne(&sim, t, settings, &state, &scratch, &batch)) ++count.stopped;
    if (batch.size() < MuscleEquations::kBatchFrames) continue;
    eq_.addPiecesBatch(batch, sys, pool);
    batch.clear();
  }
  eq_.addPiecesBatch(batch, sys, pool);
  return count;
}

bool RolloutEquations::rollOne(Simulator* sim, int t, const RolloutSettings& settings, State* state,
                               Scratch* scratch, std::vector<FramePieces>* batch) const {
  for (int k = 1; k < settings.horizon_frames; ++k) {
    scratch->before = state->x_m;
    sim->stepFrame(state, h_);
    if (!nearData(t + k, *state)) return false;
    targetFrame(t + k, *state, settings.correction_frames, scratch);
    Frames3 f;
    f.x[0] = scratch->before.data();
    f.x[1] = state->x_m.data();
    f.x[2] = scratch->next.data();
    f.occluded[2] = scratch->occluded.data();
    batch->push_back(eq_.pieces(f));
  }
  return true;
}

bool RolloutEquations::nearData(int frame, const State& state) const {
  bool near = true;
  for (int i = 0; i < n_ && near; ++i)
    near = state.x_m[i].allFinite() &&
           (data_.isOccluded(frame, i) || (state.x_m[i] - data_.position(frame, i)).norm() <= bound_.extent_m);
  return near;
}

// The target: the data's acceleration at `frame`, plus a correction that would bring the
// prediction back to the data with time constant tau (critically damped), not in one step (a
// one-step return asks for accelerations of drift / h^2: high-gain feedback).
void RolloutEquations::targetFrame(int frame, const State& state, double correction_frames,
                                   Scratch* scratch) const {
  const Frames3 d = eq_.dataFrames(frame);
  const std::vector<Eigen::Vector3d>& before = scratch->before;
  scratch->next.resize(n_);
  scratch->occluded.assign(n_, 0);
  for (int i = 0; i < n_; ++i) {
    if (!d.seen(0, i) || !d.seen(1, i) || !d.seen(2, i)) {
      scratch->occluded[i] = 1;
      continue;
    }
    const Eigen::Vector3d& x0 = d.x[0][i];
    const Eigen::Vector3d& x1 = d.x[1][i];
    const Eigen::Vector3d& x2 = d.x[2][i];
    Eigen::Vector3d acc = (x2 - 2.0 * x1 + x0) / (h_ * h_);
    if (correction_frames > 0.0) {
      const double tau = correction_frames * h_;
      acc -= (state.x_m[i] - x1) / (tau * tau) + (2.0 / tau) * ((state.x_m[i] - before[i]) - (x1 - x0)) / h_;
    }
    scratch->next[i] = acc * h_ * h_ + 2.0 * state.x_m[i] - before[i];
  }
}

bool RolloutEquations::startState(int t, State* state, int* filled) const {
  state->activation_n.clear();
  state->x_m.assign(n_, Eigen::Vector3d::Zero());
  state->v_mps.assign(n_, Eigen::Vector3d::Zero());
  for (int i = 0; i < n_; ++i) {
    const Particle& p = passive_.particles[i];
    if (p.fixed) {
      state->x_m[i] = data_.isOccluded(t, i) ? p.position_m : data_.position(t, i);
      state->v_mps[i] = p.velocity_mps;
      continue;
    }
    Eigen::Vector3d now, before;
    if (!data_.isOccluded(t, i) && !data_.isOccluded(t - 1, i)) {
      now = data_.position(t, i);
      before = data_.position(t - 1, i);
    } else if (fillFromNeighbours(obs_, passive_, t, i, &now, true) &&
               fillFromNeighbours(obs_, passive_, t - 1, i, &before, true)) {
      ++*filled;
    } else {
      return false;
    }
    state->x_m[i] = now;
    state->v_mps[i] = (now - before) / h_;
  }
  return true;
}

bool RolloutEquations::boundedFromEverywhere(const Model& model, int starts, int rollout_frames,
                                             int box_first_frame) const {
  Simulator sim(model);
  const int frames = data_.numFrames();
  const RolloutBound bound = RolloutBound::of(passive_, obs_, box_first_frame, frames);
  State state;
  for (int k = 0; k < starts; ++k) {
    const int t = 1 + static_cast<int>((static_cast<long>(frames - 2) * (k + 1)) / starts);
    int filled = 0;
    if (t >= frames || !startState(t, &state, &filled)) continue;
    for (int step = 0; step < rollout_frames; ++step) {
      sim.stepFrame(&state, h_);
      if (!bound.holds(passive_, state.x_m)) return false;
    }
  }
  return true;
}

}  // namespace mme::sensor_muscles

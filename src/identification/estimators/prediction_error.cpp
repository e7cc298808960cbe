#include "motion_model_estimation/identification/estimators/prediction_error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Dense>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/observations.h"
#include "motion_model_estimation/core/simulator.h"

namespace mme {

namespace {
/// A start's velocity comes from the latest frame before it, at most this many back, where the
/// particle is seen.
constexpr int kMaxVelocityGap = 3;
/// Neighbours whose rigid motion carries an unseen particle to the start (the nearest ones seen
/// with it); at least 3, not on one line.
constexpr int kFillNeighbours = 4;

}  // namespace

const char* predictorName(Predictor predictor) {
  switch (predictor) {
    case Predictor::kModel: return "model";
    case Predictor::kConstantVelocity: return "constant_velocity";
    case Predictor::kConstantAcceleration: return "constant_acceleration";
    case Predictor::kGravityOnly: return "gravity_only";
  }
  return "?";
}

bool fillFromNeighbours(const Observations& obs, const Model& model, int t, int i,
                        Eigen::Vector3d* position_m, bool later_frames_too) {
  const auto x = [&](int f, int j) { return Eigen::Map<const Eigen::Vector3d>(obs.position(f, j)); };
  if (!obs.isOccluded(t, i)) {
    *position_m = x(t, i);
    return true;
  }
  // The frames tried, nearest first: t-1, t-2, ... or, with later frames, t-1, t+1, t-2, t+2, ...
  const int tries = later_frames_too ? 2 * std::max(t, obs.frames - 1 - t) : t;
  for (int step = 1; step <= tries; ++step) {
    const int s = later_frames_too ? (step % 2 ? t - (step + 1) / 2 : t + step / 2) : t - step;
    if (s < 0 || s >= obs.frames || obs.isOccluded(s, i)) continue;
    std::vector<std::pair<double, int>> near;
    for (int j = 0; j < obs.particles; ++j)
      if (j != i && !model.particles[j].fixed && !obs.isOccluded(s, j) && !obs.isOccluded(t, j))
        near.emplace_back((x(s, j) - x(s, i)).squaredNorm(), j);
    // The nearest frame where i was seen is its best picture; with too few companions there, the
    // next one is tried.
    if (static_cast<int>(near.size()) < 3) continue;
    const size_t m = std::min<size_t>(kFillNeighbours, near.size());
    std::partial_sort(near.begin(), near.begin() + static_cast<long>(m), near.end());
    Eigen::Vector3d from_c = Eigen::Vector3d::Zero(), to_c = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < m; ++k) {
      from_c += x(s, near[k].second);
      to_c += x(t, near[k].second);
    }
    from_c /= static_cast<double>(m);
    to_c /= static_cast<double>(m);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (size_t k = 0; k < m; ++k)
      cov += (x(t, near[k].second) - to_c) * (x(s, near[k].second) - from_c).transpose();
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Vector3d sv = svd.singularValues();
    if (!(sv[1] > 1e-6 * std::max(sv[0], 1e-300))) continue;  // on a line: no rotation known
    Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
    d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
    const Eigen::Matrix3d r = svd.matrixU() * d * svd.matrixV().transpose();
    *position_m = r * (x(s, i) - from_c) + to_c;
    return position_m->allFinite();
  }
  return false;
}

namespace {

constexpr size_t kPredictors = 4;  ///< model, constant velocity, constant acceleration, gravity only

Eigen::Map<const Eigen::Vector3d> seenAt(const Observations& obs, int t, int i) {
  return Eigen::Map<const Eigen::Vector3d>(obs.position(t, i));
}

/// The start state at frame t: every particle's position at t and its velocity, from the latest
/// of the kMaxVelocityGap frames before t where it is seen (x(t-1) when seen: the paper's start).
/// A particle unseen at t, or not seen in those frames, is filled from its neighbours' rigid
/// motion (fillFromNeighbours: data up to t only; counted in *filled). A fixed particle moves as
/// the model says, seen or not. False when a particle cannot be placed.
bool startState(const Observations& obs, const Model& model, int t, State* s, int* filled) {
  const int n = obs.particles;
  const double h = obs.frame_period_s;
  *filled = 0;
  s->x_m.assign(n, Eigen::Vector3d::Zero());
  s->v_mps.assign(n, Eigen::Vector3d::Zero());
  for (int i = 0; i < n; ++i) {
    if (model.particles[i].fixed) {
      s->x_m[i] = obs.isOccluded(t, i) ? model.particles[i].position_m : Eigen::Vector3d(seenAt(obs, t, i));
      s->v_mps[i] = model.particles[i].velocity_mps;
      continue;
    }
    int back = 0;
    if (!obs.isOccluded(t, i))
      for (int j = 1; j <= kMaxVelocityGap && t - j >= 0 && back == 0; ++j)
        if (!obs.isOccluded(t - j, i)) back = j;
    if (back > 0) {
      s->x_m[i] = seenAt(obs, t, i);
      s->v_mps[i] = (seenAt(obs, t, i) - seenAt(obs, t - back, i)) / (back * h);
      continue;
    }
    Eigen::Vector3d now, before;
    if (!fillFromNeighbours(obs, model, t, i, &now) || !fillFromNeighbours(obs, model, t - 1, i, &before))
      return false;
    s->x_m[i] = now;
    s->v_mps[i] = (now - before) / h;
    ++*filled;
  }
  return true;
}

/// Muscles with activation dynamics start where the data's motion puts them: at t - 1 (its
/// velocity from t - 2), the activations that explain each particle's acceleration
/// x(t) - 2 x(t-1) + x(t-2) over h^2 (particles seen in those three frames; the constant-
/// acceleration guess's), then one frame of their dynamics to t. The others are placed at t - 1
/// by their start velocity.
void startActivations(const Observations& obs, const Model& model, int t, Simulator* sim, State* s) {
  s->activation_n.clear();
  if (!sim->hasActivationState()) return;
  const int n = obs.particles;
  const double h = obs.frame_period_s;
  State before = *s;
  std::vector<Eigen::Vector3d> acceleration(n, Eigen::Vector3d::Zero());
  std::vector<char> known(n, 0);
  for (int i = 0; i < n; ++i) {
    if (model.particles[i].fixed) continue;
    if (!obs.isOccluded(t, i) && !obs.isOccluded(t - 1, i) && !obs.isOccluded(t - 2, i)) {
      before.x_m[i] = seenAt(obs, t - 1, i);
      before.v_mps[i] = (seenAt(obs, t - 1, i) - seenAt(obs, t - 2, i)) / h;
      acceleration[i] = (seenAt(obs, t, i) - 2.0 * seenAt(obs, t - 1, i) + seenAt(obs, t - 2, i)) / (h * h);
      known[i] = 1;
    } else {
      before.x_m[i] = s->x_m[i] - h * s->v_mps[i];
    }
  }
  sim->estimateActivations(&before, acceleration, known);
  sim->stepFrame(&before, h);
  s->activation_n = before.activation_n;
}

/// Squared errors of every predictor at every horizon in reach of the model's open-loop path
/// from start t, where all are defined (the particle seen at t-2, t-1, t and t+K).
void scoreStart(const Observations& obs, const Model& model, const std::vector<int>& horizons, int t,
                const std::vector<std::vector<Eigen::Vector3d>>& path, const Eigen::Vector3d& g,
                std::vector<double>* sum2, std::vector<long>* count) {
  const int reach = static_cast<int>(path.size()) - 1;
  const double h = obs.frame_period_s;
  for (size_t hi = 0; hi < horizons.size(); ++hi) {
    const int K = horizons[hi];
    if (K > reach) continue;
    const double kk = 0.5 * K * (K + 1);
    for (int i = 0; i < obs.particles; ++i) {
      if (model.particles[i].fixed || obs.isOccluded(t + K, i) || obs.isOccluded(t - 1, i) ||
          obs.isOccluded(t - 2, i))
        continue;
      const Eigen::Vector3d x_t = seenAt(obs, t, i);
      const Eigen::Vector3d d1 = x_t - seenAt(obs, t - 1, i);
      const Eigen::Vector3d d2 = x_t - 2.0 * seenAt(obs, t - 1, i) + seenAt(obs, t - 2, i);
      const Eigen::Vector3d guess[kPredictors] = {path[K][i], x_t + K * d1, x_t + K * d1 + kk * d2,
                                                  x_t + K * d1 + kk * h * h * g};
      for (size_t p = 0; p < kPredictors; ++p) {
        const Eigen::Vector3d e = guess[p] - seenAt(obs, t + K, i);
        (*sum2)[hi * kPredictors + p] += e.allFinite() ? e.squaredNorm() : 1e300;
        (*count)[hi * kPredictors + p] += 3;
      }
    }
  }
}

}  // namespace

PredictionReport evaluatePredictions(const Model& model, const Trajectory& trajectory,
                                     const std::vector<int>& horizons, double rollout_factor,
                                     int first_start) {
  const Observations obs = prepareObservations(model, trajectory);
  if (horizons.empty()) throw InputError("no horizon to evaluate");
  for (int k : horizons)
    if (k < 1) throw InputError("horizons must be >= 1 frame, got " + std::to_string(k));
  const int frames = obs.frames;
  const int max_k = *std::max_element(horizons.begin(), horizons.end());
  const double h = obs.frame_period_s;
  Model sim_model = model;
  sim_model.frame_rate_hz = obs.frame_rate_hz;
  Simulator sim(sim_model);
  const Eigen::Vector3d g = sim_model.gravity();

  PredictionReport report;
  std::vector<double> sum2(horizons.size() * kPredictors, 0.0);
  std::vector<long> count(horizons.size() * kPredictors, 0);
  State s, first_state;  // first_state: the first start's, the long rollout's
  const int judged_from = std::max(first_start - 2, 0);  // the judged frames' first
  for (int t = std::max(first_start, 2); t + 1 < frames; ++t) {
    int filled = 0;
    if (!startState(obs, model, t, &s, &filled)) continue;
    ++report.starts;
    report.filled += filled;
    startActivations(obs, model, t, &sim, &s);
    // The model's open-loop motion from the start, up to the longest horizon in reach.
    const int reach = std::min(max_k, frames - 1 - t);
    if (first_state.x_m.empty()) first_state = s;
    std::vector<std::vector<Eigen::Vector3d>> path(reach + 1);
    path[0] = s.x_m;
    for (int k = 1; k <= reach; ++k) {
      sim.stepFrame(&s, h);
      path[k] = s.x_m;
    }
    scoreStart(obs, model, horizons, t, path, g, &sum2, &count);
  }
  if (report.starts == 0)
    throw InputError("no frame where every particle is seen or can be placed by the rigid motion "
                     "of 3 neighbours seen with it earlier: nothing to predict from");
  for (size_t hi = 0; hi < horizons.size(); ++hi)
    for (size_t p = 0; p < kPredictors; ++p) {
      PredictionError row;
      row.horizon = horizons[hi];
      row.predictor = static_cast<Predictor>(p);
      row.samples = count[hi * kPredictors + p];
      row.rms_m = row.samples > 0 ? std::sqrt(sum2[hi * kPredictors + p] / row.samples)
                                  : std::numeric_limits<double>::quiet_NaN();
      report.rows.push_back(row);
    }

  // A long rollout from the first start stays near the judged frames.
  const RolloutBound bound = RolloutBound::of(model, obs, judged_from, frames);
  report.rollout_frames = static_cast<int>(rollout_factor * (frames - judged_from));
  s = first_state;
  report.rollout_bounded = true;
  for (int k = 0; k < report.rollout_frames && report.rollout_bounded; ++k) {
    sim.stepFrame(&s, h);
    report.rollout_bounded = bound.holds(model, s.x_m);
  }
  return report;
}

RolloutBound RolloutBound::of(const Model& model, const Observations& obs, int first_frame,
                              int end_frame) {
  const int n = static_cast<int>(model.particles.size());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int t = std::max(first_frame, 0); t < std::min(end_frame, obs.frames); ++t)
    for (int i = 0; i < n; ++i)
      if (!model.particles[i].fixed && !obs.isOccluded(t, i)) {
        const Eigen::Map<const Eigen::Vector3d> x(obs.position(t, i));
        lo = lo.cwiseMin(x);
        hi = hi.cwiseMax(x);
      }
  RolloutBound bound;
  if (lo.allFinite() && hi.allFinite()) {
    bound.centre_m = 0.5 * (lo + hi);
    bound.extent_m = std::max((hi - lo).norm(), 1e-3);
  }
  return bound;
}

bool RolloutBound::holds(const Model& model, const std::vector<Eigen::Vector3d>& x_m) const {
  const double limit_m = kExtents * extent_m;
  for (size_t i = 0; i < x_m.size() && i < model.particles.size(); ++i)
    if (!model.particles[i].fixed && (!x_m[i].allFinite() || (x_m[i] - centre_m).norm() > limit_m))
      return false;
  return true;
}

}  // namespace mme

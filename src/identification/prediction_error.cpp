#include "motion_model_estimation/identification/prediction_error.h"

#include <algorithm>
#include <cmath>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/observations.h"
#include "motion_model_estimation/core/simulator.h"

namespace mme {

namespace {
/// A start's velocity comes from the latest frame before it, at most this many back, where the
/// particle is seen.
constexpr int kMaxVelocityGap = 3;
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

PredictionReport evaluatePredictions(const Model& model, const Trajectory& trajectory,
                                     const std::vector<int>& horizons, double rollout_factor) {
  const Observations obs = prepareObservations(model, trajectory);
  if (horizons.empty()) throw InputError("no horizon to evaluate");
  for (int k : horizons)
    if (k < 1) throw InputError("horizons must be >= 1 frame, got " + std::to_string(k));
  const int n = obs.particles, frames = obs.frames;
  const int max_k = *std::max_element(horizons.begin(), horizons.end());
  const double h = obs.frame_period_s;
  Model sim_model = model;
  sim_model.frame_rate_hz = obs.frame_rate_hz;
  Simulator sim(sim_model);
  const Eigen::Vector3d g = sim_model.gravity();
  const auto x = [&](int t, int i) { return Eigen::Map<const Eigen::Vector3d>(obs.position(t, i)); };

  PredictionReport report;
  const size_t predictors = 4;
  std::vector<double> sum2(horizons.size() * predictors, 0.0);
  std::vector<long> count(horizons.size() * predictors, 0);
  int first_start = -1;
  State s, first_state;
  std::vector<int> back(n);
  for (int t = 2; t + 1 < frames; ++t) {
    // A start needs every particle's position at t and its velocity: from the latest of the
    // kMaxVelocityGap frames before t where it is seen (x(t-1) when seen: the paper's start).
    // A fixed particle moves as the model says, seen or not.
    bool usable = true;
    for (int i = 0; i < n && usable; ++i) {
      back[i] = 0;
      if (model.particles[i].fixed) continue;
      if (obs.isOccluded(t, i)) {
        usable = false;
        break;
      }
      for (int j = 1; j <= kMaxVelocityGap && t - j >= 0 && back[i] == 0; ++j)
        if (!obs.isOccluded(t - j, i)) back[i] = j;
      usable = back[i] > 0;
    }
    if (!usable) continue;
    ++report.starts;
    // The model's open-loop motion from the start, up to the longest horizon in reach.
    const int reach = std::min(max_k, frames - 1 - t);
    s.x_m.assign(n, Eigen::Vector3d::Zero());
    s.v_mps.assign(n, Eigen::Vector3d::Zero());
    for (int i = 0; i < n; ++i) {
      if (model.particles[i].fixed) {
        s.x_m[i] = obs.isOccluded(t, i) ? model.particles[i].position_m : Eigen::Vector3d(x(t, i));
        s.v_mps[i] = model.particles[i].velocity_mps;
      } else {
        s.x_m[i] = x(t, i);
        s.v_mps[i] = (x(t, i) - x(t - back[i], i)) / (back[i] * h);
      }
    }
    if (first_start < 0) {
      first_start = t;
      first_state = s;
    }
    std::vector<std::vector<Eigen::Vector3d>> path(reach + 1);
    path[0] = s.x_m;
    for (int k = 1; k <= reach; ++k) {
      sim.stepFrame(&s, h);
      path[k] = s.x_m;
    }
    for (size_t hi = 0; hi < horizons.size(); ++hi) {
      const int K = horizons[hi];
      if (K > reach) continue;
      const double kk = 0.5 * K * (K + 1);
      for (int i = 0; i < n; ++i) {
        // Scored where every predictor is defined: the particle seen at t-2, t-1, t and t+K.
        if (model.particles[i].fixed || obs.isOccluded(t + K, i) || obs.isOccluded(t - 1, i) ||
            obs.isOccluded(t - 2, i))
          continue;
        const Eigen::Vector3d d1 = x(t, i) - x(t - 1, i);
        const Eigen::Vector3d d2 = x(t, i) - 2.0 * x(t - 1, i) + x(t - 2, i);
        const Eigen::Vector3d guess[4] = {path[K][i], x(t, i) + K * d1, x(t, i) + K * d1 + kk * d2,
                                          x(t, i) + K * d1 + kk * h * h * g};
        for (size_t p = 0; p < predictors; ++p) {
          const Eigen::Vector3d e = guess[p] - x(t + K, i);
          sum2[hi * predictors + p] += e.allFinite() ? e.squaredNorm() : 1e300;
          count[hi * predictors + p] += 3;
        }
      }
    }
  }
  if (report.starts == 0)
    throw InputError("no frame with every particle seen and seen again within " +
                     std::to_string(kMaxVelocityGap) + " frames before it: nothing to predict from");
  for (size_t hi = 0; hi < horizons.size(); ++hi)
    for (size_t p = 0; p < predictors; ++p) {
      PredictionError row;
      row.horizon = horizons[hi];
      row.predictor = static_cast<Predictor>(p);
      row.samples = count[hi * predictors + p];
      row.rms_m = row.samples > 0 ? std::sqrt(sum2[hi * predictors + p] / row.samples)
                                  : std::numeric_limits<double>::quiet_NaN();
      report.rows.push_back(row);
    }

  // A long rollout from the first start stays near the data.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (int t = 0; t < frames; ++t)
    for (int i = 0; i < n; ++i)
      if (!obs.isOccluded(t, i)) {
        lo = lo.cwiseMin(x(t, i));
        hi = hi.cwiseMax(x(t, i));
      }
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  const double limit_m = 10.0 * std::max((hi - lo).norm(), 1e-3);
  report.rollout_frames = static_cast<int>(rollout_factor * frames);
  s = first_state;
  report.rollout_bounded = true;
  for (int k = 0; k < report.rollout_frames && report.rollout_bounded; ++k) {
    sim.stepFrame(&s, h);
    for (const Eigen::Vector3d& p : s.x_m)
      if (!p.allFinite() || (p - centre).norm() > limit_m) report.rollout_bounded = false;
  }
  return report;
}

}  // namespace mme

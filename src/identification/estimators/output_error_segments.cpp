// One shooting segment of the output error: its simulation from a start state, its residuals,
// and its Jacobian (forward sensitivities through the motion law, or forward differences).
#include "output_error_segments.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

#include "motion_model_estimation/identification/estimators/motion_sensitivity.h"

namespace mme {
namespace output_error_detail {

bool SegmentSimulation::rows(const double* theta, const double* state, int row0, int count,
                             double* residuals, double* jac_theta, double* jac_state) {
  std::lock_guard<std::mutex> lock(mutex_);
  const int np = static_cast<int>(p_->smooth.size()), ns = p_->stateSize();
  const bool same = key_valid_ && std::equal(theta, theta + np, key_theta_.begin()) &&
                    std::equal(state, state + ns, key_state_.begin());
  if (!same) {
    key_theta_.assign(theta, theta + np);
    key_state_.assign(state, state + ns);
    residuals_.resize(rows_);
    ok_ = simulate(theta, state, residuals_.data());
    key_valid_ = true;
    jacobian_valid_ = false;
    jacobian_takers_ = 0;
  }
  const bool want_jacobian = jac_theta || jac_state;
  if (ok_ && want_jacobian && !jacobian_valid_) {
    computeJacobian(theta, state);
    jacobian_valid_ = true;
  }
  std::copy(residuals_.begin() + row0, residuals_.begin() + row0 + count, residuals);
  if (!ok_ || !want_jacobian) return ok_;
  for (int r = 0; r < count; ++r) {
    if (jac_theta)
      std::copy_n(jac_theta_.data() + static_cast<size_t>(row0 + r) * np, np, jac_theta + r * np);
    if (jac_state)
      std::copy_n(jac_state_.data() + static_cast<size_t>(row0 + r) * ns, ns, jac_state + r * ns);
  }
  // Every block that reads this Jacobian has taken it: its memory goes (it is the largest
  // thing the solve holds on a long capture).
  if (++jacobian_takers_ == (has_next_ ? 2 : 1)) {
    jacobian_valid_ = false;
    std::vector<double>().swap(jac_theta_);
    std::vector<double>().swap(jac_state_);
  }
  return true;
}

void SegmentSimulation::computeJacobian(const double* theta, const double* state) {
  const int np = static_cast<int>(p_->smooth.size()), ns = p_->stateSize();
  jac_theta_.assign(static_cast<size_t>(rows_) * np, 0.0);
  jac_state_.assign(static_cast<size_t>(rows_) * ns, 0.0);
  if (p_->exact_jacobian) exactJacobian(theta, state);
  else forwardDifferences(theta, state);
}

void SegmentSimulation::exactJacobian(const double* theta, const double* state) {
  const int np = static_cast<int>(p_->smooth.size()), ns = p_->stateSize();
  std::vector<ParamRef> refs;
  for (int g : p_->smooth) refs.push_back(p_->space->gene(g).ref);
  MotionSensitivity sens(model_, refs);
  sens.setParameterColumns(theta_columns_);
  sens.start(startState(state));
  // Columns of the sensitivities -> the unknowns: d physical / d gene for theta; the state's
  // velocities are v h.
  const int c0 = sens.stateColumn0();
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(sens.columns());
  if (theta_columns_) {
    std::vector<double> genes = p_->base_genes;
    for (int j = 0; j < np; ++j) genes[p_->smooth[j]] = theta[j];
    for (int j = 0; j < np; ++j) scale[j] = p_->space->physicalSlope(p_->smooth[j], genes);
  }
  for (int j = 0; j < ns; ++j)
    if (j % 6 >= 3) scale[c0 + j] = 1.0 / p_->h;
  int r = 0;
  const auto emit = [&](const MotionSensitivity::Matrix& m, int row, double weight) {
    for (int j = 0; j < c0; ++j) jac_theta_[static_cast<size_t>(r) * np + j] = weight * scale[j] * m(row, j);
    for (int j = 0; j < ns; ++j)
      jac_state_[static_cast<size_t>(r) * ns + j] = weight * scale[c0 + j] * m(row, c0 + j);
    ++r;
  };
  const auto observe = [&](int t) {
    for (int i : p_->free_particles)
      if (!p_->obs.isOccluded(t, i))
        for (int c = 0; c < 3; ++c) emit(sens.dx(), 3 * i + c, p_->w_obs);
  };
  observe(first_);
  for (int t = first_ + 1; t <= last_; ++t) {
    sens.stepFrame(p_->h);
    if (t < last_ || !has_next_) observe(t);
  }
  if (!has_next_) return;
  for (int i : p_->free_particles) {
    for (int c = 0; c < 3; ++c) emit(sens.dx(), 3 * i + c, p_->w_cont);
    for (int c = 0; c < 3; ++c) emit(sens.dv(), 3 * i + c, p_->w_cont * p_->h);
  }
}

void SegmentSimulation::forwardDifferences(const double* theta, const double* state) {
  const int np = static_cast<int>(p_->smooth.size()), ns = p_->stateSize();
  std::vector<double> perturbed(rows_);
  std::vector<double> th(theta, theta + np);
  for (int j = 0; j < (theta_columns_ ? np : 0); ++j) {
    const Gene& g = p_->space->gene(p_->smooth[j]);
    double step = 1e-7 * std::max({std::fabs(th[j]), 1e-3 * (g.upper - g.lower), 1e-8});
    if (th[j] + step > g.upper) step = -step;
    th[j] += step;
    const bool ok = simulate(th.data(), state, perturbed.data());
    th[j] = theta[j];
    if (ok)
      for (int r = 0; r < rows_; ++r)
        jac_theta_[static_cast<size_t>(r) * np + j] = (perturbed[r] - residuals_[r]) / step;
  }
  std::vector<double> st(state, state + ns);
  for (int j = 0; j < ns; ++j) {
    const double step = 1e-7 * std::max(std::fabs(st[j]), 1e-2);
    st[j] += step;
    const bool ok = simulate(theta, st.data(), perturbed.data());
    st[j] = state[j];
    if (ok)
      for (int r = 0; r < rows_; ++r)
        jac_state_[static_cast<size_t>(r) * ns + j] = (perturbed[r] - residuals_[r]) / step;
  }
}

bool SegmentSimulation::simulate(const double* theta, const double* state, double* out) {
  // The state columns of a Jacobian keep theta: the simulator's parameters are set only when
  // theta changed since the last call.
  if (!std::equal(theta, theta + p_->smooth.size(), theta_set_.begin(), theta_set_.end())) {
    std::vector<double> genes = p_->base_genes;
    for (size_t j = 0; j < p_->smooth.size(); ++j) genes[p_->smooth[j]] = theta[j];
    setValues(model_, p_->refs, p_->space->toPhysical(genes));
    sim_.setParameters(model_);
    theta_set_.assign(theta, theta + p_->smooth.size());
  }
  State s = startState(state);
  const double h = p_->h;
  int r = 0;
  const auto observe = [&](int t) {
    for (int i : p_->free_particles) {
      if (p_->obs.isOccluded(t, i)) continue;
      const double* y = p_->obs.position(t, i);
      for (int c = 0; c < 3; ++c) out[r++] = p_->w_obs * (s.x_m[i][c] - y[c]);
    }
  };
  observe(first_);
  for (int t = first_ + 1; t <= last_; ++t) {
    sim_.stepFrame(&s, h);
    if (t < last_ || !has_next_) observe(t);
  }
  if (has_next_) {
    // The end state in the state's own order: x x x, v h v h v h per particle.
    for (size_t f = 0; f < p_->free_particles.size(); ++f) {
      const int i = p_->free_particles[f];
      for (int c = 0; c < 3; ++c) out[r + 6 * f + c] = p_->w_cont * s.x_m[i][c];
      for (int c = 0; c < 3; ++c) out[r + 6 * f + 3 + c] = p_->w_cont * s.v_mps[i][c] * h;
    }
  }
  for (int k = 0; k < rows_; ++k)
    if (!std::isfinite(out[k])) return false;
  return true;
}

State SegmentSimulation::startState(const double* state) const {
  const int n = p_->obs.particles;
  State s;
  s.x_m.resize(n);
  s.v_mps.resize(n);
  for (int i = 0; i < n; ++i) {
    const double* x = p_->obs.position(first_, i);
    s.x_m[i] = Eigen::Vector3d(x[0], x[1], x[2]);
    s.v_mps[i] = model_.particles[i].velocity_mps;  // fixed particles keep the model's
  }
  for (size_t f = 0; f < p_->free_particles.size(); ++f) {
    const int i = p_->free_particles[f];
    s.x_m[i] = Eigen::Vector3d(state[6 * f], state[6 * f + 1], state[6 * f + 2]);
    s.v_mps[i] = Eigen::Vector3d(state[6 * f + 3], state[6 * f + 4], state[6 * f + 5]) / p_->h;
  }
  return s;
}

/// Start state of frame t from the data: the position, and the velocity x h from a central
/// difference (one-sided at the ends, 0 where a neighbour is occluded).
void dataState(const Problem& p, int t, double* state) {
  const Observations& o = p.obs;
  for (size_t f = 0; f < p.free_particles.size(); ++f) {
    const int i = p.free_particles[f];
    const double* x = o.position(t, i);
    for (int c = 0; c < 3; ++c) state[6 * f + c] = x[c];
    const int a = std::max(t - 1, 0), b = std::min(t + 1, o.frames - 1);
    const bool known = b > a && !o.isOccluded(a, i) && !o.isOccluded(b, i);
    for (int c = 0; c < 3; ++c)
      state[6 * f + 3 + c] = known ? (o.position(b, i)[c] - o.position(a, i)[c]) / (b - a) : 0.0;
  }
}

}  // namespace output_error_detail
}  // namespace mme

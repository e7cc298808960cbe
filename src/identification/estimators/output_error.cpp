// Multiple shooting with Ceres. Two residual blocks per segment: its observed samples (weighted by
// 1 / sigma) and its continuity to the next segment's start (weighted continuity_weight / sigma),
// both read from the segment's one simulation.
// Parameter blocks: the smooth genes (theta, shared by every segment, bounded as the search space)
// and one state per segment (positions and velocity x h of the free particles, metres both). A
// segment's Jacobian comes from forward sensitivities through the motion law (one simulation
// carrying the derivatives, motion_sensitivity.h), or by forward differences through the
// simulator (one short simulation per column) for a model they do not cover or when asked; it
// is shared by the segment's two blocks; the continuity's derivative along the next state is -I
// exactly. The linear solver is sparse Cholesky of the normal equations (block-tridiagonal states
// bordered by theta).
#include "motion_model_estimation/identification/estimators/output_error.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <Eigen/Sparse>

#include <algorithm>
#include <chrono>
#include <functional>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/observations.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/motion_sensitivity.h"

namespace mme {

double estimateMarkerNoise(const Trajectory& trajectory) {
  const int frames = trajectory.numFrames(), n = trajectory.numMarkers();
  std::vector<double> squares;
  for (int i = 0; i < n; ++i)
    for (int t = 2; t + 2 < frames; ++t) {
      bool seen = true;
      for (int j = -2; j <= 2 && seen; ++j) seen = !trajectory.isOccluded(t + j, i);
      if (!seen) continue;
      const Eigen::Vector3d d4 = trajectory.position(t - 2, i) - 4.0 * trajectory.position(t - 1, i) +
                                 6.0 * trajectory.position(t, i) - 4.0 * trajectory.position(t + 1, i) +
                                 trajectory.position(t + 2, i);
      for (int c = 0; c < 3; ++c) squares.push_back(d4[c] * d4[c]);
    }
  if (squares.size() < 10) return 0.0;
  std::nth_element(squares.begin(), squares.begin() + squares.size() / 2, squares.end());
  // The median of a chi-square with one degree of freedom is 0.4549 of its mean.
  return std::sqrt(squares[squares.size() / 2] / 0.4549 / 70.0);
}

namespace {

/// What every segment shares (read-only during the solve).
struct Problem {
  Model model;                      // values of fixed parameters; free ones set per evaluation
  std::vector<ParamRef> refs;
  const ParameterSpace* space = nullptr;
  std::vector<double> base_genes;   // the start: thresholds keep these
  std::vector<int> smooth;          // gene indices Ceres moves (theta order)
  std::vector<int> free_particles;  // particle indices in the state
  Observations obs;
  double h = 0.0;                   // frame period [s]
  double w_obs = 1.0;               // 1 / sigma
  double w_cont = 1.0;              // continuity_weight / sigma
  bool exact_jacobian = true;       // forward sensitivities (else forward differences)

  int stateSize() const { return 6 * static_cast<int>(free_particles.size()); }
};

/// A shooting segment's simulation (frames [first, last]), shared by its two residual blocks:
/// both need the same residuals and the same forward-difference Jacobian (one short simulation
/// per column), which it computes once per (theta, state) and hands to each. The rows are the
/// observed samples (at first..last-1, and at last for the final segment) and then, when a next
/// segment exists, the end state x continuity weight (the next state is subtracted by the
/// continuity block, whose derivative along it is -I exactly). Thread-safe: Ceres may evaluate
/// both blocks at once.
class SegmentSimulation {
 public:
  /// `theta_columns` false: the Jacobian along theta is left zero (a fit with theta held).
  SegmentSimulation(const Problem* p, int first, int last, bool has_next, bool theta_columns = true)
      : p_(p), first_(first), last_(last), has_next_(has_next), theta_columns_(theta_columns),
        model_(p->model), sim_(p->model) {
    const int end = has_next ? last : last + 1;
    for (int t = first; t < end; ++t)
      for (int i : p->free_particles) observed_ += p->obs.isOccluded(t, i) ? 0 : 1;
    rows_ = 3 * observed_ + (has_next ? p->stateSize() : 0);
  }

  int observedSamples() const { return observed_; }

  /// Forgets what it computed (the weights changed).
  void invalidate() {
    std::lock_guard<std::mutex> lock(mutex_);
    key_valid_ = false;
    jacobian_valid_ = false;
  }

  /// Copies rows [row0, row0 + count) of the residuals (and of the Jacobians along theta and
  /// the state when the pointers are given, row-major) for (theta, state). False when the
  /// simulation is not finite.
  bool rows(const double* theta, const double* state, int row0, int count, double* residuals,
            double* jac_theta, double* jac_state) {
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

 private:
  void computeJacobian(const double* theta, const double* state) {
    const int np = static_cast<int>(p_->smooth.size()), ns = p_->stateSize();
    jac_theta_.assign(static_cast<size_t>(rows_) * np, 0.0);
    jac_state_.assign(static_cast<size_t>(rows_) * ns, 0.0);
    if (p_->exact_jacobian) exactJacobian(theta, state);
    else forwardDifferences(theta, state);
  }

  /// The rows' derivatives from one simulation carrying the sensitivities; model_ holds theta's
  /// values (simulate() ran for the residuals).
  void exactJacobian(const double* theta, const double* state) {
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

  /// Forward differences around residuals_ (which hold (theta, state)'s).
  void forwardDifferences(const double* theta, const double* state) {
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

  /// The segment's rows for theta (smooth genes) and its start state.
  bool simulate(const double* theta, const double* state, double* out) {
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

  /// The simulation's start: the free particles from `state`, the fixed ones where the data
  /// see them at the first frame, with the model's velocity.
  State startState(const double* state) const {
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

  const Problem* p_;
  int first_, last_;
  bool has_next_;
  bool theta_columns_;
  int observed_ = 0;
  int rows_ = 0;
  Model model_;
  Simulator sim_;
  std::vector<double> theta_set_;  // theta the simulator holds (empty: none yet)
  std::mutex mutex_;
  bool key_valid_ = false;
  std::vector<double> key_theta_, key_state_;  // what residuals_ (and the Jacobian) are for
  std::vector<double> residuals_;
  bool ok_ = false;
  bool jacobian_valid_ = false;
  int jacobian_takers_ = 0;
  std::vector<double> jac_theta_, jac_state_;  // rows_ x np, rows_ x ns, row-major
};

/// One residual block of a segment: its observations (parameter blocks theta and the segment's
/// state) or its continuity with the next segment's state (theta, the state and the next
/// state). The two are separate blocks so that the dense Jacobian blocks stay small: the next
/// state touches only the continuity rows; both read the segment's one simulation.
class SegmentCost final : public ceres::CostFunction {
 public:
  enum class Part { kObservations, kContinuity };

  SegmentCost(SegmentSimulation* sim, const Problem* p, Part part) : sim_(sim), p_(p), part_(part) {
    const bool continuity = part == Part::kContinuity;
    set_num_residuals(continuity ? p->stateSize() : 3 * sim->observedSamples());
    mutable_parameter_block_sizes()->push_back(static_cast<int32_t>(p->smooth.size()));
    mutable_parameter_block_sizes()->push_back(p->stateSize());
    if (continuity) mutable_parameter_block_sizes()->push_back(p->stateSize());
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int m = num_residuals(), ns = p_->stateSize();
    const int row0 = part_ == Part::kObservations ? 0 : 3 * sim_->observedSamples();
    if (!sim_->rows(parameters[0], parameters[1], row0, m, residuals,
                    jacobians ? jacobians[0] : nullptr, jacobians ? jacobians[1] : nullptr))
      return false;
    if (part_ == Part::kObservations) return true;
    const double* next = parameters[2];
    for (int k = 0; k < m; ++k) residuals[k] -= p_->w_cont * next[k];
    if (jacobians && jacobians[2]) {
      std::fill(jacobians[2], jacobians[2] + static_cast<size_t>(m) * ns, 0.0);
      for (int j = 0; j < ns; ++j) jacobians[2][j * ns + j] = -p_->w_cont;
    }
    return true;
  }

 private:
  SegmentSimulation* sim_;
  const Problem* p_;
  Part part_;
};

/// Stops the solve when the caller's flag is raised.
class CancelCallback final : public ceres::IterationCallback {
 public:
  explicit CancelCallback(const std::atomic<bool>* flag) : flag_(flag) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return flag_ && flag_->load() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  const std::atomic<bool>* flag_;
};

/// Hands every iteration to the caller's progress hook.
class ProgressCallback final : public ceres::IterationCallback {
 public:
  ProgressCallback(const OutputErrorOptions& options, const std::function<double()>& elapsed_s)
      : options_(options), elapsed_s_(elapsed_s) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration > 0) options_.progress(summary.iteration, options_.max_iterations, elapsed_s_());
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const OutputErrorOptions& options_;
  const std::function<double()>& elapsed_s_;
};

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

}  // namespace

namespace {

/// Segments of K frames over `frames`; the last one takes the remainder (at least 2 frames).
std::vector<std::pair<int, int>> segmentsOf(int frames, int K) {
  std::vector<std::pair<int, int>> segments;
  for (int first = 0; first < frames - 1; first += K) {
    int last = std::min(first + K, frames - 1);
    if (frames - 1 - last < 2 && last < frames - 1) last = frames - 1;
    segments.emplace_back(first, last);
    if (last == frames - 1) break;
  }
  return segments;
}

/// The problem's data and weights; "" or why the fit cannot run.
std::string setUpProblem(const Model& model, const Trajectory& trajectory, const ParameterSpace& space,
                         const std::vector<double>& start_genes, const OutputErrorOptions& options,
                         Problem* p, OutputErrorResult* out) {
  p->obs = prepareObservations(model, trajectory);
  if (p->obs.frames < 3) return "fewer than 3 frames";
  p->model = model;
  p->model.frame_rate_hz = p->obs.frame_rate_hz;
  p->refs = freeParameters(model);
  p->space = &space;
  p->base_genes = start_genes;
  for (size_t k = 0; k < space.size(); ++k)
    if (space.gene(k).smooth) p->smooth.push_back(static_cast<int>(k));
  for (size_t i = 0; i < model.particles.size(); ++i)
    if (!model.particles[i].fixed) p->free_particles.push_back(static_cast<int>(i));
  if (p->smooth.empty() || p->free_particles.empty()) return "no smooth free parameter or no free particle";
  p->h = p->obs.frame_period_s;
  out->noise_std_prior_m =
      options.noise_std_m > 0.0 ? options.noise_std_m : std::max(estimateMarkerNoise(trajectory), 1e-9);
  p->w_obs = 1.0 / out->noise_std_prior_m;
  p->w_cont = options.continuity_weight / out->noise_std_prior_m;
  p->exact_jacobian = options.jacobian == OutputErrorJacobian::kExact;
  out->jacobian = "finite differences";
  if (p->exact_jacobian) {
    const std::string why_not = sensitivityUnsupportedReason(model);
    p->exact_jacobian = why_not.empty();
    out->jacobian = why_not.empty() ? "exact" : "finite differences: " + why_not;
  }
  return "";
}

/// The fit's unknowns: the smooth genes (theta) and one start state per segment, and the
/// segments' simulations (which outlive the Ceres problem whose blocks read them).
struct SegmentUnknowns {
  std::vector<std::pair<int, int>> segments;
  std::vector<double> theta;
  std::vector<std::vector<double>> states;
  std::vector<std::unique_ptr<SegmentSimulation>> sims;

  int count() const { return static_cast<int>(segments.size()); }

  /// The observation part of the cost, unweighted [m^2]; infinite when a simulation fails.
  double observationCost(const Problem& p) const {
    double sum = 0.0;
    for (int s = 0; s < count(); ++s) {
      std::vector<double> r(3 * sims[s]->observedSamples());
      if (!sims[s]->rows(theta.data(), states[s].data(), 0, static_cast<int>(r.size()), r.data(),
                         nullptr, nullptr))
        return std::numeric_limits<double>::infinity();
      for (double v : r) sum += v * v;
    }
    return sum / (p.w_obs * p.w_obs);
  }
};

/// Per segment, the start state whose simulation (theta held) best matches the segment's first
/// frames: a dense problem of one state, the same residuals as the observations'. Kept only when
/// it matches the whole segment better: particles unseen in the first frames (occlusion) can make
/// a fit of a few frames wrong for the rest. `elapsed_s`: the fit's time so far.
void fitStartStates(Problem* p, const OutputErrorOptions& options, const std::function<double()>& elapsed_s,
                    SegmentUnknowns* u) {
  ceres::Solver::Options local;
  local.linear_solver_type = ceres::DENSE_QR;
  local.max_num_iterations = 20;
  local.logging_type = ceres::SILENT;
  const int frames = p->obs.frames;
  for (int s = 0; s < u->count() && !(options.cancel && options.cancel->load()); ++s) {
    if (options.max_time_s > 0.0) {
      if (elapsed_s() >= options.max_time_s) break;  // the rest keep the data's states
      local.max_solver_time_in_seconds = options.max_time_s - elapsed_s();
    }
    const int first = u->segments[s].first;
    SegmentSimulation sim(p, first, std::min(first + options.start_state_frames, frames - 1), false, false);
    if (sim.observedSamples() == 0) continue;
    ceres::Problem::Options local_options;
    local_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem fit(local_options);
    fit.AddResidualBlock(new SegmentCost(&sim, p, SegmentCost::Part::kObservations), nullptr,
                         u->theta.data(), u->states[s].data());
    fit.SetParameterBlockConstant(u->theta.data());
    const std::vector<double> from_data = u->states[s];
    ceres::Solver::Summary fit_summary;
    ceres::Solve(local, &fit, &fit_summary);
    SegmentSimulation whole(p, first, u->segments[s].second, false, false);
    const auto segmentCost = [&](const std::vector<double>& state) {
      std::vector<double> r(3 * whole.observedSamples());
      if (!whole.rows(u->theta.data(), state.data(), 0, static_cast<int>(r.size()), r.data(), nullptr, nullptr))
        return std::numeric_limits<double>::infinity();
      double sum = 0.0;
      for (double v : r) sum += v * v;
      return sum;
    };
    if (!fit_summary.IsSolutionUsable() || !(segmentCost(u->states[s]) < segmentCost(from_data)))
      u->states[s] = from_data;
  }
}

/// theta bounded by the genes' bounds, a state block per segment; every observation block first,
/// then every continuity block: Ceres' threads take blocks in this order, so two threads
/// simulate two segments rather than one waiting for the other's. Returns the observations.
int buildProblem(Problem* p, const ParameterSpace& space, SegmentUnknowns* u, ceres::Problem* problem) {
  const int S = u->count();
  for (int s = 0; s < S; ++s)
    u->sims.push_back(std::make_unique<SegmentSimulation>(p, u->segments[s].first, u->segments[s].second, s + 1 < S));
  problem->AddParameterBlock(u->theta.data(), static_cast<int>(u->theta.size()));
  for (size_t j = 0; j < p->smooth.size(); ++j) {
    const Gene& g = space.gene(p->smooth[j]);
    problem->SetParameterLowerBound(u->theta.data(), static_cast<int>(j), g.lower);
    problem->SetParameterUpperBound(u->theta.data(), static_cast<int>(j), g.upper);
  }
  for (int s = 0; s < S; ++s) problem->AddParameterBlock(u->states[s].data(), p->stateSize());
  int observations = 0;
  for (int s = 0; s < S; ++s) {
    observations += 3 * u->sims[s]->observedSamples();
    problem->AddResidualBlock(new SegmentCost(u->sims[s].get(), p, SegmentCost::Part::kObservations),
                              nullptr, u->theta.data(), u->states[s].data());
  }
  for (int s = 0; s + 1 < S; ++s)
    problem->AddResidualBlock(new SegmentCost(u->sims[s].get(), p, SegmentCost::Part::kContinuity), nullptr,
                              u->theta.data(), u->states[s].data(), u->states[s + 1].data());
  return observations;
}

ceres::Solver::Options solverOptions(const OutputErrorOptions& options) {
  ceres::Solver::Options solver;
  switch (options.linear_solver) {
    case OutputErrorLinearSolver::kSparseNormalCholesky:
      solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
      break;
    case OutputErrorLinearSolver::kSparseSchur:
      solver.linear_solver_type = ceres::SPARSE_SCHUR;
      break;
    case OutputErrorLinearSolver::kIterativeSchur:
      solver.linear_solver_type = ceres::ITERATIVE_SCHUR;
      solver.preconditioner_type = ceres::SCHUR_JACOBI;
      break;
  }
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = std::max(1, options.threads);
  solver.function_tolerance = 1e-14;
  solver.gradient_tolerance = 1e-16;
  solver.parameter_tolerance = 1e-12;
  // The projected line search Ceres runs on a bounded problem interpolates with function values
  // only: its default (cubic) asks for the Jacobian at every trial point, here a simulation per
  // column, nearly doubling the cost of an iteration.
  solver.line_search_interpolation_type = ceres::QUADRATIC;
  solver.logging_type = ceres::SILENT;
  return solver;
}

/// Adds a solve's time split to the result's.
void addTimes(const ceres::Solver::Summary& summary, OutputErrorResult* out) {
  out->jacobian_time_s += summary.jacobian_evaluation_time_in_seconds;
  out->linear_solver_time_s += summary.linear_solver_time_in_seconds;
}

/// The solve, with continuation when asked: soft continuity first, then the given weight (the
/// cached residuals carry the weight: recomputed at each change). Returns the iterations.
int solveWithContinuation(Problem* p, const OutputErrorOptions& options, double noise_std_prior_m,
                          const std::function<double()>& elapsed_s, SegmentUnknowns* u,
                          ceres::Problem* problem, ceres::Solver::Summary* summary,
                          OutputErrorResult* out) {
  ceres::Solver::Options solver = solverOptions(options);
  // The start-state fits spent part of the budget.
  if (options.max_time_s > 0.0) solver.max_solver_time_in_seconds = std::max(1e-3, options.max_time_s - elapsed_s());
  CancelCallback cancel(options.cancel);
  if (options.cancel) solver.callbacks.push_back(&cancel);
  ProgressCallback progress(options, elapsed_s);
  if (options.progress) solver.callbacks.push_back(&progress);
  int first_stage_iterations = 0;
  const double hard_w_cont = p->w_cont;
  if (options.first_continuity_weight > 0.0 && options.first_continuity_weight != options.continuity_weight) {
    p->w_cont = options.first_continuity_weight / noise_std_prior_m;
    for (auto& sim : u->sims) sim->invalidate();
    ceres::Solve(solver, problem, summary);
    addTimes(*summary, out);
    first_stage_iterations = static_cast<int>(summary->iterations.size()) - 1;
    p->w_cont = hard_w_cont;
    for (auto& sim : u->sims) sim->invalidate();
    if (options.max_time_s > 0.0)
      solver.max_solver_time_in_seconds = std::max(1e-3, options.max_time_s - elapsed_s());
  }
  if (!(options.cancel && options.cancel->load())) {
    ceres::Solve(solver, problem, summary);
    addTimes(*summary, out);
  }
  return first_stage_iterations + static_cast<int>(summary->iterations.size()) - 1;
}

/// Fisher information of theta with the states eliminated (Schur complement):
/// I = A - B C^-1 B^T from J^T J = [A B; B^T C], then Cov = I^+ (sigma_hat / sigma_prior)^2.
/// Fills out->std_devs and out->unidentifiable (directions with a relative eigenvalue below
/// 1e-10 of the unit-diagonal information are what the data do not determine).
void estimateStd(const Problem& p, const ParameterSpace& space, const OutputErrorOptions& options,
                 SegmentUnknowns* u, ceres::Problem* problem, OutputErrorResult* out) {
  ceres::CRSMatrix crs;
  ceres::Problem::EvaluateOptions eval;
  eval.parameter_blocks.push_back(u->theta.data());
  for (int s = 0; s < u->count(); ++s) eval.parameter_blocks.push_back(u->states[s].data());
  if (!problem->Evaluate(eval, nullptr, nullptr, nullptr, &crs)) return;
  const int np = static_cast<int>(u->theta.size());
  Eigen::SparseMatrix<double> j(crs.num_rows, crs.num_cols);
  std::vector<Eigen::Triplet<double>> entries;
  for (int row = 0; row < crs.num_rows; ++row)
    for (int e = crs.rows[row]; e < crs.rows[row + 1]; ++e) entries.emplace_back(row, crs.cols[e], crs.values[e]);
  j.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SparseMatrix<double> jtj = Eigen::SparseMatrix<double>(j.transpose() * j);
  const Eigen::MatrixXd a = Eigen::MatrixXd(jtj.topLeftCorner(np, np));
  const Eigen::MatrixXd b = Eigen::MatrixXd(jtj.topRightCorner(np, crs.num_cols - np));
  const Eigen::SparseMatrix<double> c = jtj.bottomRightCorner(crs.num_cols - np, crs.num_cols - np);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(c);
  Eigen::MatrixXd info = a;
  if (ldlt.info() == Eigen::Success) info -= b * ldlt.solve(Eigen::MatrixXd(b.transpose()));
  Eigen::VectorXd d = info.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (int k = 0; k < np; ++k) d[k] = d[k] > 0.0 ? 1.0 / d[k] : 0.0;
  const Eigen::MatrixXd scaled = d.asDiagonal() * info * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
  const Eigen::VectorXd lambda = eig.eigenvalues();
  const double top = std::max(lambda.maxCoeff(), 1e-300);
  Eigen::MatrixXd pinv = Eigen::MatrixXd::Zero(np, np);
  Eigen::VectorXd null_loading = Eigen::VectorXd::Zero(np);
  for (int q = 0; q < np; ++q) {
    const Eigen::VectorXd v = eig.eigenvectors().col(q);
    if (lambda[q] > 1e-10 * top) pinv += v * v.transpose() / lambda[q];
    else null_loading += v.cwiseProduct(v);
  }
  const double scale2 = options.std_from_given_noise ? 1.0 : std::pow(out->noise_std_m / out->noise_std_prior_m, 2);
  for (int k = 0; k < np; ++k) {
    const size_t gene = static_cast<size_t>(p.smooth[k]);
    const double gene_var = pinv(k, k) * d[k] * d[k] * scale2;
    const double sd = std::abs(space.physicalSlope(gene, out->genes)) * std::sqrt(std::max(gene_var, 0.0));
    if (null_loading[k] > 0.5 || !(d[k] > 0.0)) {
      out->unidentifiable[gene] = 1;
      continue;
    }
    out->std_devs[gene] = sd;
    if (sd > std::abs(out->values[gene])) out->unidentifiable[gene] = 1;
  }
}

/// One fit on the whole trajectory (the stages of OutputErrorOptions::grow_segments call it on
/// its first frames).
OutputErrorResult fitOnce(const Model& model, const Trajectory& trajectory,
                          const ParameterSpace& space, const std::vector<double>& start_genes,
                          const OutputErrorOptions& options) {
  const auto began = std::chrono::steady_clock::now();
  const std::function<double()> elapsed_s = [&]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  };
  OutputErrorResult out;
  out.genes = start_genes;
  out.values = space.toPhysical(start_genes);
  out.std_devs.assign(start_genes.size(), std::numeric_limits<double>::quiet_NaN());
  out.unidentifiable.assign(start_genes.size(), 0);
  if (options.segment_frames < 2 || !(options.continuity_weight > 0.0) ||
      !(options.first_continuity_weight >= 0.0) || options.grow_segments < 0) {
    out.reason = "segment_frames must be >= 2, continuity_weight > 0, first_continuity_weight >= 0 "
                 "and grow_segments >= 0";
    return out;
  }
  auto p = std::make_unique<Problem>();
  out.reason = setUpProblem(model, trajectory, space, start_genes, options, p.get(), &out);
  if (!out.reason.empty()) return out;
  SegmentUnknowns u;
  u.segments = segmentsOf(p->obs.frames, options.segment_frames);
  const int ns = p->stateSize();
  u.theta.resize(p->smooth.size());
  for (size_t j = 0; j < p->smooth.size(); ++j) u.theta[j] = start_genes[p->smooth[j]];
  u.states.assign(u.count(), std::vector<double>(ns));
  for (int s = 0; s < u.count(); ++s) dataState(*p, u.segments[s].first, u.states[s].data());
  if (options.start_state_frames > 0) fitStartStates(p.get(), options, elapsed_s, &u);

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  out.observations = buildProblem(p.get(), space, &u, &problem);
  out.segments = u.count();
  out.start_cost_m2 = u.observationCost(*p);
  ceres::Solver::Summary summary;
  out.iterations = solveWithContinuation(p.get(), options, out.noise_std_prior_m, elapsed_s, &u, &problem,
                                         &summary, &out);
  out.ran = true;
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  out.stopped_by_time = !out.converged && options.max_time_s > 0.0 && elapsed_s() >= options.max_time_s;
  out.termination = summary.message;
  out.observation_cost_m2 = u.observationCost(*p);
  for (size_t j = 0; j < p->smooth.size(); ++j) out.genes[p->smooth[j]] = u.theta[j];
  out.values = space.toPhysical(out.genes);
  // With nearly hard continuity the segment states are one trajectory's: its start state and
  // the parameters are what the observations determine.
  const int unknowns = static_cast<int>(u.theta.size()) + ns;
  const int dof = std::max(1, out.observations - unknowns);
  out.noise_std_m = std::sqrt(out.observation_cost_m2 / dof);
  if (options.estimate_std && !(options.cancel && options.cancel->load()))
    estimateStd(*p, space, options, &u, &problem, &out);
  out.wall_time_s = elapsed_s();
  return out;
}

}  // namespace

OutputErrorResult estimateOutputError(const Model& model, const Trajectory& trajectory,
                                      const ParameterSpace& space,
                                      const std::vector<double>& start_genes,
                                      const OutputErrorOptions& options) {
  const int K = options.segment_frames;
  // Nothing to grow, or options fitOnce refuses (with its reason).
  if (options.grow_segments <= 0 || K < 2 ||
      static_cast<long>(options.grow_segments) * K + 1 >= trajectory.numFrames())
    return fitOnce(model, trajectory, space, start_genes, options);
  // Continuation in the data's length: the first grow_segments segments' frames, then twice as
  // many, ..., then all, each stage from the last one's answer. One noise figure (the whole
  // data's) weights every stage; the last stage alone estimates the std.
  const auto began = std::chrono::steady_clock::now();
  const auto elapsed_s = [&]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  };
  OutputErrorOptions stage = options;
  stage.grow_segments = 0;
  if (!(stage.noise_std_m > 0.0))
    stage.noise_std_m = std::max(estimateMarkerNoise(trajectory), 1e-9);
  std::vector<double> genes = start_genes;
  int iterations = 0, stages = 0;
  double jacobian_time_s = 0.0, linear_solver_time_s = 0.0;
  for (long segments = options.grow_segments;; segments *= 2) {
    const bool last = segments * K + 1 >= trajectory.numFrames();
    stage.estimate_std = last && options.estimate_std;
    if (options.max_time_s > 0.0)
      stage.max_time_s = std::max(1e-3, options.max_time_s - elapsed_s());
    const Trajectory part =
        last ? trajectory : sliceFrames(trajectory, 0, static_cast<int>(segments * K + 1));
    OutputErrorResult r = fitOnce(model, part, space, genes, stage);
    if (!r.ran) {
      r.reason = "on the first " + std::to_string(part.numFrames()) + " frames: " + r.reason;
      return r;
    }
    iterations += r.iterations;
    jacobian_time_s += r.jacobian_time_s;
    linear_solver_time_s += r.linear_solver_time_s;
    ++stages;
    genes = r.genes;
    const bool stopped = (options.cancel && options.cancel->load()) ||
                         (options.max_time_s > 0.0 && elapsed_s() >= options.max_time_s);
    if (last || stopped) {
      // Stopped early: the answer so far, judged on the whole data (its costs are what callers
      // compare, its std what they report), with no iteration.
      if (!last) {
        stage.max_iterations = 0;
        stage.max_time_s = 0.0;
        stage.estimate_std = options.estimate_std;
        r = fitOnce(model, trajectory, space, genes, stage);
      }
      if (!last && !(options.cancel && options.cancel->load())) r.stopped_by_time = true;
      r.iterations = iterations;
      r.jacobian_time_s = jacobian_time_s;
      r.linear_solver_time_s = linear_solver_time_s;
      r.stages = stages;
      r.wall_time_s = elapsed_s();
      return r;
    }
  }
}

std::vector<double> cramerRaoBound(const Model& model, const Trajectory& trajectory,
                                   const ParameterSpace& space, double noise_std_m,
                                   int segment_frames) {
  const std::vector<double> truth = space.toSearch(getValues(model, freeParameters(model)));
  OutputErrorOptions o;
  o.segment_frames = segment_frames;
  o.noise_std_m = noise_std_m;
  o.std_from_given_noise = true;
  o.max_iterations = 20;  // only the segment states move (the data are the truth's own motion)
  const OutputErrorResult r = estimateOutputError(model, trajectory, space, truth, o);
  return r.std_devs;
}

}  // namespace mme

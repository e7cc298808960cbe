#include "motion_model_estimation/identification/muscles/sensor_muscles.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"
#include "motion_model_estimation/core/observations.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"

namespace mme {

namespace {

/// A pair of particles and its distance over the frames where both are seen.
struct PairStats {
  int a = -1, b = -1;
  double mean_m = 0.0, std_m = 0.0;
  int seen = 0;
};

std::vector<PairStats> pairStatistics(const Model& model, const Trajectory& data) {
  const int n = static_cast<int>(model.particles.size());
  std::vector<PairStats> pairs;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      if (model.particles[a].fixed && model.particles[b].fixed) continue;
      const MarkerDistance d = markerDistance(data, a, b);
      if (d.seen_frames == 0) continue;
      pairs.push_back({a, b, d.mean_m, d.std_m, d.seen_frames});
    }
  return pairs;
}

/// Where the sensors and muscles go.
struct Layout {
  std::vector<PairStats> sensors, muscles;
  /// Per muscle: its own stiffness is held at 0 (a muscle to an anchor, with
  /// SensorMuscleOptions::anchor_stiffness kNone).
  std::vector<char> no_own_stiffness;
};

/// The equation error's normal equations in the scaled columns (see the header).
struct System {
  Eigen::MatrixXd ata;
  Eigen::VectorXd atb;
  size_t rows = 0;
  double btb = 0.0;
};

class Fitter {
 public:
  Fitter(const Model& passive, const Trajectory& data, const Layout& layout, bool nonnegative_own_spring)
      : passive_(passive), data_(data), obs_(prepareObservations(passive, data)), layout_(layout), sim_(passive),
        own_spring_nonnegative_(nonnegative_own_spring),
        n_(static_cast<int>(passive.particles.size())),
        s_(static_cast<int>(layout.sensors.size())),
        m_(static_cast<int>(layout.muscles.size())), k_(2 * s_ + 3) {
    h_ = 1.0 / passive.frame_rate_hz;
    // Particles whose force depends on particle i's state: every bond's other members, or all
    // of them when bonds are installed on the fly.
    partners_.assign(n_, {});
    for (const Bond& bond : passive.bonds) {
      const int arity = kindArity(passive.bond_types[bond.type].kind);
      for (int p = 0; p < arity; ++p)
        for (int q = 0; q < arity; ++q)
          if (p != q) partners_[bond.particles[p]].push_back(bond.particles[q]);
    }
    all_partners_ = !passive.interactions.empty();
    at_.assign(n_, {});
    for (int m = 0; m < m_; ++m) {
      at_[layout.muscles[m].a].push_back({m, 1.0});
      at_[layout.muscles[m].b].push_back({m, -1.0});
    }
    computeScales();
    bound_ = RolloutBound::of(passive, obs_, 0, data.numFrames());
  }

  int unknowns() const { return m_ * k_; }

  /// Adds the equations whose window's centre t lies in [centre_begin, centre_end) and whose
  /// window (frames t - window .. t + window) lies inside the data: per particle, the one-step
  /// equations of frames t - window + 1 .. t + window - 1 summed with triangle weights
  /// window - |j| (see the header).
  void accumulate(int window, int centre_begin, int centre_end, System* sys) {
    if (sys->ata.rows() == 0) {
      sys->ata = Eigen::MatrixXd::Zero(unknowns(), unknowns());
      sys->atb = Eigen::VectorXd::Zero(unknowns());
    }
    const int first = std::max(window, centre_begin);
    const int last = std::min(centre_end, data_.numFrames() - window);  // exclusive
    if (first >= last) return;
    // The one-step pieces of frames t - window + 1 .. t + window - 1, oldest first.
    std::deque<FramePieces> ring;
    std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> g(m_);
    for (int t = first; t < last; ++t) {
      if (ring.empty()) {
        for (int f = t - window + 1; f <= t + window - 1; ++f) ring.push_back(pieces(f));
      } else {
        ring.pop_front();
        ring.push_back(pieces(t + window - 1));
      }
      for (int i = 0; i < n_; ++i) {
        bool ok = true;
        for (const FramePieces& f : ring) ok = ok && f.particle_ok[i];
        if (!ok) continue;
        const double mass = passive_.particles[i].mass_kg;
        Eigen::Vector3d y = Eigen::Vector3d::Zero();
        for (const auto& [m, sign] : at_[i]) g[m].setZero(3, k_);
        for (int j = 0; j < 2 * window - 1; ++j) {
          const FramePieces& f = ring[j];
          const double w = window - std::abs(j - (window - 1));
          y += w * f.y[i];
          for (const auto& [m, sign] : at_[i]) g[m].noalias() += (w * sign / mass) * f.u[m] * f.phi.col(m).transpose();
        }
        addEquation(i, g, y, sys);
      }
    }
  }

  /// Starts and rollouts of one round of rollout equations.
  struct RolloutCount {
    int starts = 0;   ///< rollouts run
    int filled = 0;   ///< of which a particle was placed from its neighbours (startState)
    int stopped = 0;  ///< rollouts stopped early: non-finite, or farther from the data than
                      ///< the data's extent (their later rows would only carry the blow-up)
  };

  /// Adds the equations of the model's own open-loop predictions (Data as Demonstrator,
  /// Venkatraman et al. 2015): from every `stride`-th start t in [start_begin, start_end) where
  /// every particle can be placed (startState), the model carrying theta runs horizon - 1 frames; at
  /// each predicted frame t + k the equation is written at the predicted posture and speeds,
  /// its target the data's acceleration at t + k plus a critically damped return to the data
  /// with time constant `correction_frames` (0: none). The one-step fit learns where the data go
  /// from where the data are; these rows teach it where to go from where its own errors take
  /// it, which is what a prediction k frames ahead meets.
  RolloutCount accumulateRollouts(const Eigen::VectorXd& theta, double margin, int gain_t_end, int horizon,
                         int stride, double correction_frames, int start_begin, int start_end,
                         System* sys) const {
    if (sys->ata.rows() == 0) {
      sys->ata = Eigen::MatrixXd::Zero(unknowns(), unknowns());
      sys->atb = Eigen::VectorXd::Zero(unknowns());
    }
    const Model model = build(theta, margin, gain_t_end);
    Simulator sim(model);
    const int last = std::min(start_end, data_.numFrames() - horizon);  // exclusive
    RolloutCount count;
    std::vector<Eigen::Vector3d> before, next;
    std::vector<uint8_t> occluded;
    State state;
    for (int t = std::max(start_begin, 1); t < last; t += stride) {
      int filled = 0;
      if (!startState(t, &state, &filled)) continue;
      ++count.starts;
      if (filled > 0) ++count.filled;
      for (int k = 1; k < horizon; ++k) {
        before = state.x_m;
        sim.stepFrame(&state, h_);
        bool near = true;
        for (int i = 0; i < n_ && near; ++i)
          near = state.x_m[i].allFinite() &&
                 (data_.isOccluded(t + k, i) || (state.x_m[i] - data_.position(t + k, i)).norm() <= bound_.extent_m);
        if (!near) {
          ++count.stopped;
          break;
        }
        // The target: the data's acceleration at t + k, plus a correction that would bring the
        // prediction back to the data with time constant tau (critically damped), not in one
        // step (a one-step return asks for accelerations of drift / h^2: high-gain feedback).
        const Frames3 d = dataFrames(t + k);
        next.resize(n_);
        occluded.assign(n_, 0);
        for (int i = 0; i < n_; ++i) {
          if (!d.seen(0, i) || !d.seen(1, i) || !d.seen(2, i)) {
            occluded[i] = 1;
            continue;
          }
          const Eigen::Vector3d& x0 = d.x[0][i];
          const Eigen::Vector3d& x1 = d.x[1][i];
          const Eigen::Vector3d& x2 = d.x[2][i];
          Eigen::Vector3d acc = (x2 - 2.0 * x1 + x0) / (h_ * h_);
          if (correction_frames > 0.0) {
            const double tau = correction_frames * h_;
            acc -= (state.x_m[i] - x1) / (tau * tau) +
                   (2.0 / tau) * ((state.x_m[i] - before[i]) - (x1 - x0)) / h_;
          }
          next[i] = acc * h_ * h_ + 2.0 * state.x_m[i] - before[i];
        }
        Frames3 f;
        f.x[0] = before.data();
        f.x[1] = state.x_m.data();
        f.x[2] = next.data();
        f.occluded[2] = occluded.data();
        addPieces(pieces(f), sys);
      }
    }
    return count;
  }

  /// The state a rollout starts from at frame t: a particle seen at t - 1 and t at its position
  /// there, its velocity their difference; one unseen at either placed by the rigid motion of its
  /// nearest neighbours from the nearest frame where it was seen, earlier or later
  /// (fillFromNeighbours; `filled` counts these), as evaluatePredictions fills its starts; a
  /// fixed one where the model holds it when unseen. False when a particle cannot be placed.
  bool startState(int t, State* state, int* filled) const {
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

  /// Whether `model` stays near the data when run open loop `rollout_frames` long from `starts`
  /// frames spread evenly over the data (startState's states): within the RolloutBound of the
  /// frames from `box_first_frame` on, as evaluatePredictions bounds its one rollout by the
  /// frames it judges. A model's instability can depend on where it starts; the held-out test
  /// starts where the data end.
  bool boundedFromEverywhere(const Model& model, int starts, int rollout_frames,
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

  /// theta for a relative ridge, every muscle's own stiffness and damping >= 0 (when
  /// own_spring_nonnegative_); false when a solve fails. The signs by an active set that only
  /// grows: a negative stiffness or damping is held at 0 and the rest solved again, until none
  /// is negative (at most kMaxClampRounds solves; what is still negative then is set to 0).
  /// The ridge is relative to `reference_diagonal` when > 0 (to keep a ridge's weight when rows
  /// are added), else to the system's own mean diagonal.
  bool solve(const System& sys, double ridge, Eigen::VectorXd* theta, double reference_diagonal = 0.0) const {
    constexpr int kMaxClampRounds = 6;
    const double mean_diagonal = reference_diagonal > 0.0 ? reference_diagonal : meanDiagonal(sys);
    std::vector<int> clamped;
    for (int m = 0; m < m_; ++m)
      if (layout_.no_own_stiffness[m]) clamped.push_back(m * k_ + 2 * s_ + 1);
    for (int round = 0;; ++round) {
      Eigen::MatrixXd a = sys.ata;
      a.diagonal().array() += ridge * mean_diagonal;
      Eigen::VectorXd b = sys.atb;
      for (int j : clamped) {
        a.row(j).setZero();
        a.col(j).setZero();
        a(j, j) = 1.0;
        b(j) = 0.0;
      }
      Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(a);  // in place: one copy of the matrix
      if (llt.info() != Eigen::Success) return false;
      *theta = llt.solve(b);
      if (!theta->allFinite()) return false;
      if (!own_spring_nonnegative_) return true;
      bool changed = false;
      for (int m = 0; m < m_; ++m)
        for (int j = m * k_ + 2 * s_ + 1; j <= m * k_ + 2 * s_ + 2; ++j)
          if ((*theta)(j) < 0.0) {
            if (round + 1 < kMaxClampRounds) clamped.push_back(j);
            else (*theta)(j) = 0.0;
            changed = true;
          }
      if (!changed || round + 1 >= kMaxClampRounds) return true;
    }
  }

  /// The mean diagonal of a system's normal matrix (the ridges' reference).
  static double meanDiagonal(const System& sys) { return std::max(sys.ata.diagonal().mean(), 1e-300); }

  /// RMS of a system's rows at theta [m/s^2].
  static double residualRms(const System& sys, const Eigen::VectorXd& theta) {
    if (sys.rows == 0) return 0.0;
    const double r2 = sys.btb - 2.0 * theta.dot(sys.atb) + theta.dot(sys.ata * theta);
    return std::sqrt(std::max(0.0, r2) / static_cast<double>(sys.rows));
  }

  /// The passive model with sensors and muscles carrying theta (scaled columns), every gain
  /// `margin` x its muscle's largest linear activation over frames [0, t_end).
  Model build(const Eigen::VectorXd& theta, double margin, int t_end,
              double activation_time_s = 0.0) const {
    Model model = passive_;
    std::set<std::string> type_names, bond_names;
    for (const BondType& type : model.bond_types) type_names.insert(type.name);
    for (const Bond& bond : model.bonds)
      if (!bond.name.empty()) bond_names.insert(bond.name);
    auto unique = [](std::set<std::string>* names, std::string name) {
      while (names->count(name)) name += "_";
      names->insert(name);
      return name;
    };
    auto fixed = [](double value) {
      Param p;
      p.present = p.has_value = true;
      p.free = false;
      p.value = value;
      return p;
    };
    std::vector<int> sensor_bonds;
    for (int s = 0; s < s_; ++s) {
      const PairStats& pair = layout_.sensors[s];
      const std::string stem = "sensor_" + model.particles[pair.a].name + "_" + model.particles[pair.b].name;
      BondType type;
      type.name = unique(&type_names, stem);
      type.kind = BondKind::kSpring;
      type.param(kStiffness) = fixed(0.0);
      type.param(kRestLength) = fixed(pair.mean_m);
      model.bond_types.push_back(type);
      Bond bond;
      bond.type = static_cast<int>(model.bond_types.size()) - 1;
      bond.particles = {{pair.a, pair.b, -1}};
      bond.name = unique(&bond_names, stem);
      model.bonds.push_back(bond);
      sensor_bonds.push_back(static_cast<int>(model.bonds.size()) - 1);
    }
    // Each muscle's largest linear activation over the fitted frames sets its gain.
    std::vector<double> largest(m_, 0.0);
    for (int t = 1; t < std::min(t_end, data_.numFrames()); ++t) {
      Eigen::VectorXd z;
      if (!sensorInputs(dataFrames(t), &z)) continue;
      const Eigen::VectorXd scaled = z.cwiseQuotient(z_scale_);
      for (int m = 0; m < m_; ++m) {
        const double y = theta.segment(m * k_, 2 * s_).dot(scaled) + theta(m * k_ + 2 * s_);
        largest[m] = std::max(largest[m], std::abs(y));
      }
    }
    for (int m = 0; m < m_; ++m) {
      const PairStats& pair = layout_.muscles[m];
      const Eigen::VectorXd th = theta.segment(m * k_, k_);
      const double gain = largest[m] > 0.0 ? margin * largest[m] : 1.0;
      BondType type;
      type.name = unique(&type_names, "muscle_" + model.particles[pair.a].name + "_" +
                                          model.particles[pair.b].name);
      type.kind = BondKind::kMuscle;
      type.param(kStiffness) = fixed(th(2 * s_ + 1) / e_scale_[m]);
      type.param(kRestLength) = fixed(pair.mean_m);
      type.param(kDamping) = fixed(th(2 * s_ + 2) / s_scale_[m]);
      type.param(kGain) = fixed(gain);
      if (activation_time_s > 0.0) type.param(kActivationTime) = fixed(activation_time_s);
      type.network_inputs = s_;
      type.network_hidden = 0;
      type.network.assign(muscleNetworkSize(s_, 0), Param{});
      for (int j = 0; j < 2 * s_; ++j) type.network[j] = fixed(th(j) / z_scale_(j) / gain);
      type.network[2 * s_] = fixed(th(2 * s_) / gain);
      model.bond_types.push_back(type);
      Bond bond;
      bond.type = static_cast<int>(model.bond_types.size()) - 1;
      bond.particles = {{pair.a, pair.b, -1}};
      bond.inputs = sensor_bonds;
      model.bonds.push_back(bond);
    }
    const std::string problem = validateModel(model);
    if (!problem.empty()) throw InputError("sensor muscles: " + problem);
    return model;
  }

 private:
  /// One frame's one-step equations: per particle, usable (see usable()) and a - F_passive / m
  /// from the frame differences; per muscle, its ends seen, its unit vector and its scaled
  /// regressors (the sensor inputs, 1, its elongation and speed).
  struct FramePieces {
    std::vector<char> particle_ok, muscle_ok;
    std::vector<Eigen::Vector3d> y, u;
    Eigen::MatrixXd phi;  // k x muscles
  };

  /// Three consecutive frames (before, now, after): positions and occlusion flags per particle
  /// (x[k] null: that frame is outside the data; occluded[k] null: every particle seen).
  struct Frames3 {
    const Eigen::Vector3d* x[3] = {nullptr, nullptr, nullptr};
    const uint8_t* occluded[3] = {nullptr, nullptr, nullptr};
    bool seen(int k, int i) const { return x[k] && (!occluded[k] || !occluded[k][i]); }
  };

  /// Frames t-1, t, t+1 of the data.
  Frames3 dataFrames(int t) const {
    Frames3 f;
    const int n = data_.numMarkers();
    for (int k = 0; k < 3; ++k) {
      const int frame = t - 1 + k;
      if (frame < 0 || frame >= data_.numFrames()) continue;
      f.x[k] = &data_.positions_m[static_cast<size_t>(frame) * n];
      f.occluded[k] = &data_.occluded[static_cast<size_t>(frame) * n];
    }
    return f;
  }

  FramePieces pieces(int t) const {
    if (t < 1 || t + 1 >= data_.numFrames()) return emptyPieces();
    return pieces(dataFrames(t));
  }

  FramePieces emptyPieces() const {
    FramePieces f;
    f.particle_ok.assign(n_, 0);
    f.muscle_ok.assign(m_, 0);
    f.y.assign(n_, Eigen::Vector3d::Zero());
    f.u.assign(m_, Eigen::Vector3d::Zero());
    f.phi = Eigen::MatrixXd::Zero(k_, m_);
    return f;
  }

  /// The one-step equations of the middle frame of `frames` (its acceleration from all three).
  FramePieces pieces(const Frames3& frames) const {
    FramePieces f = emptyPieces();
    Eigen::VectorXd z;
    if (!sensorInputs(frames, &z)) return f;
    const State state = stateAt(frames);
    std::vector<Eigen::Vector3d> forces;
    sim_.computeForces(state, &forces);
    const Eigen::VectorXd scaled = z.cwiseQuotient(z_scale_);
    for (int m = 0; m < m_; ++m) {
      double e = 0.0, s = 0.0;
      f.muscle_ok[m] = muscleGeometry(frames, m, state, &f.u[m], &e, &s);
      if (!f.muscle_ok[m]) continue;
      f.phi.col(m).head(2 * s_) = scaled;
      f.phi(2 * s_, m) = 1.0;
      f.phi(2 * s_ + 1, m) = e / e_scale_[m];
      f.phi(2 * s_ + 2, m) = s / s_scale_[m];
    }
    for (int i = 0; i < n_; ++i) {
      if (!usable(frames, i, f.muscle_ok)) continue;
      f.particle_ok[i] = 1;
      const Eigen::Vector3d acc = (frames.x[2][i] - 2.0 * frames.x[1][i] + frames.x[0][i]) / (h_ * h_);
      f.y[i] = acc - forces[i] / passive_.particles[i].mass_kg;
    }
    return f;
  }

  /// Adds one frame's equations (window 1).
  void addPieces(const FramePieces& f, System* sys) const {
    std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> g(m_);
    for (int i = 0; i < n_; ++i) {
      if (!f.particle_ok[i]) continue;
      const double mass = passive_.particles[i].mass_kg;
      for (const auto& [m, sign] : at_[i]) g[m] = (sign / mass) * f.u[m] * f.phi.col(m).transpose();
      addEquation(i, g, f.y[i], sys);
    }
  }

  /// Adds particle i's three rows y = sum over its muscles of g[m] theta_m to the normal
  /// equations.
  void addEquation(int i, const std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>>& g,
                   const Eigen::Vector3d& y, System* sys) const {
    sys->btb += y.squaredNorm();
    sys->rows += 3;
    for (const auto& [m, sign] : at_[i]) {
      sys->atb.segment(m * k_, k_).noalias() += g[m].transpose() * y;
      for (const auto& [m2, sign2] : at_[i])
        sys->ata.block(m * k_, m2 * k_, k_, k_).noalias() += g[m].transpose() * g[m2];
    }
  }

  /// Positions now and velocities (now - before) / h where seen; zeros elsewhere.
  State stateAt(const Frames3& f) const {
    State s;
    s.x_m.assign(n_, Eigen::Vector3d::Zero());
    s.v_mps.assign(n_, Eigen::Vector3d::Zero());
    for (int i = 0; i < n_; ++i) {
      if (!f.seen(1, i)) continue;
      s.x_m[i] = f.x[1][i];
      if (f.seen(0, i)) s.v_mps[i] = (f.x[1][i] - f.x[0][i]) / h_;
    }
    return s;
  }

  /// The 2S network inputs now (elongations from the sensors' rest lengths, then speeds along
  /// them); false when a sensor's particle is unseen now or before.
  bool sensorInputs(const Frames3& f, Eigen::VectorXd* z) const {
    z->resize(2 * s_);
    for (int s = 0; s < s_; ++s) {
      const PairStats& p = layout_.sensors[s];
      if (!f.seen(1, p.a) || !f.seen(1, p.b) || !f.seen(0, p.a) || !f.seen(0, p.b)) return false;
      const Eigen::Vector3d d = f.x[1][p.b] - f.x[1][p.a];
      const double l = d.norm();
      if (!(l > 0.0)) return false;
      const Eigen::Vector3d u = d / l;
      const Eigen::Vector3d dv = (f.x[1][p.b] - f.x[0][p.b] - f.x[1][p.a] + f.x[0][p.a]) / h_;
      (*z)(s) = l - p.mean_m;
      (*z)(s_ + s) = dv.dot(u);
    }
    return true;
  }

  /// Unit vector a->b, elongation from the mean length and speed of muscle m now; false when an
  /// end is unseen now or before.
  bool muscleGeometry(const Frames3& f, int m, const State& state, Eigen::Vector3d* u, double* e,
                      double* s) const {
    const PairStats& p = layout_.muscles[m];
    if (!f.seen(1, p.a) || !f.seen(1, p.b) || !f.seen(0, p.a) || !f.seen(0, p.b)) return false;
    const Eigen::Vector3d d = state.x_m[p.b] - state.x_m[p.a];
    const double l = d.norm();
    if (!(l > 0.0)) return false;
    *u = d / l;
    *e = l - p.mean_m;
    *s = (state.v_mps[p.b] - state.v_mps[p.a]).dot(*u);
    return true;
  }

  /// Particle i gives an equation: seen before, now and after, not fixed, its passive partners
  /// and every muscle at it seen before and now.
  bool usable(const Frames3& f, int i, const std::vector<char>& muscle_ok) const {
    if (passive_.particles[i].fixed || at_[i].empty()) return false;
    if (!f.seen(0, i) || !f.seen(1, i) || !f.seen(2, i)) return false;
    if (all_partners_) {
      for (int j = 0; j < n_; ++j)
        if (!f.seen(1, j) || !f.seen(0, j)) return false;
    }
    for (int j : partners_[i])
      if (!f.seen(1, j) || !f.seen(0, j)) return false;
    for (const auto& entry : at_[i])
      if (!muscle_ok[entry.first]) return false;
    return true;
  }

  /// Column scales: the RMS of each sensor input and of each muscle's elongation and speed over
  /// the frames (1 where they are 0 or unseen).
  void computeScales() {
    Eigen::VectorXd z2 = Eigen::VectorXd::Zero(2 * s_);
    int frames = 0;
    std::vector<double> e2(m_, 0.0), s2(m_, 0.0);
    std::vector<int> count(m_, 0);
    for (int t = 1; t < data_.numFrames(); ++t) {
      const Frames3 f = dataFrames(t);
      Eigen::VectorXd z;
      if (sensorInputs(f, &z)) {
        z2 += z.cwiseAbs2();
        ++frames;
      }
      const State state = stateAt(f);
      for (int m = 0; m < m_; ++m) {
        Eigen::Vector3d u;
        double e = 0.0, s = 0.0;
        if (!muscleGeometry(f, m, state, &u, &e, &s)) continue;
        e2[m] += e * e;
        s2[m] += s * s;
        ++count[m];
      }
    }
    auto scale = [](double sum2, int count) {
      const double rms = count > 0 ? std::sqrt(sum2 / count) : 0.0;
      return rms > 1e-12 ? rms : 1.0;
    };
    z_scale_.resize(2 * s_);
    for (int j = 0; j < 2 * s_; ++j) z_scale_(j) = scale(z2(j), frames);
    e_scale_.resize(m_);
    s_scale_.resize(m_);
    for (int m = 0; m < m_; ++m) {
      e_scale_[m] = scale(e2[m], count[m]);
      s_scale_[m] = scale(s2[m], count[m]);
    }
  }

  const Model& passive_;
  const Trajectory& data_;
  const Observations obs_;  ///< data_ as the neighbour fill reads it
  const Layout& layout_;
  mutable Simulator sim_;  // computeForces keeps scratch
  bool own_spring_nonnegative_;  ///< see solve()
  int n_, s_, m_, k_;
  double h_ = 0.0;
  RolloutBound bound_;  ///< the free particles' box over the data (its diagonal: the data's extent)
  std::vector<std::vector<int>> partners_;
  bool all_partners_ = false;
  std::vector<std::vector<std::pair<int, double>>> at_;  ///< per particle: (muscle, sign)
  Eigen::VectorXd z_scale_;
  std::vector<double> e_scale_, s_scale_;
};

/// Unknowns at most: the normal matrix and its factor are two dense squares of this size
/// (2 x 1.6 GB at 14000).
constexpr size_t kMaxUnknowns = 14000;

/// The sensor muscles are kept when they predict the validation frames better than the passive
/// model by this share of the larger of its and the constant-velocity guess's errors.
constexpr double kKeepMargin = 0.01;

/// A relative ridge as the progress lines write it ("3e+00").
std::string formatRidge(double ridge) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.0e", ridge);
  return text;
}

/// Sensors and muscles; `anchor` flags the particles addAnchors added (no sensor, no neighbour).
Layout chooseLayout(const Model& passive, const Trajectory& data, const std::vector<char>& anchor,
                    const SensorMuscleOptions& o) {
  const std::vector<PairStats> pairs = pairStatistics(passive, data);
  const int well_seen = static_cast<int>(std::ceil(o.min_seen_share * data.numFrames()));
  Layout layout;
  std::vector<PairStats> ranked;
  for (const PairStats& p : pairs)
    if (p.seen >= well_seen && !anchor[p.a] && !anchor[p.b]) ranked.push_back(p);
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const PairStats& x, const PairStats& y) { return x.std_m > y.std_m; });
  for (int k = 0; k < o.sensors && k < static_cast<int>(ranked.size()); ++k)
    layout.sensors.push_back(ranked[k]);
  // Muscles: the model's two-particle bonds with an elongation, the sensor pairs, every particle
  // to its nearest neighbours and to each anchor; one muscle per pair.
  std::set<std::pair<int, int>> taken;
  auto stats = [&](int a, int b) -> const PairStats* {
    if (a > b) std::swap(a, b);
    for (const PairStats& p : pairs)
      if (p.a == a && p.b == b) return &p;
    return nullptr;
  };
  auto add = [&](int a, int b) {
    if (a == b) return;
    if (a > b) std::swap(a, b);
    if (taken.count({a, b})) return;
    const PairStats* p = stats(a, b);
    if (!p || !(p->mean_m > 0.0)) return;
    taken.insert({a, b});
    layout.muscles.push_back(*p);
    layout.no_own_stiffness.push_back((anchor[a] || anchor[b]) &&
                                      o.anchor_stiffness == AnchorStiffness::kNone);
  };
  for (const Bond& bond : passive.bonds)
    if (bondKindInfo(passive.bond_types[bond.type].kind).has_elongation)
      add(bond.particles[0], bond.particles[1]);
  for (const PairStats& p : layout.sensors) add(p.a, p.b);
  const int n = static_cast<int>(passive.particles.size());
  for (int i = 0; i < n; ++i) {
    if (passive.particles[i].fixed) continue;
    std::vector<std::pair<double, int>> near;
    for (const PairStats& p : pairs)
      if (p.seen >= well_seen && (p.a == i || p.b == i) && !anchor[p.a] && !anchor[p.b])
        near.push_back({p.mean_m, p.a == i ? p.b : p.a});
    std::sort(near.begin(), near.end());
    for (int k = 0; k < o.neighbours && k < static_cast<int>(near.size()); ++k) add(i, near[k].second);
    for (int a = 0; a < n; ++a)
      if (anchor[a]) add(i, a);
  }
  return layout;
}

/// Adds the anchors (see the header) to a copy of the model and of the data: three fixed
/// particles at the free particles' mean position over the data plus `extents` x their
/// bounding-box diagonal along x, y and z, seen in every frame. Returns the flags per particle.
std::vector<char> addAnchors(Model* model, Trajectory* data, double extents) {
  const int n = static_cast<int>(model->particles.size()), frames = data->numFrames();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  long seen = 0;
  for (int t = 0; t < frames; ++t)
    for (int i = 0; i < n; ++i)
      if (!model->particles[i].fixed && !data->isOccluded(t, i)) {
        const Eigen::Vector3d& x = data->position(t, i);
        sum += x;
        lo = lo.cwiseMin(x);
        hi = hi.cwiseMax(x);
        ++seen;
      }
  if (seen == 0) throw InputError("sensor muscles: no free particle is ever seen");
  const Eigen::Vector3d centre = sum / static_cast<double>(seen);
  const double distance_m = extents * std::max((hi - lo).norm(), 1e-3);
  std::set<std::string> names;
  for (const Particle& p : model->particles) names.insert(p.name);
  Trajectory out;
  out.marker_names = data->marker_names;
  out.frame_rate_hz = data->frame_rate_hz;
  std::vector<Eigen::Vector3d> at;
  for (int k = 0; k < 3; ++k) {
    Particle p;
    p.name = std::string("anchor_") + "xyz"[k];
    while (names.count(p.name)) p.name += "_";
    names.insert(p.name);
    p.fixed = true;
    p.position_m = centre + distance_m * Eigen::Vector3d::Unit(k);
    model->particles.push_back(p);
    out.marker_names.push_back(p.name);
    at.push_back(p.position_m);
  }
  out.resize(frames);
  out.times_s = data->times_s;
  out.frame_numbers = data->frame_numbers;
  const int m = out.numMarkers();
  for (int t = 0; t < frames; ++t) {
    for (int i = 0; i < n; ++i) {
      out.position(t, i) = data->position(t, i);
      out.occluded[static_cast<size_t>(t) * m + i] = data->occluded[static_cast<size_t>(t) * n + i];
    }
    for (int k = 0; k < 3; ++k) {
      out.position(t, n + k) = at[k];
      out.occluded[static_cast<size_t>(t) * m + n + k] = 0;
    }
  }
  *data = std::move(out);
  std::vector<char> anchor(n + 3, 0);
  for (int k = 0; k < 3; ++k) anchor[n + k] = 1;
  return anchor;
}

/// A progress line to the caller, when it asked for them.
void say(const SensorMuscleOptions& o, const std::string& line) {
  if (o.progress) o.progress(line);
}

/// SensorMuscleOptions::max_time_s, counted from the start of addSensorMuscles; it remembers
/// whether it stopped a step (SensorMuscleResult::stopped_by_time).
class Budget {
 public:
  explicit Budget(double max_time_s) : max_time_s_(max_time_s), start_(std::chrono::steady_clock::now()) {}
  double elapsedS() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  bool spent() const { return max_time_s_ > 0.0 && elapsedS() >= max_time_s_; }
  /// spent(), and when so a progress line saying what is not started (`what`).
  bool stops(const SensorMuscleOptions& o, const std::string& what) {
    if (!spent()) return false;
    stopped_ = true;
    char line[240];
    std::snprintf(line, sizeof(line), "sensor muscles: time limit of %g s spent (%.1f s): no %s",
                  max_time_s_, elapsedS(), what.c_str());
    say(o, line);
    return true;
  }
  bool stopped() const { return stopped_; }  ///< stops() has stopped a step

 private:
  double max_time_s_;
  std::chrono::steady_clock::time_point start_;
  bool stopped_ = false;
};

SensorMuscleResult fitSensorMuscles(const Model& passive, const Trajectory& data,
                                    const std::vector<char>& anchor, const SensorMuscleOptions& o,
                                    Budget& budget);

}  // namespace

double bodyTravel(const Model& model, const Trajectory& data) {
  const int n = std::min(static_cast<int>(model.particles.size()), data.numMarkers());
  const double inf = std::numeric_limits<double>::infinity();
  auto median = [](std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  std::vector<Eigen::Vector3d> lo(n, Eigen::Vector3d::Constant(inf)), hi(n, Eigen::Vector3d::Constant(-inf));
  std::vector<double> sizes;
  for (int t = 0; t < data.numFrames(); ++t) {
    Eigen::Vector3d frame_lo = Eigen::Vector3d::Constant(inf), frame_hi = Eigen::Vector3d::Constant(-inf);
    int seen = 0;
    for (int i = 0; i < n; ++i) {
      if (model.particles[i].fixed || data.isOccluded(t, i)) continue;
      const Eigen::Vector3d x = data.position(t, i);
      lo[i] = lo[i].cwiseMin(x);
      hi[i] = hi[i].cwiseMax(x);
      frame_lo = frame_lo.cwiseMin(x);
      frame_hi = frame_hi.cwiseMax(x);
      ++seen;
    }
    if (seen >= 2) sizes.push_back((frame_hi - frame_lo).norm());
  }
  std::vector<double> ranges;
  for (int i = 0; i < n; ++i)
    if (hi[i].x() >= lo[i].x()) ranges.push_back((hi[i] - lo[i]).norm());
  const double size = median(sizes);
  return size > 0.0 ? median(ranges) / size : 0.0;
}

SensorMuscleResult addSensorMuscles(const Model& passive, const Trajectory& data,
                                    const SensorMuscleOptions& o) {
  if (o.sensors < 1 || o.sensors > kMaxMuscleInputs)
    throw InputError("sensor muscles: sensors must be 1.." + std::to_string(kMaxMuscleInputs) +
                     ", got " + std::to_string(o.sensors));
  if (o.neighbours < 0 || o.neighbours > 64)
    throw InputError("sensor muscles: neighbours must be 0..64, got " + std::to_string(o.neighbours));
  if (o.windows_frames.empty()) throw InputError("sensor muscles: no candidate window");
  for (int w : o.windows_frames)
    if (w < 1 || w > 100) throw InputError("sensor muscles: every window must be 1..100 frames, got " + std::to_string(w));
  if (o.ridges.empty())
    throw InputError("sensor muscles: no candidate ridge");
  for (double r : o.ridges)
    if (!(r > 0.0) || !std::isfinite(r))
      throw InputError("sensor muscles: every ridge must be a finite number > 0");
  if (!(o.validation_fraction > 0.0 && o.validation_fraction < 0.5))
    throw InputError("sensor muscles: the validation fraction must be in (0, 0.5)");
  if (o.horizon_frames < 1) throw InputError("sensor muscles: the horizon must be >= 1 frame");
  if (!(o.gain_margin >= 1.0) || !std::isfinite(o.gain_margin))
    throw InputError("sensor muscles: the gain margin must be a finite number >= 1");
  if (o.rollout_rounds < 0 || o.rollout_rounds > 20)
    throw InputError("sensor muscles: rollout rounds must be 0..20, got " + std::to_string(o.rollout_rounds));
  if (o.rollout_lower_ridges < 0 || o.rollout_lower_ridges > 20)
    throw InputError("sensor muscles: rollout_lower_ridges must be 0..20, got " +
                     std::to_string(o.rollout_lower_ridges));
  if (o.rollout_stride_frames < 1)
    throw InputError("sensor muscles: the rollout stride must be >= 1 frame, got " +
                     std::to_string(o.rollout_stride_frames));
  if (!(o.rollout_correction_frames >= 0.0) || !std::isfinite(o.rollout_correction_frames))
    throw InputError("sensor muscles: the rollout correction time must be a finite number >= 0 frames");
  if (!(o.anchor_distance_extents >= 1.0) || !std::isfinite(o.anchor_distance_extents))
    throw InputError("sensor muscles: the anchors' distance must be a finite number >= 1 extent");
  for (double tau_frames : o.activation_times_frames)
    if (!(tau_frames >= 0.0) || !std::isfinite(tau_frames))
      throw InputError("sensor muscles: the activation time constants must be finite numbers >= 0 "
                       "frames, got " + std::to_string(tau_frames));
  if (!(o.min_seen_share >= 0.0 && o.min_seen_share <= 1.0))
    throw InputError("sensor muscles: min_seen_share must be in [0, 1]");
  if (!(o.max_time_s >= 0.0) || !std::isfinite(o.max_time_s))
    throw InputError("sensor muscles: the time limit must be a finite number >= 0 s (0: none)");
  if (o.max_unknowns < 1 || o.max_unknowns > kMaxUnknowns)
    throw InputError("sensor muscles: max_unknowns must be 1.." + std::to_string(kMaxUnknowns) + ", got " +
                     std::to_string(o.max_unknowns));
  if (!(passive.frame_rate_hz > 0.0)) throw InputError("sensor muscles: the model has no frame rate");
  const int n = static_cast<int>(passive.particles.size());
  if (data.numMarkers() != n)
    throw InputError("sensor muscles: the data have " + std::to_string(data.numMarkers()) +
                     " markers, the model " + std::to_string(n) + " particles");
  for (int i = 0; i < n; ++i)
    if (data.marker_names[i] != passive.particles[i].name)
      throw InputError("sensor muscles: marker " + std::to_string(i) + " is '" + data.marker_names[i] +
                       "', the model's particle '" + passive.particles[i].name + "'");
  for (const ParamRef& ref : freeParameters(passive))
    if (!paramOf(passive, ref).has_value)
      throw InputError("sensor muscles: the passive model's '" + ref.name + "' has no value (identify it first)");
  if (!(o.travel_body_sizes > 0.0) || !std::isfinite(o.travel_body_sizes))
    throw InputError("sensor muscles: travel_body_sizes must be a finite number > 0");
  Budget budget(o.max_time_s);
  const auto timed = [&](SensorMuscleResult r) {
    r.wall_time_s = budget.elapsedS();
    r.stopped_by_time = budget.stopped();
    return r;
  };
  if (!o.anchors) return timed(fitSensorMuscles(passive, data, std::vector<char>(n, 0), o, budget));
  // The anchor muscles' own stiffness (see the header): kAuto decided here, once for both layouts.
  const double travel = bodyTravel(passive, data);
  SensorMuscleOptions resolved = o;
  if (o.anchor_stiffness == AnchorStiffness::kAuto) {
    const bool tied = std::any_of(passive.particles.begin(), passive.particles.end(),
                                  [](const Particle& p) { return p.fixed; });
    resolved.anchor_stiffness = !tied && travel >= o.travel_body_sizes ? AnchorStiffness::kNone
                                                                        : AnchorStiffness::kFitted;
    if (o.progress) {
      char line[240];
      std::snprintf(line, sizeof(line), "sensor muscles: the body travels %.2f body sizes over the data%s: "
                    "anchor muscles %s", travel, tied ? " (and the model ties it to the world)" : "",
                    resolved.anchor_stiffness == AnchorStiffness::kNone
                    ? "without a stiffness of their own" : "with a stiffness of their own");
      o.progress(line);
    }
  }
  const bool anchor_stiffness = resolved.anchor_stiffness == AnchorStiffness::kFitted;
  const auto tagged = [&](SensorMuscleResult r) {
    r.anchor_stiffness = r.anchors && anchor_stiffness;
    r.body_travel = travel;
    return timed(std::move(r));
  };
  Model anchored = passive;
  Trajectory anchored_data = data;
  const std::vector<char> anchor = addAnchors(&anchored, &anchored_data, o.anchor_distance_extents);
  if (!o.anchors_by_validation) {
    SensorMuscleResult with = fitSensorMuscles(anchored, anchored_data, anchor, resolved, budget);
    with.anchors = true;
    return tagged(with);
  }
  // Both layouts, judged on the same validation frames: the anchors' extra unknowns fit noise
  // on a small body whose controller lives between its particles, and push along the world
  // where a walk's accelerations live. A layout too large to fit (max_unknowns) or without a
  // usable fit leaves the other.
  std::optional<SensorMuscleResult> with, without;
  try {
    say(o, "sensor muscles: with anchors");
    with = fitSensorMuscles(anchored, anchored_data, anchor, resolved, budget);
    with->anchors = true;
  } catch (const InputError& e) {
    say(o, std::string("sensor muscles: with anchors: ") + e.what());
  }
  if (with && budget.stops(o, "fit without anchors (the fit with them is kept)")) return tagged(*with);
  say(o, "sensor muscles: without anchors");
  try {
    without = fitSensorMuscles(passive, data, std::vector<char>(n, 0), resolved, budget);
  } catch (const InputError& e) {
    if (!with) throw;
    say(o, std::string("sensor muscles: without anchors: ") + e.what());
  }
  if (!with) return tagged(*without);
  if (!without) return tagged(*with);
  const bool plain_better =
      (without->better_than_passive && !with->better_than_passive) ||
      (without->better_than_passive == with->better_than_passive &&
       without->validation_rms_m < with->validation_rms_m);
  char line[200];
  std::snprintf(line, sizeof(line), "sensor muscles: %s anchors (validation %.2f mm, %s %.2f mm)",
                plain_better ? "without" : "with", 1e3 * (plain_better ? without : with)->validation_rms_m,
                plain_better ? "with them" : "without them",
                1e3 * (plain_better ? with : without)->validation_rms_m);
  say(o, line);
  return tagged(plain_better ? *without : *with);
}

namespace {

/// addSensorMuscles on a checked model and data (anchors added when asked).
SensorMuscleResult fitSensorMuscles(const Model& passive, const Trajectory& data,
                                    const std::vector<char>& anchor, const SensorMuscleOptions& o,
                                    Budget& budget) {
  const int frames = data.numFrames();
  const int validation_start = static_cast<int>(std::floor((1.0 - o.validation_fraction) * frames));
  if (validation_start < 4 || frames - validation_start < o.horizon_frames + 1)
    throw InputError("sensor muscles: " + std::to_string(frames) + " frames are too few to hold out " +
                     "a validation of " + std::to_string(o.horizon_frames) + " frames ahead");

  Layout layout = chooseLayout(passive, data, anchor, o);
  if (layout.sensors.empty())
    throw InputError("sensor muscles: no pair of particles is seen together in " +
                     std::to_string(static_cast<int>(100 * o.min_seen_share)) + " % of the frames");
  if (layout.muscles.empty()) throw InputError("sensor muscles: no pair of particles to put a muscle on");
  const auto unknownsOf = [](const Layout& l) { return l.muscles.size() * (2 * l.sensors.size() + 3); };
  // A body too large for max_unknowns reads fewer sensors (the most varying pairs are kept):
  // each muscle then has fewer unknowns, and the sensor pairs' own muscles go with them.
  while (unknownsOf(layout) > o.max_unknowns && layout.sensors.size() > 1) {
    const size_t per_muscle = o.max_unknowns / layout.muscles.size();
    SensorMuscleOptions fewer = o;
    fewer.sensors = static_cast<int>(std::max<size_t>(
        1, std::min(layout.sensors.size() - 1, per_muscle > 3 ? (per_muscle - 3) / 2 : 1)));
    char line[200];
    std::snprintf(line, sizeof(line),
                  "sensor muscles: %zu muscles reading %zu sensors are %zu unknowns, more than %zu: "
                  "%d sensors", layout.muscles.size(), layout.sensors.size(), unknownsOf(layout),
                  o.max_unknowns, fewer.sensors);
    say(o, line);
    layout = chooseLayout(passive, data, anchor, fewer);
  }
  const size_t unknowns = unknownsOf(layout);
  if (unknowns > o.max_unknowns)
    throw InputError("sensor muscles: " + std::to_string(layout.muscles.size()) + " muscles reading " +
                     std::to_string(layout.sensors.size()) + " sensor(s) are " + std::to_string(unknowns) +
                     " unknowns, more than " + std::to_string(o.max_unknowns) +
                     " (two dense matrices of that size): fewer neighbours, or no anchors");
  Fitter fitter(passive, data, layout, o.nonnegative_own_spring);
  SensorMuscleResult result;
  result.sensors = static_cast<int>(layout.sensors.size());
  result.muscles = static_cast<int>(layout.muscles.size());
  result.unknowns = unknowns;
  {
    char line[200];
    std::snprintf(line, sizeof(line), "sensor muscles: %d sensors, %d muscles, %zu unknowns",
                  result.sensors, result.muscles, result.unknowns);
    say(o, line);
  }

  // The window and the ridge: fitted on the frames before validation_start (every window's
  // frames before it), judged on the rest.
  const std::vector<int> horizons = {o.horizon_frames};
  auto judge = [&](const Model& model, double* rms, double* cv, bool* bounded) {
    const PredictionReport report = evaluatePredictions(model, data, horizons, 10.0, validation_start);
    for (const PredictionError& row : report.rows) {
      if (row.predictor == Predictor::kModel) *rms = row.rms_m;
      if (row.predictor == Predictor::kConstantVelocity && cv) *cv = row.rms_m;
    }
    if (bounded) *bounded = report.rollout_bounded;
  };
  judge(passive, &result.passive_rms_m, &result.constant_velocity_rms_m, nullptr);
  int best = -1;
  bool any_rows = false;
  System best_sys;  // the equations of the best candidate's window, to be completed below
  std::vector<Eigen::VectorXd> thetas;  // per candidate, its validation fit (empty: the solve failed)
  // With a time limit (Budget): once spent, no further candidate after the first that gave a
  // model, no rollout round and no activation time constant; the final refits below are not cut
  // (a refit that leaves the data is common, and the next candidate's is what gives a model).
  for (int window : o.windows_frames) {
    if (best >= 0 && budget.stops(o, "further window")) break;
    System sys;
    fitter.accumulate(window, 0, validation_start - window, &sys);
    if (sys.rows == 0) continue;
    any_rows = true;
    const int window_first = static_cast<int>(result.candidates.size());
    for (double ridge : o.ridges) {
      if (best >= 0 && budget.stops(o, "further ridge")) break;
      SensorMuscleCandidate c;
      c.window_frames = window;
      c.ridge = ridge;
      Eigen::VectorXd theta;
      if (fitter.solve(sys, ridge, &theta)) {
        try {
          judge(fitter.build(theta, o.gain_margin, validation_start), &c.validation_rms_m, nullptr, &c.bounded);
        } catch (const InputError&) {
          c.validation_rms_m = std::nan("");
        }
      } else {
        theta.resize(0);
      }
      thetas.push_back(std::move(theta));
      if (!std::isfinite(c.validation_rms_m)) c.bounded = false;
      char line[240];
      std::snprintf(line, sizeof(line), "sensor muscles: window %d, ridge %.0e: %d frames ahead on "
                    "the last %d frames %.2f mm (passive %.2f mm, constant velocity %.2f mm), rollout %s",
                    window, ridge, o.horizon_frames, frames - validation_start, 1e3 * c.validation_rms_m,
                    1e3 * result.passive_rms_m, 1e3 * result.constant_velocity_rms_m,
                    c.bounded ? "bounded" : "unbounded");
      say(o, line);
      result.candidates.push_back(c);
      // Bounded candidates first, then the lowest error.
      const SensorMuscleCandidate* b = best < 0 ? nullptr : &result.candidates[best];
      const bool better = std::isfinite(c.validation_rms_m) &&
                          (!b || (c.bounded && !b->bounded) ||
                           (c.bounded == b->bounded && c.validation_rms_m < b->validation_rms_m));
      if (better) best = static_cast<int>(result.candidates.size()) - 1;
    }
    if (best >= window_first) best_sys = std::move(sys);
  }
  if (!any_rows)
    throw InputError("sensor muscles: no frame gives an equation before the validation frames "
                     "(too short, or gaps everywhere)");
  if (best < 0) throw InputError("sensor muscles: no candidate gave a model (every solve failed)");
  // Rollout equations from the best one-step candidate and, when another of its window predicted
  // the validation frames better but left its rollout unbounded, from that one too (the rollout
  // equations can bound it): each round a candidate of its own.
  // Each runs from the one-step fit theta on data_rows; the ridge stays relative to those rows'
  // mean diagonal as rollout rows are added.
  // `budgeted`: a round after the first is not started once the time limit is spent (the
  // candidates' rounds, whose first the loop over their starts gates; the final refit runs its
  // candidate's rounds all).
  auto runRounds = [&](const System& data_rows, double ridge, Eigen::VectorXd theta, int gain_t_end,
                       int start_end, int rounds, bool budgeted,
                       const std::function<void(int, const Eigen::VectorXd&, const Fitter::RolloutCount&)>& each) {
    const double reference_diagonal = Fitter::meanDiagonal(data_rows);
    System all = data_rows;
    for (int round = 1; round <= rounds; ++round) {
      if (budgeted && round > 1 && budget.stops(o, "further rollout round")) return true;
      const Fitter::RolloutCount count =
          fitter.accumulateRollouts(theta, o.gain_margin, gain_t_end, o.horizon_frames,
                                    o.rollout_stride_frames, o.rollout_correction_frames, 1, start_end, &all);
      if (!fitter.solve(all, ridge, &theta, reference_diagonal)) return false;
      each(round, theta, count);
    }
    return true;
  };
  std::vector<int> round_starts;  // candidates' indices
  if (o.rollout_rounds > 0 && result.candidates[best].window_frames == 1) {
    round_starts.push_back(best);
    int lowest = -1;
    for (int k = 0; k < static_cast<int>(result.candidates.size()); ++k) {
      const SensorMuscleCandidate& c = result.candidates[k];
      if (c.window_frames == 1 && std::isfinite(c.validation_rms_m) &&
          (lowest < 0 || c.validation_rms_m < result.candidates[lowest].validation_rms_m))
        lowest = k;
    }
    if (lowest >= 0 && result.candidates[lowest].ridge != result.candidates[best].ridge)
      round_starts.push_back(lowest);
    // The rollout rows hold the fit near the data as the ridge does, so a round's best ridge can
    // lie below the one-step fit's: the next rollout_lower_ridges ridges below the best's too.
    std::vector<int> lower;
    for (int k = 0; k < static_cast<int>(result.candidates.size()); ++k) {
      const SensorMuscleCandidate& c = result.candidates[k];
      if (c.window_frames == 1 && c.ridge < result.candidates[best].ridge &&
          std::isfinite(c.validation_rms_m))
        lower.push_back(k);
    }
    std::stable_sort(lower.begin(), lower.end(), [&](int a, int b) {
      return result.candidates[a].ridge > result.candidates[b].ridge;
    });
    for (int k = 0; k < static_cast<int>(lower.size()) && k < o.rollout_lower_ridges; ++k)
      if (std::find(round_starts.begin(), round_starts.end(), lower[k]) == round_starts.end())
        round_starts.push_back(lower[k]);
  }
  for (int index : round_starts) {
    if (budget.stops(o, "further rollout rounds")) break;
    const SensorMuscleCandidate start = result.candidates[index];
    runRounds(best_sys, start.ridge, thetas[index], validation_start,
              validation_start - o.horizon_frames - 1, o.rollout_rounds, true,
              [&](int round, const Eigen::VectorXd& theta, const Fitter::RolloutCount& count) {
                SensorMuscleCandidate c = start;
                c.rollout_rounds = round;
                c.validation_rms_m = std::nan("");
                try {
                  judge(fitter.build(theta, o.gain_margin, validation_start), &c.validation_rms_m, nullptr, &c.bounded);
                } catch (const InputError&) {
                }
                if (!std::isfinite(c.validation_rms_m)) c.bounded = false;
                char line[240];
                c.rollout_starts = count.starts;
                thetas.push_back(theta);
                std::snprintf(line, sizeof(line), "sensor muscles: ridge %.0e, rollout round %d (%d "
                              "rollouts, %d from a filled marker, %d stopped off the data): %d frames "
                              "ahead on the last %d frames %.2f mm, rollout %s", c.ridge, round,
                              count.starts, count.filled, count.stopped,
                              o.horizon_frames, frames - validation_start, 1e3 * c.validation_rms_m,
                              c.bounded ? "bounded" : "unbounded");
                say(o, line);
                result.candidates.push_back(c);
                const SensorMuscleCandidate& b = result.candidates[best];
                if (std::isfinite(c.validation_rms_m) && ((c.bounded && !b.bounded) ||
                    (c.bounded == b.bounded && c.validation_rms_m < b.validation_rms_m)))
                  best = static_cast<int>(result.candidates.size()) - 1;
              });
  }
  // The chosen candidate on every frame: the validation fit's equations plus the rest, and its
  // rounds of rollout equations run again on every frame. That refit is judged again by its own
  // rollouts, from the validation start and from 8 frames spread over the data (the last one near
  // where a held-out test starts), each bounded by the validation frames' box as a held-out test
  // is by its own frames' (the whole data's box can be larger: a body that walks in lets a
  // rollout drift farther), each final_rollout_frames long: when one leaves the data (a refit
  // can, where the validation fit did not), the next candidate of the same window (bounded in
  // validation, by validation error) is refitted instead, up to kMaxFinalFits; when none stays
  // bounded, the first is kept and reported not better than the passive model.
  constexpr int kMaxFinalFits = 4;
  constexpr int kFinalRolloutStarts = 8;
  // 10x the frames a held-out test of the same share judges when these data are its fitted part
  // (validation / (1 - share): 10x the validation frames alone is 20 % short, and a model
  // that leaves slowly passes the shorter check and fails the test: Sample02_dec's refit left
  // at 172 frames, checked over 170, judged over 180), plus the 2 frames of a start's history.
  const int final_rollout_frames = static_cast<int>(
      std::ceil(10.0 * ((frames - validation_start) / (1.0 - o.validation_fraction) + 2.0)));
  // A candidate's activation time constant: its validation fit run with each of the options'
  // time constants (its starts' activations estimated from the data, evaluatePredictions),
  // the bounded one with the lowest error kept (0, none, when none beats the fit without).
  const double frame_period_s = 1.0 / passive.frame_rate_hz;
  struct Activation {
    double time_s = 0.0;
    double validation_rms_m = 0.0;
  };
  auto chooseActivation = [&](int index) {
    const SensorMuscleCandidate& c = result.candidates[index];
    Activation chosen{0.0, c.validation_rms_m};
    if (thetas[index].size() == 0) return chosen;
    for (double tau_frames : o.activation_times_frames) {
      if (!(tau_frames > 0.0)) continue;
      if (budget.stops(o, "further activation time constant")) break;
      double rms = std::nan("");
      bool bounded = false;
      try {
        judge(fitter.build(thetas[index], o.gain_margin, validation_start, tau_frames * frame_period_s),
              &rms, nullptr, &bounded);
      } catch (const InputError&) {
      }
      char line[240];
      std::snprintf(line, sizeof(line), "sensor muscles: ridge %.0e, %d rollout round(s), activation "
                    "time constant %g frames: %d frames ahead on the last %d frames %.2f mm, rollout %s",
                    c.ridge, c.rollout_rounds, tau_frames, o.horizon_frames, frames - validation_start,
                    1e3 * rms, bounded ? "bounded" : "unbounded");
      say(o, line);
      if (bounded && std::isfinite(rms) && rms < chosen.validation_rms_m)
        chosen = {tau_frames * frame_period_s, rms};
    }
    return chosen;
  };
  const int window = result.candidates[best].window_frames;
  System& sys = best_sys;
  fitter.accumulate(window, validation_start - window, frames, &sys);
  std::vector<int> order = {best};
  for (int k = 0; k < static_cast<int>(result.candidates.size()); ++k) {
    const SensorMuscleCandidate& c = result.candidates[k];
    if (k != best && c.window_frames == window && c.bounded && std::isfinite(c.validation_rms_m))
      order.push_back(k);
  }
  std::stable_sort(order.begin() + 1, order.end(), [&](int a, int b) {
    return result.candidates[a].validation_rms_m < result.candidates[b].validation_rms_m;
  });
  if (static_cast<int>(order.size()) > kMaxFinalFits) order.resize(kMaxFinalFits);
  Eigen::VectorXd theta, first_theta;
  bool final_bounded = false;
  int accepted = best;
  Activation activation, first_activation;
  for (int index : order) {
    const SensorMuscleCandidate& c = result.candidates[index];
    Eigen::VectorXd t;
    if (!fitter.solve(sys, c.ridge, &t)) continue;
    if (c.rollout_rounds > 0) {
      say(o, "sensor muscles: ridge " + formatRidge(c.ridge) + ", " + std::to_string(c.rollout_rounds) +
          " rollout round(s) on every frame");
      if (!runRounds(sys, c.ridge, t, frames, frames, c.rollout_rounds, false,
                     [&](int, const Eigen::VectorXd& r, const Fitter::RolloutCount&) { t = r; }))
        continue;
    }
    const Activation a = chooseActivation(index);
    if (first_theta.size() == 0) {
      first_theta = t;
      first_activation = a;
    }
    double rms = 0.0;
    bool bounded = false;
    try {
      const Model model = fitter.build(t, o.gain_margin, frames, a.time_s);
      judge(model, &rms, nullptr, &bounded);
      bounded = bounded && fitter.boundedFromEverywhere(model, kFinalRolloutStarts,
                                                        final_rollout_frames, validation_start);
    } catch (const InputError&) {
    }
    if (bounded) {
      theta = t;
      activation = a;
      accepted = index;
      final_bounded = true;
      break;
    }
    say(o, "sensor muscles: ridge " + formatRidge(c.ridge) + ", " + std::to_string(c.rollout_rounds) +
        " rollout round(s), refitted on every frame: a rollout of it " +
        std::to_string(final_rollout_frames) + " frames long (from the validation start or from one "
        "of 8 frames over the data) leaves the validation frames' box; the next candidate");
  }
  if (first_theta.size() == 0) throw InputError("sensor muscles: the final solve failed");
  if (!final_bounded) {
    theta = first_theta;
    activation = first_activation;
  }
  const SensorMuscleCandidate chosen = result.candidates[accepted];
  result.chosen = accepted;
  result.window_frames = chosen.window_frames;
  result.ridge = chosen.ridge;
  result.activation_time_s = activation.time_s;
  result.validation_rms_m = activation.validation_rms_m;
  // Better by a margin: 1 % of the larger of the passive model's and the constant-velocity
  // guess's errors (the guess gives the motion's scale). Where the passive model already
  // explains the data (synthetic data without a controller, noiseless or not), a fit of its
  // residue is no better than the passive model in any sense that matters, and without the
  // margin round-off decided whether silent muscles were written.
  const double margin_m = kKeepMargin * std::max(result.passive_rms_m, result.constant_velocity_rms_m);
  const bool better = result.validation_rms_m < result.passive_rms_m - margin_m;
  result.better_than_passive = final_bounded && chosen.bounded && better;
  char why[240] = "";
  if (!chosen.bounded)
    std::snprintf(why, sizeof(why), "no candidate's 10x validation rollout stayed bounded");
  else if (!final_bounded)
    std::snprintf(why, sizeof(why), "every refit on all frames tried (%zu) left the data over its "
                  "10x rollouts", order.size());
  else if (!better)
    std::snprintf(why, sizeof(why), "its validation error %.3g m is not below the passive model's "
                  "%.3g m by %.3g m, 1 %% of the larger of it and the constant-velocity guess's",
                  result.validation_rms_m, result.passive_rms_m, margin_m);
  result.not_kept_because = why;
  result.rows = sys.rows;
  // A row sums window^2 frames' a h^2 (the triangle's weights): per frame, divided by that.
  const double per_frame = 1.0 / (passive.frame_rate_hz * passive.frame_rate_hz *
                                  chosen.window_frames * chosen.window_frames);
  result.residual_rms_m = Fitter::residualRms(sys, theta) * per_frame;
  result.model = fitter.build(theta, o.gain_margin, frames, activation.time_s);
  return result;
}

}  // namespace

}  // namespace mme

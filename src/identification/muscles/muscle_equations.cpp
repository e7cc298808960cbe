#include "muscle_equations.h"

#include <algorithm>
#include <cmath>

#include "motion_model_estimation/core/muscle.h"

namespace mme::sensor_muscles {

MuscleEquations::MuscleEquations(const Model& passive, const Trajectory& data, const Layout& layout)
    : passive_(passive), data_(data), layout_(layout), sim_(passive),
      n_(static_cast<int>(passive.particles.size())),
      s_(static_cast<int>(layout.sensors.size())),
      m_(static_cast<int>(layout.muscles.size())), k_(2 * s_ + 3) {
  h_ = 1.0 / passive.frame_rate_hz;
  findPartners();
  at_.assign(n_, {});
  for (int m = 0; m < m_; ++m) {
    at_[layout.muscles[m].a].push_back({m, 1.0});
    at_[layout.muscles[m].b].push_back({m, -1.0});
  }
  makePattern();
  computeScales();
}

/// Particles whose force depends on particle i's state: every bond's other members, or all of
/// them when bonds are installed on the fly.
void MuscleEquations::findPartners() {
  partners_.assign(n_, {});
  for (const Bond& bond : passive_.bonds) {
    const int arity = kindArity(passive_.bond_types[bond.type].kind);
    for (int p = 0; p < arity; ++p)
      for (int q = 0; q < arity; ++q)
        if (p != q) partners_[bond.particles[p]].push_back(bond.particles[q]);
  }
  all_partners_ = !passive_.interactions.empty();
}

SignConstraints MuscleEquations::signConstraints(bool nonnegative_own_spring) const {
  SignConstraints c;
  c.muscles = m_;
  c.per_muscle = k_;
  c.own_stiffness = 2 * s_ + 1;
  c.nonnegative_own_spring = nonnegative_own_spring;
  for (int m = 0; m < m_; ++m)
    if (layout_.no_own_stiffness[m]) c.held_at_zero.push_back(m * k_ + 2 * s_ + 1);
  c.sparse = true;
  c.cache = makeSparseRidgeCache();
  return c;
}

/// The blocks a particle's equations fill (addEquation): every pair of its muscles, at the
/// particles that give equations.
void MuscleEquations::makePattern() {
  std::vector<std::vector<int>> coupled_below(m_);
  for (int i = 0; i < n_; ++i) {
    if (passive_.particles[i].fixed) continue;
    for (const auto& [m, sign] : at_[i])
      for (const auto& [m2, sign2] : at_[i])
        if (m2 <= m) coupled_below[m].push_back(m2);
  }
  pattern_ = makeBlockPattern(m_, k_, std::move(coupled_below));
}

void MuscleEquations::accumulate(int window, int centre_begin, int centre_end, System* sys, ThreadPool* pool) const {
  sizeSystem(pattern_, sys);
  const int first = std::max(window, centre_begin);
  const int last = std::min(centre_end, data_.numFrames() - window);  // exclusive
  if (first >= last) return;
  if (window == 1 && pool && pool->threads() > 1) {  // the frames' pieces in batches, in order
    std::vector<FramePieces> batch;
    for (int t = first; t < last; ++t) {
      batch.push_back(pieces(t));
      if (batch.size() < kBatchFrames && t + 1 < last) continue;
      addPiecesBatch(batch, sys, pool);
      batch.clear();
    }
    return;
  }
  // The one-step pieces of frames t - window + 1 .. t + window - 1, oldest first.
  std::deque<FramePieces> ring;
  Gradients g(m_);
  for (int t = first; t < last; ++t) {
    if (ring.empty()) {
      for (int f = t - window + 1; f <= t + window - 1; ++f) ring.push_back(pieces(f));
    } else {
      ring.pop_front();
      ring.push_back(pieces(t + window - 1));
    }
    for (int i = 0; i < n_; ++i) {
      if (window == 1) {
        if (ring[0].particle_ok[i]) addFrameEquation(i, ring[0], sys);
      } else {
        addWindowEquation(i, window, ring, &g, sys);
      }
    }
  }
}

/// Particle i's equation summed over the window's frames in `ring` (none when a frame lacks it).
void MuscleEquations::addWindowEquation(int i, int window, const std::deque<FramePieces>& ring, Gradients* g,
                                        System* sys) const {
  bool ok = true;
  for (const FramePieces& f : ring) ok = ok && f.particle_ok[i];
  if (!ok) return;
  const double mass = passive_.particles[i].mass_kg;
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  for (const auto& [m, sign] : at_[i]) (*g)[m].setZero(3, k_);
  for (int j = 0; j < 2 * window - 1; ++j) {
    const FramePieces& f = ring[j];
    const double w = window - std::abs(j - (window - 1));
    y += w * f.y[i];
    for (const auto& [m, sign] : at_[i])
      (*g)[m].noalias() += (w * sign / mass) * f.u[m] * f.phi.col(m).transpose();
  }
  addEquation(i, *g, y, sys);
}

Frames3 MuscleEquations::dataFrames(int t) const {
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

FramePieces MuscleEquations::pieces(int t) const {
  if (t < 1 || t + 1 >= data_.numFrames()) return emptyPieces();
  return pieces(dataFrames(t));
}

FramePieces MuscleEquations::emptyPieces() const {
  FramePieces f;
  f.particle_ok.assign(n_, 0);
  f.muscle_ok.assign(m_, 0);
  f.y.assign(n_, Eigen::Vector3d::Zero());
  f.u.assign(m_, Eigen::Vector3d::Zero());
  f.phi = Eigen::MatrixXd::Zero(k_, m_);
  return f;
}

FramePieces MuscleEquations::pieces(const Frames3& frames) const {
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

void MuscleEquations::addPieces(const FramePieces& f, System* sys) const {
  sizeSystem(pattern_, sys);
  for (int i = 0; i < n_; ++i)
    if (f.particle_ok[i]) addFrameEquation(i, f, sys);
}

/// addEquation for one frame's rows of particle i: muscle m's gradient there is the rank-one
/// (sign / mass) u_m phi_m^T, so each block of the normal matrix is the outer product
/// phi_m phi_m2^T scaled by (u_m . u_m2) / mass^2, a third of the work of the general product.
/// Only the blocks on and below the diagonal are kept (m2 <= m): the others are their transposes.
void MuscleEquations::addFrameEquation(int i, const FramePieces& f, System* sys) const {
  sys->btb += f.y[i].squaredNorm();
  sys->rows += 3;
  addFrameEquationPart(i, f, 0, 1, sys);
}

void MuscleEquations::addPiecesBatch(const std::vector<FramePieces>& batch, System* sys, ThreadPool* pool) const {
  if (!pool || pool->threads() < 2) {
    for (const FramePieces& f : batch) addPieces(f, sys);
    return;
  }
  sizeSystem(pattern_, sys);
  for (const FramePieces& f : batch)
    for (int i = 0; i < n_; ++i)
      if (f.particle_ok[i]) {
        sys->btb += f.y[i].squaredNorm();
        sys->rows += 3;
      }
  const int parts = pool->threads();
  pool->parallelFor(static_cast<size_t>(parts), [&](size_t part) {
    for (const FramePieces& f : batch)
      for (int i = 0; i < n_; ++i)
        if (f.particle_ok[i]) addFrameEquationPart(i, f, static_cast<int>(part), parts, sys);
  });
}

void MuscleEquations::addFrameEquationPart(int i, const FramePieces& f, int part, int parts, System* sys) const {
  const double mass = passive_.particles[i].mass_kg;
  const Eigen::Vector3d& y = f.y[i];
  for (const auto& [m, sign] : at_[i]) {
    if (m % parts != part) continue;
    const double wm = sign / mass;
    sys->atb.segment(m * k_, k_).noalias() += (wm * f.u[m].dot(y)) * f.phi.col(m);
    for (const auto& [m2, sign2] : at_[i]) {
      if (m2 > m) continue;
      const double c = wm * (sign2 / mass) * f.u[m].dot(f.u[m2]);
      sys->block(m, m2).noalias() += c * f.phi.col(m) * f.phi.col(m2).transpose();
    }
  }
}

/// Adds particle i's three rows y = sum over its muscles of g[m] theta_m to the normal equations.
void MuscleEquations::addEquation(int i, const Gradients& g, const Eigen::Vector3d& y, System* sys) const {
  sys->btb += y.squaredNorm();
  sys->rows += 3;
  for (const auto& [m, sign] : at_[i]) {
    sys->atb.segment(m * k_, k_).noalias() += g[m].transpose() * y;
    for (const auto& [m2, sign2] : at_[i])
      if (m2 <= m) sys->block(m, m2).noalias() += g[m].transpose() * g[m2];
  }
}

/// Positions now and velocities (now - before) / h where seen; zeros elsewhere.
State MuscleEquations::stateAt(const Frames3& f) const {
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

bool MuscleEquations::sensorInputs(const Frames3& f, Eigen::VectorXd* z) const {
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
bool MuscleEquations::muscleGeometry(const Frames3& f, int m, const State& state, Eigen::Vector3d* u,
                                     double* e, double* s) const {
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
bool MuscleEquations::usable(const Frames3& f, int i, const std::vector<char>& muscle_ok) const {
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
void MuscleEquations::computeScales() {
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

}  // namespace mme::sensor_muscles

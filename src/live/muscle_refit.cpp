#include "motion_model_estimation/live/muscle_refit.h"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <vector>

#include "motion_model_estimation/core/simulator.h"

namespace mme {

namespace {

bool refittable(const BondType& type) {
  if (type.kind != BondKind::kMuscle || type.network_hidden != 0) return false;
  if (type.network.size() != static_cast<size_t>(2 * type.network_inputs + 1)) return false;
  return std::none_of(type.network.begin(), type.network.end(), [](const Param& p) { return p.free; });
}

/// One frame's state from the window: positions (a fixed particle without its marker where the
/// model holds it) and the paper's backward-difference velocity (fixed particles at rest).
State frameState(const Model& model, const Trajectory& w, int t) {
  const int n = static_cast<int>(model.particles.size());
  State s;
  s.x_m.resize(n);
  s.v_mps.assign(n, Eigen::Vector3d::Zero());
  for (int i = 0; i < n; ++i) {
    const Particle& p = model.particles[i];
    s.x_m[i] = (p.fixed && w.isOccluded(t, i)) ? p.position_m : w.position(t, i);
    if (!p.fixed) s.v_mps[i] = (w.position(t, i) - w.position(t - 1, i)) * w.frame_rate_hz;
  }
  return s;
}

/// Frame t gives equations: every free particle seen at t-1, t and t+1.
bool usableFrame(const Model& model, const Trajectory& w, int t) {
  for (size_t i = 0; i < model.particles.size(); ++i) {
    if (model.particles[i].fixed) continue;
    for (int k = t - 1; k <= t + 1; ++k)
      if (w.isOccluded(k, static_cast<int>(i))) return false;
  }
  return true;
}

/// A muscle bond's network inputs (elongations of its input bonds from their rest lengths, then
/// their elongation speeds) and a 1 for the bias: muscle.h's z, in the network's storage order.
Eigen::VectorXd regressors(const Model& model, const Bond& bond, const State& s) {
  const int n = static_cast<int>(bond.inputs.size());
  Eigen::VectorXd phi(2 * n + 1);
  for (int j = 0; j < n; ++j) {
    const Bond& input = model.bonds[bond.inputs[j]];
    const int a = input.particles[0], b = input.particles[1];
    const Eigen::Vector3d d = s.x_m[b] - s.x_m[a];
    const double l = d.norm();
    const Eigen::Vector3d u = l > 0.0 ? Eigen::Vector3d(d / l) : Eigen::Vector3d::Zero();
    phi(j) = l - model.bond_types[input.type].value(kRestLength);
    phi(n + j) = (s.v_mps[b] - s.v_mps[a]).dot(u);
  }
  phi(2 * n) = 1.0;
  return phi;
}

struct LinearSystem {
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<double> target;                     ///< per row: a h^2 not explained [m]
  std::vector<std::vector<std::pair<int, Eigen::VectorXd>>> activations;  ///< per type: (frame, phi)
};

/// Writes the rows of frame t: per free particle, its one-step acceleration times h^2 minus
/// what the known forces explain, against its muscles' regressors (a pulls toward b: +u at a).
void addFrameRows(const Model& model, const Model& known, Simulator& sim, const Trajectory& w, int t,
                  const std::vector<int>& first_column, LinearSystem* sys) {
  const int n = static_cast<int>(model.particles.size());
  const State s = frameState(model, w, t);
  std::vector<Eigen::Vector3d> forces;
  sim.computeForces(s, &forces);
  const double h2 = 1.0 / (w.frame_rate_hz * w.frame_rate_hz);
  std::vector<int> row_of(n, -1);
  for (int i = 0; i < n; ++i) {
    const Particle& p = known.particles[i];
    if (p.fixed) continue;
    row_of[i] = static_cast<int>(sys->target.size());
    const Eigen::Vector3d a_h2 = w.position(t + 1, i) - 2.0 * w.position(t, i) + w.position(t - 1, i);
    const Eigen::Vector3d y = a_h2 - forces[i] * (h2 / p.mass_kg);
    for (int k = 0; k < 3; ++k) sys->target.push_back(y(k));
  }
  for (const Bond& bond : model.bonds) {
    const int column = first_column[bond.type];
    if (column < 0) continue;
    const int a = bond.particles[0], b = bond.particles[1];
    const Eigen::Vector3d d = s.x_m[b] - s.x_m[a];
    if (!(d.norm() > 0.0)) continue;
    const Eigen::Vector3d u = d.normalized();
    const Eigen::VectorXd phi = regressors(model, bond, s);
    sys->activations[bond.type].push_back({t, phi});
    for (const auto& [i, sign] : {std::pair<int, double>{a, 1.0}, std::pair<int, double>{b, -1.0}}) {
      if (row_of[i] < 0) continue;
      const double scale = sign * h2 / model.particles[i].mass_kg;
      for (int k = 0; k < 3; ++k)
        for (int m = 0; m < phi.size(); ++m)
          sys->entries.emplace_back(row_of[i] + k, column + m, scale * u(k) * phi(m));
    }
  }
}

/// Conjugate-gradient iterations at most, above the direct solve's size: a body of 40 markers
/// couples most of its muscles through shared particles, and a sparse factor of a few thousand
/// unknowns fills in to a dense one.
constexpr int kIterations = 200;

/// Ridge-regularised least squares in columns scaled to unit RMS; unused columns stay 0.
/// `theta` holds the current values on entry (the iterative solve starts there).
bool solveScaled(const Eigen::SparseMatrix<double>& J, const Eigen::VectorXd& y, double relative_ridge,
                 int direct_max_unknowns, Eigen::VectorXd* theta) {
  const int rows = static_cast<int>(J.rows()), cols = static_cast<int>(J.cols());
  Eigen::VectorXd scale(cols);
  for (int c = 0; c < cols; ++c) scale(c) = std::sqrt(J.col(c).squaredNorm() / rows);
  Eigen::VectorXd inverse = scale;
  for (int c = 0; c < cols; ++c) inverse(c) = scale(c) > 0.0 ? 1.0 / scale(c) : 0.0;
  const Eigen::SparseMatrix<double> Js = J * inverse.asDiagonal();
  Eigen::SparseMatrix<double> A = Js.transpose() * Js;
  double mean_diagonal = 0.0;
  int used = 0;
  for (int c = 0; c < cols; ++c)
    if (scale(c) > 0.0) mean_diagonal += A.coeff(c, c), ++used;
  if (used == 0) return false;
  mean_diagonal /= used;
  Eigen::SparseMatrix<double> ridge(cols, cols);
  ridge.setIdentity();
  A += (relative_ridge > 0.0 ? relative_ridge * mean_diagonal : 1e-12 * mean_diagonal) * ridge;
  const Eigen::VectorXd rhs = Js.transpose() * y;
  Eigen::VectorXd scaled;
  if (cols <= direct_max_unknowns) {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
    if (solver.info() != Eigen::Success) return false;
    scaled = solver.solve(rhs);
    if (solver.info() != Eigen::Success) return false;
  } else {
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> solver;
    solver.setMaxIterations(kIterations);
    solver.setTolerance(1e-8);
    solver.compute(A);
    const Eigen::VectorXd start = scale.asDiagonal() * (*theta);
    scaled = solver.solveWithGuess(rhs, start.allFinite() ? start : Eigen::VectorXd::Zero(cols));
  }
  if (!scaled.allFinite()) return false;
  *theta = inverse.asDiagonal() * scaled;
  return true;
}

/// gain x network of every refitted type, in column order: the values the solve starts from.
Eigen::VectorXd currentTheta(const Model& model, const std::vector<int>& first_column, int unknowns) {
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(unknowns);
  for (size_t k = 0; k < model.bond_types.size(); ++k) {
    if (first_column[k] < 0) continue;
    const BondType& type = model.bond_types[k];
    for (size_t m = 0; m < type.network.size(); ++m)
      theta(first_column[k] + static_cast<int>(m)) = type.value(kGain) * type.network[m].value;
  }
  return theta;
}

}  // namespace

int refittableMuscleTypes(const Model& model) {
  return static_cast<int>(std::count_if(model.bond_types.begin(), model.bond_types.end(), refittable));
}

MuscleRefitResult refitMuscleActivations(const Model& model, const Trajectory& window,
                                         double relative_ridge, double gain_margin,
                                         int direct_max_unknowns) {
  MuscleRefitResult r;
  r.model = model;
  const int types = static_cast<int>(model.bond_types.size());
  if (window.numMarkers() != static_cast<int>(model.particles.size()) || !(window.frame_rate_hz > 0.0)) {
    r.why = "the window is not the model's particles or has no frame rate";
    return r;
  }
  // Columns per refittable type; the known model has their activations silenced (tanh(0) = 0).
  std::vector<int> first_column(types, -1);
  Model known = model;
  for (int k = 0; k < types; ++k) {
    if (!refittable(model.bond_types[k])) continue;
    first_column[k] = r.unknowns;
    r.unknowns += static_cast<int>(model.bond_types[k].network.size());
    ++r.muscle_types;
    for (Param& p : known.bond_types[k].network) p.value = 0.0;
  }
  if (r.muscle_types == 0) {
    r.why = "the model has no muscle with a linear network to refit";
    return r;
  }
  Simulator sim(known);
  LinearSystem sys;
  sys.activations.resize(types);
  for (int t = 1; t + 1 < window.numFrames(); ++t)
    if (usableFrame(model, window, t)) addFrameRows(model, known, sim, window, t, first_column, &sys);
  r.rows = static_cast<int>(sys.target.size());
  if (r.rows == 0) {
    r.why = "no frame of the window sees every free particle with the frames around it";
    return r;
  }
  Eigen::SparseMatrix<double> J(r.rows, r.unknowns);
  J.setFromTriplets(sys.entries.begin(), sys.entries.end());
  const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(sys.target.data(), r.rows);
  Eigen::VectorXd theta = currentTheta(model, first_column, r.unknowns);
  if (!solveScaled(J, y, relative_ridge, direct_max_unknowns, &theta)) {
    r.why = "the least-squares solve failed";
    return r;
  }
  r.residual_rms_m = std::sqrt((J * theta - y).squaredNorm() / r.rows);
  // theta = gain x network: a new gain from the largest linear activation, then the network.
  for (int k = 0; k < types; ++k) {
    if (first_column[k] < 0) continue;
    BondType& type = r.model.bond_types[k];
    const Eigen::VectorXd th = theta.segment(first_column[k], static_cast<Eigen::Index>(type.network.size()));
    double largest = 0.0;
    for (const auto& sample : sys.activations[k]) largest = std::max(largest, std::abs(th.dot(sample.second)));
    double gain = gain_margin * largest;
    if (!(gain > 0.0) || !std::isfinite(gain)) gain = type.value(kGain) > 0.0 ? type.value(kGain) : 1.0;
    Param& g = type.param(kGain);
    g.value = gain;
    g.present = g.has_value = true;
    for (size_t m = 0; m < type.network.size(); ++m) {
      type.network[m].value = th(static_cast<Eigen::Index>(m)) / gain;
      type.network[m].present = type.network[m].has_value = true;
    }
  }
  r.ok = true;
  return r;
}

}  // namespace mme

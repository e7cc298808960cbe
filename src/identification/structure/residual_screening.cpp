// Screening by the one-step residual (residual_screening.h): the missing pairs a spring would
// explain and the thresholds a spring's switching would earn, both read from the residual of a
// fitted model on the fitted frames.
#include "residual_screening.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

#include "motion_model_estimation/core/forces.h"
#include "motion_model_estimation/core/simulator.h"

namespace mme {
namespace structure {

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

/// The residual's mean square over its finite rows (three per particle and frame), and the
/// rows; 0 rows when none is finite.
std::pair<double, long> residualSquares(const std::vector<std::vector<Eigen::Vector3d>>& residual) {
  double sum2 = 0.0;
  long rows = 0;
  for (const auto& frame : residual)
    for (const Eigen::Vector3d& r : frame)
      if (r.allFinite()) {
        sum2 += r.squaredNorm();
        rows += 3;
      }
  return {sum2, rows};
}

/// The part of the one-step residual a spring between a and b would explain, c^T G^-1 c with
/// the tension f = k l - (k L) as unknowns (on a, +f u; on b, -f u; rows weighted h^2 / m);
/// NaN when the frames do not determine it (G not positive definite).
double explainedBySpringM2(const Model& model, const Trajectory& data,
                           const std::vector<std::vector<Eigen::Vector3d>>& residual, int a, int b) {
  const double h = 1.0 / model.frame_rate_hz;
  Eigen::Matrix2d g = Eigen::Matrix2d::Zero();
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (int t = 1; t + 1 < data.numFrames(); ++t) {
    if (residual[t].empty()) continue;
    const Eigen::Vector3d d = data.position(t, b) - data.position(t, a);
    const double l = d.norm();
    if (!(l > 0.0) || data.isOccluded(t, a) || data.isOccluded(t, b)) continue;
    const Eigen::Vector3d u = d / l;
    for (int side = 0; side < 2; ++side) {
      const int i = side == 0 ? a : b;
      if (model.particles[i].fixed || !residual[t][i].allFinite()) continue;
      const double w = (side == 0 ? 1.0 : -1.0) * h * h / model.particles[i].mass_kg;
      const double r = residual[t][i].dot(u);
      const Eigen::Vector2d f(w * l, -w);
      g += f * f.transpose();
      c += f * r;
    }
  }
  if (!(g.determinant() > 0.0)) return kNan;
  return c.dot(g.ldlt().solve(c));
}

/// The law of an unconditional spring type (its values).
SpringLaw springLawOf(const BondType& type) {
  SpringLaw law;
  law.stiffness = type.value(kStiffness);
  law.rest_length = type.value(kRestLength);
  law.damping = type.value(kDamping);
  law.stiffness_nl = type.value(kStiffnessNl);
  law.damping_nl = type.value(kDampingNl);
  return law;
}

/// Per frame where the spring `bond` is seen (at t and t-1) and one of its particles has a
/// residual: (its length, the residual's change in squares when its force is removed).
std::vector<std::pair<double, double>> switchRows(
    const Model& model, const Trajectory& data,
    const std::vector<std::vector<Eigen::Vector3d>>& residual, const Bond& bond) {
  const double h = 1.0 / model.frame_rate_hz;
  const SpringLaw law = springLawOf(model.bond_types[bond.type]);
  const int a = bond.particles[0], c = bond.particles[1];
  std::vector<std::pair<double, double>> rows;
  for (int t = 1; t + 1 < data.numFrames(); ++t) {
    if (residual[t].empty() || data.isOccluded(t, a) || data.isOccluded(t, c) ||
        data.isOccluded(t - 1, a) || data.isOccluded(t - 1, c))
      continue;
    const Eigen::Vector3d xa = data.position(t, a), xc = data.position(t, c);
    const Eigen::Vector3d va = (xa - data.position(t - 1, a)) / h, vc = (xc - data.position(t - 1, c)) / h;
    Eigen::Vector3d fa = Eigen::Vector3d::Zero(), fc = Eigen::Vector3d::Zero();
    addSpringForce(law, xa, xc, va, vc, &fa, &fc);
    double change = 0.0;
    bool usable = false;
    for (int side = 0; side < 2; ++side) {
      const int i = side == 0 ? a : c;
      const Eigen::Vector3d& r = residual[t][i];
      if (!r.allFinite()) continue;
      usable = true;
      // r = (m a - F) h^2 / m: without the bond's force f on i, r + f h^2 / m.
      const Eigen::Vector3d off = r + (h * h / model.particles[i].mass_kg) * (side == 0 ? fa : fc);
      change += off.squaredNorm() - r.squaredNorm();
    }
    if (usable) rows.push_back({(xc - xa).norm(), change});
  }
  return rows;
}

/// The threshold of `type` whose switching lowers the residual most, over `rows` sorted by
/// length: the frames below it off (a prefix) or the frames above it off (a suffix).
ConditionalChoice bestThreshold(int type, const std::vector<std::pair<double, double>>& rows) {
  ConditionalChoice best;
  best.type = type;
  double prefix = 0.0, total = 0.0;
  for (const auto& row : rows) total += row.second;
  for (size_t k = 1; k < rows.size(); ++k) {
    prefix += rows[k - 1].second;  // frames [0, k) off: the bond shorter than the threshold
    const double threshold = 0.5 * (rows[k - 1].first + rows[k].first);
    if (-prefix > best.gain_m2) best = {type, true, threshold, -prefix};
    const double suffix = total - prefix;  // frames [k, end) off: longer than the threshold
    if (-suffix > best.gain_m2) best = {type, false, threshold, -suffix};
  }
  return best;
}

}  // namespace

std::vector<std::vector<Eigen::Vector3d>> oneStepResiduals(const Model& model, const Trajectory& data) {
  const int n = static_cast<int>(model.particles.size()), frames = data.numFrames();
  const double h = 1.0 / model.frame_rate_hz;
  Simulator simulator(model);
  State state;
  state.x_m.resize(n);
  state.v_mps.resize(n);
  std::vector<Eigen::Vector3d> force;
  std::vector<std::vector<Eigen::Vector3d>> residual(frames);
  for (int t = 1; t + 1 < frames; ++t) {
    std::vector<uint8_t> seen(n);
    for (int i = 0; i < n; ++i) {
      seen[i] = !data.isOccluded(t - 1, i) && !data.isOccluded(t, i) && !data.isOccluded(t + 1, i);
      state.x_m[i] = seen[i] ? data.position(t, i) : model.particles[i].position_m;
      state.v_mps[i] = seen[i] ? Eigen::Vector3d((data.position(t, i) - data.position(t - 1, i)) / h)
                               : Eigen::Vector3d::Zero();
      if (model.particles[i].fixed) state.v_mps[i] = model.particles[i].velocity_mps;
    }
    simulator.computeForces(state, &force);
    residual[t].assign(n, Eigen::Vector3d::Constant(kNan));
    for (int i = 0; i < n; ++i) {
      if (!seen[i] || model.particles[i].fixed) continue;
      const double m = model.particles[i].mass_kg;
      const Eigen::Vector3d a = (data.position(t + 1, i) - 2.0 * data.position(t, i) + data.position(t - 1, i)) / (h * h);
      residual[t][i] = h * h / m * (m * a - force[i]);
    }
  }
  return residual;
}

std::vector<std::pair<int, int>> missingPairs(const Model& model, const Trajectory& data,
                                              const std::set<std::pair<int, int>>& have,
                                              double floor_rms_m, int most) {
  const int n = static_cast<int>(model.particles.size());
  const std::vector<std::vector<Eigen::Vector3d>> residual = oneStepResiduals(model, data);
  const std::pair<double, long> squares = residualSquares(residual);
  const double sum2 = squares.first;
  const long rows = squares.second;
  if (rows == 0 || std::sqrt(sum2 / rows) < floor_rms_m) return {};
  const double threshold_m2 = 20.0 * std::log(static_cast<double>(rows)) * sum2 / rows;
  std::vector<std::pair<double, std::pair<int, int>>> scored;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      if (have.count({a, b}) || (model.particles[a].fixed && model.particles[b].fixed)) continue;
      const double explained = explainedBySpringM2(model, data, residual, a, b);
      if (explained > threshold_m2) scored.push_back({-explained, {a, b}});
    }
  std::sort(scored.begin(), scored.end());
  std::vector<std::pair<int, int>> out;
  for (size_t k = 0; k < scored.size() && static_cast<int>(out.size()) < most; ++k)
    out.push_back(scored[k].second);
  return out;
}

std::vector<ConditionalChoice> conditionalCandidates(const Model& model, const Trajectory& data,
                                                     int first_candidate_type, double min_gain_m2) {
  const std::vector<std::vector<Eigen::Vector3d>> residual = oneStepResiduals(model, data);
  std::vector<ConditionalChoice> out;
  for (const Bond& bond : model.bonds) {
    if (bond.type < first_candidate_type) continue;
    const BondType& type = model.bond_types[bond.type];
    if (type.kind != BondKind::kSpring || type.param(kMinDistance).present ||
        type.param(kMaxDistance).present)
      continue;
    std::vector<std::pair<double, double>> rows = switchRows(model, data, residual, bond);
    if (rows.size() < 4) continue;
    std::sort(rows.begin(), rows.end());
    const ConditionalChoice best = bestThreshold(bond.type, rows);
    if (best.gain_m2 > min_gain_m2) out.push_back(best);
  }
  std::sort(out.begin(), out.end(),
            [](const ConditionalChoice& x, const ConditionalChoice& y) { return x.gain_m2 > y.gain_m2; });
  return out;
}

}  // namespace structure
}  // namespace mme

#include "motion_model_estimation/core/stiffness.h"

#include <algorithm>
#include <cmath>

namespace mme {

double stiffestModeRadPerS(const Model& model, const std::vector<Eigen::Vector3d>& x_m) {
  const int n = static_cast<int>(model.particles.size());
  if (static_cast<int>(x_m.size()) != n || n == 0) return 0.0;
  struct Block {
    int a, b;
    Eigen::Matrix3d k;  // the 3x3 stiffness of the pair: +k on (a,a), (b,b), -k off-diagonal
  };
  std::vector<Block> blocks;
  for (const Bond& bond : model.bonds) {
    const BondType& type = model.bond_types[bond.type];
    // Pair bonds with a stiffness; a muscle's activation is a driving force, not a stiffness.
    if (!bondKindInfo(type.kind).has_elongation) continue;
    const int a = bond.particles[0], b = bond.particles[1];
    const Eigen::Vector3d d = x_m[b] - x_m[a];
    const double l = d.norm();
    if (!(l > 0.0)) continue;
    const Eigen::Vector3d u = d / l;
    const double e = l - type.value(kRestLength);
    const double k_axial = std::max(0.0, type.value(kStiffness) + 3.0 * type.value(kStiffnessNl) * e * e);
    const double tension = type.value(kStiffness) * e + type.value(kStiffnessNl) * e * e * e;
    const double k_transverse = std::max(0.0, tension / l);
    const Eigen::Matrix3d uu = u * u.transpose();
    blocks.push_back({a, b, k_axial * uu + k_transverse * (Eigen::Matrix3d::Identity() - uu)});
  }
  std::vector<double> inv_sqrt_m(n, 0.0);
  for (int i = 0; i < n; ++i)
    if (!model.particles[i].fixed && model.particles[i].mass_kg > 0.0)
      inv_sqrt_m[i] = 1.0 / std::sqrt(model.particles[i].mass_kg);
  // Power iteration on A = M^-1/2 K M^-1/2 (symmetric positive semi-definite).
  std::vector<Eigen::Vector3d> v(n), w(n);
  for (int i = 0; i < n; ++i)
    v[i] = Eigen::Vector3d(1.0 + 0.37 * i, 0.5 - 0.11 * i, 0.25 + 0.07 * i) * inv_sqrt_m[i];
  double lambda = 0.0;
  for (int iteration = 0; iteration < 200; ++iteration) {
    double norm2 = 0.0;
    for (const Eigen::Vector3d& x : v) norm2 += x.squaredNorm();
    if (!(norm2 > 0.0)) return 0.0;
    for (Eigen::Vector3d& x : v) x /= std::sqrt(norm2);
    for (Eigen::Vector3d& x : w) x.setZero();
    for (const Block& blk : blocks) {
      const Eigen::Vector3d ya = inv_sqrt_m[blk.a] * v[blk.a], yb = inv_sqrt_m[blk.b] * v[blk.b];
      const Eigen::Vector3d f = blk.k * (ya - yb);
      w[blk.a] += inv_sqrt_m[blk.a] * f;
      w[blk.b] -= inv_sqrt_m[blk.b] * f;
    }
    double rayleigh = 0.0;
    for (int i = 0; i < n; ++i) rayleigh += v[i].dot(w[i]);
    const bool settled = std::abs(rayleigh - lambda) <= 1e-6 * std::abs(rayleigh);
    lambda = rayleigh;
    v.swap(w);
    if (settled && iteration > 10) break;
  }
  return std::sqrt(std::max(lambda, 0.0));
}

}  // namespace mme

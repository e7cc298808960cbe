#include "motion_model_estimation/scenes/random_object.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/random.h"

namespace mme {

namespace {

/// Bonds of a compact, well-braced object: each particle from `first` on joined to its nearest
/// earlier one (connected), then the shortest remaining pairs not in `used`, up to `bonds`;
/// shuffled, so that types assigned round-robin each span the object.
std::vector<std::pair<int, int>> bracedPairs(const Model& model, int first, int bonds,
                                             std::set<std::pair<int, int>> used, Random& random) {
  const int n = static_cast<int>(model.particles.size());
  std::vector<std::pair<int, int>> pairs;
  auto dist = [&](int a, int b) {
    return (model.particles[a].position_m - model.particles[b].position_m).norm();
  };
  for (int i = first; i < n; ++i) {
    int best = 0;
    for (int j = 1; j < i; ++j)
      if (dist(i, j) < dist(i, best)) best = j;
    pairs.emplace_back(best, i);
    used.insert({best, i});
  }
  std::vector<std::pair<double, std::pair<int, int>>> rest;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      if (!used.count({a, b})) rest.push_back({dist(a, b), {a, b}});
  std::sort(rest.begin(), rest.end());
  for (size_t k = 0; static_cast<int>(pairs.size()) < bonds && k < rest.size(); ++k)
    pairs.push_back(rest[k].second);
  for (size_t k = pairs.size(); k > 1; --k) std::swap(pairs[k - 1], pairs[random.index(static_cast<int>(k))]);
  return pairs;
}

/// Installs the pairs as spring bonds of types 0..types-1 round-robin; returns each type's mean
/// initial length [m].
std::vector<double> installBonds(Model* model, const std::vector<std::pair<int, int>>& pairs, int types) {
  std::vector<double> sum(types, 0.0);
  std::vector<int> count(types, 0);
  for (size_t k = 0; k < pairs.size(); ++k) {
    const int t = static_cast<int>(k % types);
    sum[t] += (model->particles[pairs[k].second].position_m - model->particles[pairs[k].first].position_m).norm();
    ++count[t];
    Bond bond;
    bond.type = t;
    bond.particles = {{pairs[k].first, pairs[k].second, -1}};
    model->bonds.push_back(bond);
  }
  for (int t = 0; t < types; ++t) sum[t] /= std::max(count[t], 1);
  return sum;
}

}  // namespace

Model makeRandomObject(const RandomObjectSpec& spec) {
  const int n = spec.particles;
  if (n < 2 || spec.bond_types < 1 || spec.bonds < n - 1 || spec.bonds < spec.bond_types ||
      spec.bonds > n * (n - 1) / 2 || !(spec.frame_rate_hz > 0.0) || !(spec.size_m > 0.0))
    throw InputError("random object: impossible spec (need particles >= 2, bonds >= particles-1, "
                     "bonds >= bond_types, bonds <= particles*(particles-1)/2)");
  Random random(spec.seed);
  Model model;
  model.frame_rate_hz = spec.frame_rate_hz;
  model.frame_id = "world";
  char name[32];
  for (int i = 0; i < n; ++i) {
    Particle p;
    std::snprintf(name, sizeof(name), "m%02d", i);
    p.name = name;
    p.mass_kg = 0.5 + 1.5 * random.uniform();
    for (int c = 0; c < 3; ++c) {
      p.position_m[c] = spec.size_m * random.uniform();
      p.velocity_mps[c] = 0.1 * (random.uniform() - 0.5);
    }
    model.particles.push_back(p);
  }
  // Bonds: a spanning tree, then the shortest remaining pairs (a compact, well-braced object).
  const std::vector<std::pair<int, int>> pairs = bracedPairs(model, 1, spec.bonds, {}, random);
  const double h = 1.0 / spec.frame_rate_hz;
  double min_mass = 1e300;
  for (const Particle& p : model.particles) min_mass = std::min(min_mass, p.mass_kg);
  // Stiffest allowed spring: a particle may sit on several springs; keep omega h < ~0.3 with a
  // margin for up to ~6 springs on a particle.
  const double k_max = std::min(200.0, 0.09 * min_mass / (h * h) / 6.0);
  const std::vector<double> mean_length = installBonds(&model, pairs, spec.bond_types);
  for (int t = 0; t < spec.bond_types; ++t) {
    BondType type;
    std::snprintf(name, sizeof(name), "k%02d", t);
    type.name = name;
    type.kind = BondKind::kSpring;
    const double k = k_max * std::exp(std::log(0.1) * random.uniform());  // [k_max/10, k_max]
    // Rest length 0.85..1.15 of the type's mean initial length: the object starts strained.
    const double length = mean_length[t] * (0.85 + 0.3 * random.uniform());
    Param& ks = type.param(kStiffness);
    ks = Param{k, true, true, true, k / 10.0, k * 10.0, true, true};
    Param& ls = type.param(kRestLength);
    ls = Param{length, true, true, true, length / 2.0, length * 2.0, true, true};
    if (spec.damping_max_nspm > 0.0) {
      const double c = spec.damping_max_nspm * std::exp(std::log(0.1) * random.uniform());
      type.param(kDamping) = Param{c, true, true, true, c / 10.0, c * 10.0, true, true};
    }
    model.bond_types.push_back(type);
  }
  return model;
}

Model makeHangingObject(const HangingObjectSpec& spec) {
  const int n = spec.particles;
  if (n < 3 || spec.bond_types < 1 || spec.bonds < n - 1 || spec.bonds < spec.bond_types ||
      spec.bonds > n * (n - 1) / 2 || !(spec.frame_rate_hz > 0.0) ||
      !(spec.min_stretch >= 1.0 && spec.max_stretch >= spec.min_stretch))
    throw InputError("hanging object: impossible spec (need particles >= 3, bonds >= particles-1, "
                     "bonds >= bond_types, 1 <= min_stretch <= max_stretch)");
  Random random(spec.seed);
  Model model;
  model.frame_rate_hz = spec.frame_rate_hz;
  model.frame_id = "world";
  for (int c = 0; c < 3; ++c) model.gravity_mps2[c] = Param{c == 2 ? -9.81 : 0.0, true, true};
  char name[32];
  for (int i = 0; i < n; ++i) {
    Particle p;
    std::snprintf(name, sizeof(name), "h%02d", i);
    p.name = name;
    if (i < 2) {  // the two fixed suspension points
      p.fixed = true;
      p.position_m = Eigen::Vector3d(i == 0 ? -0.1 : 0.1, 0.0, 0.0);
    } else {
      p.mass_kg = 0.02 + 0.08 * random.uniform();
      p.position_m = Eigen::Vector3d(0.3 * (random.uniform() - 0.5), 0.1 * (random.uniform() - 0.5),
                                     -0.02 - 0.28 * random.uniform());
      for (int c = 0; c < 3; ++c) p.velocity_mps[c] = 0.2 * (random.uniform() - 0.5);
    }
    model.particles.push_back(p);
  }
  // Bonds: each free particle to its nearest earlier one (the fixed pair first: connected to the
  // suspension), then the shortest remaining pairs that do not join the two fixed points.
  const std::vector<double> mean_length =
      installBonds(&model, bracedPairs(model, 2, spec.bonds, {{0, 1}}, random), spec.bond_types);
  const double log_stretch = std::log(spec.max_stretch / spec.min_stretch);
  for (int t = 0; t < spec.bond_types; ++t) {
    BondType type;
    std::snprintf(name, sizeof(name), "d%02d", t);
    type.name = name;
    type.kind = BondKind::kSpring;
    // Soft (weights of 0.02-0.1 kg stretch them far), damped, and short at rest: the type's
    // bonds start at min_stretch..max_stretch times the rest length.
    const double stretch = spec.min_stretch * std::exp(log_stretch * random.uniform());
    const double k = 2.0 * std::exp(std::log(10.0) * random.uniform());     // [2, 20] N/m
    const double c = 0.02 * std::exp(std::log(15.0) * random.uniform());    // [0.02, 0.3] N s/m
    const double length = mean_length[t] / stretch;
    type.param(kStiffness) = Param{k, true, true, true};
    type.param(kRestLength) = Param{length, true, true, true};
    type.param(kDamping) = Param{c, true, true, true};
    model.bond_types.push_back(type);
  }
  return model;
}

}  // namespace mme

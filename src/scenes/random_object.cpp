#include "motion_model_estimation/scenes/random_object.h"

#include <Eigen/Geometry>

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
    if (spec.stiffness_nl_scale > 0.0) {
      const double k_nl = (0.5 + 0.5 * random.uniform()) * spec.stiffness_nl_scale * k / (length * length);
      type.param(kStiffnessNl) = Param{k_nl, true, true, true, k_nl / 10.0, k_nl * 10.0, true, true};
    }
    if (t < spec.cable_types)
      type.param(kMinDistance) = Param{length, true, true, true, length / 2.0, length * 2.0, true, true};
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

Model makeChainObject(const ChainObjectSpec& spec) {
  if (spec.chains < 3 || spec.links < 3 || spec.spring_types < 1 || spec.flexion_types < 1 ||
      !(spec.frame_rate_hz > 0.0) || !(spec.segment_m > 0.0))
    throw InputError("chain object: impossible spec (need chains >= 3, links >= 3, spring_types >= 1, "
                     "flexion_types >= 1, frame_rate_hz > 0, segment_m > 0)");
  constexpr double kPi = 3.14159265358979323846;
  Random random(spec.seed);
  Model model;
  model.frame_rate_hz = spec.frame_rate_hz;
  model.frame_id = "world";
  const double h = 1.0 / spec.frame_rate_hz, s = spec.segment_m;
  const auto bounded = [](double value, double lo, double hi) {
    return Param{value, true, true, true, lo, hi, true, true};
  };
  const auto damping = [&](double max) {
    const double c = max * std::exp(std::log(0.1) * random.uniform());
    return bounded(c, c / 10.0, c * 10.0);
  };
  // Types: hub, segment springs, flexions. Stiffness as makeRandomObject's (omega h < ~0.3 with
  // a margin for several bonds on a particle; masses >= 0.5 kg).
  const double k_max = std::min(200.0, 0.09 * 0.5 / (h * h) / 6.0);
  char name[32];
  const auto spring = [&](const std::string& type_name, double length) {
    BondType type;
    type.name = type_name;
    type.kind = BondKind::kSpring;
    const double k = k_max * std::exp(std::log(0.1) * random.uniform());
    type.param(kStiffness) = bounded(k, k / 10.0, k * 10.0);
    const double rest = length * (0.9 + 0.2 * random.uniform());
    type.param(kRestLength) = bounded(rest, rest / 2.0, rest * 2.0);
    if (spec.damping_max_nspm > 0.0) type.param(kDamping) = damping(spec.damping_max_nspm);
    model.bond_types.push_back(type);
  };
  spring("hub", s);
  for (int t = 0; t < spec.spring_types; ++t) {
    std::snprintf(name, sizeof(name), "seg%02d", t);
    spring(name, s);
  }
  const int first_flexion = static_cast<int>(model.bond_types.size());
  std::vector<double> rest_angle(spec.flexion_types);
  for (int t = 0; t < spec.flexion_types; ++t) {
    BondType type;
    std::snprintf(name, sizeof(name), "flex%02d", t);
    type.name = name;
    type.kind = BondKind::kFlexion;
    // Bending a segment end by dy turns the angle by dy / s: an effective stiffness k_f / s^2.
    const double k = 0.3 * k_max * s * s * std::exp(std::log(0.1) * random.uniform());
    type.param(kStiffness) = bounded(k, k / 10.0, k * 10.0);
    rest_angle[t] = (150.0 + 22.0 * random.uniform()) * kPi / 180.0;
    type.param(kRestAngle) = bounded(rest_angle[t], 0.5 * rest_angle[t], kPi);
    if (spec.damping_max_nspm > 0.0) type.param(kDamping) = damping(spec.damping_max_nspm * s * s);
    model.bond_types.push_back(type);
  }
  // Particles: roots on an equilateral triangle (edge s) in the z = 0 plane, then each chain
  // outwards, every inner particle bent by its type's rest angle about a random axis.
  const int n_chains = spec.chains;
  std::vector<std::vector<int>> chain(n_chains);
  const double hub_radius = s / (2.0 * std::sin(kPi / n_chains));
  const auto addParticle = [&](const Eigen::Vector3d& x) {
    Particle p;
    std::snprintf(name, sizeof(name), "c%02d", static_cast<int>(model.particles.size()));
    p.name = name;
    p.mass_kg = 0.5 + 1.5 * random.uniform();
    p.position_m = x;
    for (int c = 0; c < 3; ++c) p.velocity_mps[c] = 0.1 * (random.uniform() - 0.5);
    model.particles.push_back(p);
    return static_cast<int>(model.particles.size()) - 1;
  };
  for (int c = 0; c < n_chains; ++c) {
    const double phi = 2.0 * kPi * c / n_chains;
    const Eigen::Vector3d out(std::cos(phi), std::sin(phi), 0.0);
    chain[c].push_back(addParticle(hub_radius * out));
    Eigen::Vector3d dir = (out + Eigen::Vector3d(0.0, 0.0, 0.6 * (random.uniform() - 0.5))).normalized();
    chain[c].push_back(addParticle(model.particles[chain[c][0]].position_m + s * dir));
    const int flex = first_flexion + c % spec.flexion_types;
    for (int k = 2; k < spec.links; ++k) {
      // Turn by pi - theta0 about an axis perpendicular to the chain.
      Eigen::Vector3d axis = dir.cross(Eigen::Vector3d(random.uniform() - 0.5, random.uniform() - 0.5,
                                                       random.uniform() - 0.5));
      axis.normalize();
      const double turn = kPi - rest_angle[flex - first_flexion];
      dir = (std::cos(turn) * dir + std::sin(turn) * axis.cross(dir)).normalized();
      chain[c].push_back(addParticle(model.particles[chain[c][k - 1]].position_m + s * dir));
    }
  }
  const auto addBond = [&](int type, int a, int b, int c) {
    Bond bond;
    bond.type = type;
    bond.particles = {{a, b, c}};
    model.bonds.push_back(bond);
  };
  for (int c = 0; c < n_chains; ++c) addBond(0, chain[c][0], chain[(c + 1) % n_chains][0], -1);
  for (int c = 0; c < n_chains; ++c) {
    const int seg = 1 + c % spec.spring_types, flex = first_flexion + c % spec.flexion_types;
    for (int k = 1; k < spec.links; ++k) addBond(seg, chain[c][k - 1], chain[c][k], -1);
    for (int k = 1; k + 1 < spec.links; ++k) addBond(flex, chain[c][k - 1], chain[c][k], chain[c][k + 1]);
  }
  return model;
}

}  // namespace mme


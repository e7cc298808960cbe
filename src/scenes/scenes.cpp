// Built-in scenes of SPEC section 8, after the experiments of the paper's section 4. Each scene
// is a model holding the TRUE parameter values with free flags on what identification should
// recover (the value of a free parameter is the truth, kept for comparisons), and bounds that
// bracket the truth (x10 for positive magnitudes, searched in log space; x2 for lengths).
//
// Everything is deterministic: randomness comes from mme::Random with fixed seeds, whose
// distributions are platform independent.
#include "motion_model_estimation/scenes/scenes.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/model_builder.h"
#include "motion_model_estimation/core/random.h"
#include "motion_model_estimation/core/simulator.h"
#include "scene_parts.h"

namespace mme {
namespace {

using scene_parts::freeLength;
using scene_parts::freeMagnitude;
using scene_parts::kPi;
using scene_parts::setGravity;

double roundTo(double x, double step) { return std::round(x / step) * step; }

// ------------------------------------------------------------------------------------------
// paper_object: the paper's Fig. 1 set-up (section 4.1). 15 masses, 10 linear spring types
// s00..s09 (stiffness + rest_length free = 20 parameters), 31 bonds, 100 frames at 100 Hz.
// A connected floating object (no gravity, nothing fixed): rest lengths differ from the initial
// distances by 5..12 % and the particles start with small random velocities, so it vibrates.
// Bonds are grouped into types by length (similar lengths share a type), which keeps the
// initial strain, hence the amplitude, at the centimetre level.
Scene makePaperObject() {
  constexpr int kParticles = 15, kTypes = 10, kBonds = 31;
  Random random(0x9a9e70b1ec7ULL);
  Scene scene;
  Model& model = scene.model;
  model.frame_rate_hz = 100.0;
  model.substeps = 1;
  setGravity(&model, Eigen::Vector3d::Zero());
  // Particles: rejection-sampled in a 0.45 x 0.35 x 0.3 m box, at least 0.1 m apart.
  std::vector<Eigen::Vector3d> x;
  while (static_cast<int>(x.size()) < kParticles) {
    Eigen::Vector3d p(roundTo(0.45 * random.uniform(), 1e-3), roundTo(0.35 * random.uniform(), 1e-3),
                      roundTo(0.30 * random.uniform(), 1e-3));
    bool far_enough = true;
    for (const Eigen::Vector3d& q : x) far_enough = far_enough && (p - q).norm() >= 0.1;
    if (far_enough) x.push_back(p);
  }
  char name[32];
  for (int i = 0; i < kParticles; ++i) {
    Eigen::Vector3d v;
    for (int c = 0; c < 3; ++c) v[c] = roundTo(0.1 * (random.uniform() - 0.5), 1e-3);  // +-5 cm/s
    std::snprintf(name, sizeof(name), "m%02d", i);
    addParticle(&model, x[i], {name, roundTo(0.5 + 1.5 * random.uniform(), 0.01), v});
  }
  // Bonds: a minimum spanning tree (Prim) keeps the object connected with short bonds; then the
  // shortest remaining pairs until 31.
  auto dist = [&](int a, int b) { return (x[a] - x[b]).norm(); };
  std::set<std::pair<int, int>> used;
  std::vector<std::pair<int, int>> pairs;
  std::vector<bool> in_tree(kParticles, false);
  in_tree[0] = true;
  for (int added = 1; added < kParticles; ++added) {
    int best_a = -1, best_b = -1;
    for (int a = 0; a < kParticles; ++a)
      for (int b = 0; b < kParticles; ++b)
        if (in_tree[a] && !in_tree[b] && (best_a < 0 || dist(a, b) < dist(best_a, best_b))) {
          best_a = a;
          best_b = b;
        }
    in_tree[best_b] = true;
    pairs.emplace_back(std::min(best_a, best_b), std::max(best_a, best_b));
    used.insert(pairs.back());
  }
  std::vector<std::pair<double, std::pair<int, int>>> candidates;
  for (int a = 0; a < kParticles; ++a)
    for (int b = a + 1; b < kParticles; ++b)
      if (!used.count({a, b})) candidates.push_back({dist(a, b), {a, b}});
  std::sort(candidates.begin(), candidates.end());
  for (size_t k = 0; static_cast<int>(pairs.size()) < kBonds; ++k) pairs.push_back(candidates[k].second);
  // Types by length rank: type t gets the bonds of ranks 3t..3t+2 (the 31st goes to s09).
  std::sort(pairs.begin(), pairs.end(), [&](const std::pair<int, int>& p, const std::pair<int, int>& q) {
    return dist(p.first, p.second) < dist(q.first, q.second);
  });
  std::vector<double> length_sum(kTypes, 0.0);
  std::vector<int> count(kTypes, 0);
  for (int b = 0; b < kBonds; ++b) {
    const int t = std::min(b / 3, kTypes - 1);
    length_sum[t] += dist(pairs[b].first, pairs[b].second);
    ++count[t];
    addBond(&model, t, pairs[b].first, pairs[b].second);
  }
  // Stiffness log-uniform in [10, 80] N/m; rest length = the type's mean initial length
  // shortened or lengthened by 5..12 %.
  for (int t = 0; t < kTypes; ++t) {
    BondType type;
    std::snprintf(name, sizeof(name), "s%02d", t);
    type.name = name;
    type.kind = BondKind::kSpring;
    const double k = roundTo(10.0 * std::exp(std::log(8.0) * random.uniform()), 0.1);
    const double sign = random.uniform() < 0.5 ? -1.0 : 1.0;
    const double strain = sign * (0.05 + 0.07 * random.uniform());
    const double length = roundTo(length_sum[t] / count[t] * (1.0 + strain), 1e-4);
    type.param(kStiffness) = freeMagnitude(k);
    type.param(kRestLength) = freeLength(length);
    addBondType(&model, type);
  }
  scene.default_frames = 100;
  return scene;
}

// ------------------------------------------------------------------------------------------
// provot_cloth: Provot's (1995) cloth (section 4.2, Table I). A 17 x 17 mesh, 1.5 m square
// (period 0.09375 m), released horizontally in the x-y plane and hanging from the corners c_0_0
// and c_0_16 under gravity. Six spring types, 3 free parameters each (stiffness, rest_length,
// cubic stiffness_nl): structural struct_h/struct_v (rest 0.09375), shear shear_d1/shear_d2
// (0.132583), flexion flex_h/flex_v (double-length springs, 0.1875). Provot's maximum
// elongation rate tau_c = 0.5 is free on both structural types (20 free parameters in all).
// Spring damping and an air drag (viscosity type "air", 5 /s) are known and fixed: they only
// make the cloth settle (spring dampers alone barely damp its pendulum swing about the corners).
// 100 Hz with 5 substeps (stiffest mode omega dt ~ 0.4). The reference data set is the
// equilibrium, a single frame; default_frames (300) shows the fall and most of the settling.
constexpr int kClothSide = 17;
constexpr double kClothPeriodM = 0.09375;
// Whole cloth [kg]: heavy enough for the clamp to hold the springs at the two corners (2 struct_h
// and 2 struct_v springs at exactly (1 + tau) L at equilibrium; 0.1 kg clamps none), light
// enough for the rest to stay elastic (the mesh stretches from 1.5 m to ~1.79 m of drop).
constexpr double kClothMassKg = 0.2;
constexpr int kClothMaxSettleFrames = 20000;
constexpr double kClothRestSpeedMps = 1e-6;  // observable (frame-to-frame) speed ending phase 1
constexpr int kMaxNewtonIterations = 12;
constexpr double kFixedPointTolM = 1e-14;  // max |P(x) - x| ending the Newton polish

struct EquilibriumReport {
  int newton_iterations = 0;
  int jacobians = 0;
  double residual_m = 0.0;  ///< max |P(x) - x| at the end
};

/// Polishes positions x (in place) into a fixed point of the static prediction P: one frame of
/// the motion law from x with zero velocity, exactly what the cost predicts from a motionless
/// observation. Newton's method on P(x) - x over the free coordinates, with a finite-difference
/// Jacobian reused while it keeps converging fast.
EquilibriumReport polishStaticEquilibrium(const Model& model, std::vector<Eigen::Vector3d>* x) {
  Simulator simulator(model);
  const double h = 1.0 / model.frame_rate_hz;
  const int n = static_cast<int>(model.particles.size());
  std::vector<int> coords;  // free coordinates
  for (int i = 0; i < n; ++i)
    if (!model.particles[i].fixed)
      for (int c = 0; c < 3; ++c) coords.push_back(3 * i + c);
  const int m = static_cast<int>(coords.size());
  State probe;
  probe.x_m = *x;
  auto residual = [&](const Eigen::VectorXd& q) {
    for (int k = 0; k < m; ++k) probe.x_m[coords[k] / 3][coords[k] % 3] = q[k];
    probe.v_mps.assign(n, Eigen::Vector3d::Zero());
    simulator.stepFrame(&probe, h);
    Eigen::VectorXd r(m);
    for (int k = 0; k < m; ++k) r[k] = probe.x_m[coords[k] / 3][coords[k] % 3] - q[k];
    return r;
  };
  Eigen::VectorXd q(m);
  for (int k = 0; k < m; ++k) q[k] = (*x)[coords[k] / 3][coords[k] % 3];
  Eigen::VectorXd r = residual(q);
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
  bool fresh = false, have_jacobian = false;
  EquilibriumReport report;
  report.residual_m = r.lpNorm<Eigen::Infinity>();
  while (report.newton_iterations < kMaxNewtonIterations && report.residual_m > kFixedPointTolM) {
    if (!have_jacobian) {
      const double eps = 1e-7;
      Eigen::MatrixXd jacobian(m, m);
      for (int k = 0; k < m; ++k) {
        Eigen::VectorXd qk = q;
        qk[k] += eps;
        jacobian.col(k) = (residual(qk) - r) / eps;
      }
      lu.compute(jacobian);
      have_jacobian = fresh = true;
      ++report.jacobians;
    }
    ++report.newton_iterations;
    const Eigen::VectorXd next = q - lu.solve(r);
    const Eigen::VectorXd next_r = residual(next);
    const double norm = next_r.lpNorm<Eigen::Infinity>();
    if (!(norm < report.residual_m)) {  // stale Jacobian or a changed clamp set: rebuild it
      if (fresh) break;                 // even a fresh one does not help: stop here
      have_jacobian = false;
      continue;
    }
    fresh = false;
    if (norm > 0.1 * report.residual_m) have_jacobian = false;  // slow: refresh next time
    q = next;
    r = next_r;
    report.residual_m = norm;
  }
  for (int k = 0; k < m; ++k) (*x)[coords[k] / 3][coords[k] % 3] = q[k];
  return report;
}

/// The cloth's static data set: positions x with P(x) = x (see polishStaticEquilibrium).
/// Phase 1 lets the cloth fall and settle dynamically until its frame-to-frame speed is below
/// kClothRestSpeedMps. That state is not exactly a fixed point of P: the Provot clamp corrects
/// positions only, so a clamped particle at rest keeps a velocity whose damping forces act on
/// its neighbours, which a prediction started from zero velocity does not see. Phase 2 polishes
/// it with Newton's method, so that the true model's static cost is ~0 (~1e-29 m^2).
Trajectory settleToEquilibrium(const Model& model) {
  Simulator simulator(model);
  const double h = 1.0 / model.frame_rate_hz;
  const int n = static_cast<int>(model.particles.size());
  State state = simulator.initialState();
  std::vector<Eigen::Vector3d> previous = state.x_m;
  int frames = 0;
  for (frames = 1; frames <= kClothMaxSettleFrames; ++frames) {
    simulator.stepFrame(&state, h);
    double max_speed = 0.0;
    for (int i = 0; i < n; ++i) max_speed = std::max(max_speed, (state.x_m[i] - previous[i]).norm() / h);
    previous = state.x_m;
    if (max_speed < kClothRestSpeedMps) break;
  }
  polishStaticEquilibrium(model, &state.x_m);
  Trajectory data;
  for (const Particle& p : model.particles) data.marker_names.push_back(p.name);
  data.frame_rate_hz = model.frame_rate_hz;
  data.resize(1);
  for (int i = 0; i < n; ++i) {
    data.positions_m[i] = state.x_m[i];
    data.occluded[i] = 0;
  }
  return data;
}

Scene makeProvotCloth() {
  Scene scene;
  Model& model = scene.model;
  model.frame_rate_hz = 100.0;
  model.substeps = 5;  // stiffest mode: omega dt ~ 0.4
  setGravity(&model, Eigen::Vector3d(0.0, 0.0, -9.81));
  const double mass = kClothMassKg / (kClothSide * kClothSide);
  char name[32];
  for (int r = 0; r < kClothSide; ++r)
    for (int c = 0; c < kClothSide; ++c) {
      std::snprintf(name, sizeof(name), "c_%d_%d", r, c);
      const bool fixed = r == 0 && (c == 0 || c == kClothSide - 1);
      addParticle(&model, Eigen::Vector3d(c * kClothPeriodM, -r * kClothPeriodM, 0.0),
                  {name, mass, Eigen::Vector3d::Zero(), fixed});
    }
  auto id = [](int r, int c) { return r * kClothSide + c; };
  struct TypeSpec {
    const char* name;
    double rest_length, stiffness, stiffness_nl, damping;
    bool clamped;
  };
  const double shear = 0.132583;  // Table I: sqrt(2) * 0.09375, rounded as printed
  const TypeSpec specs[6] = {
      {"struct_h", kClothPeriodM, 4.0, 400.0, 0.004, true},
      {"struct_v", kClothPeriodM, 4.0, 400.0, 0.004, true},
      {"shear_d1", shear, 2.0, 100.0, 0.002, false},
      {"shear_d2", shear, 2.0, 100.0, 0.002, false},
      {"flex_h", 2.0 * kClothPeriodM, 1.0, 25.0, 0.001, false},
      {"flex_v", 2.0 * kClothPeriodM, 1.0, 25.0, 0.001, false},
  };
  for (const TypeSpec& s : specs) {
    BondType type;
    type.name = s.name;
    type.kind = BondKind::kSpring;
    type.param(kStiffness) = freeMagnitude(s.stiffness);
    type.param(kRestLength) = freeLength(s.rest_length);
    type.param(kStiffnessNl) = freeMagnitude(s.stiffness_nl);
    type.param(kDamping) = valueParam(s.damping);
    if (s.clamped) type.param(kMaxElongation) = freeMagnitude(0.5);
    addBondType(&model, type);
  }
  BondType air;
  air.name = "air";
  air.kind = BondKind::kViscosity;
  air.param(kViscosity) = valueParam(5.0 * mass);  // [N s/m]: decay rate 5 /s
  const int air_type = addBondType(&model, air);
  for (int r = 0; r < kClothSide; ++r)
    for (int c = 0; c < kClothSide; ++c) {
      if (c + 1 < kClothSide) addBond(&model, 0, id(r, c), id(r, c + 1));
      if (r + 1 < kClothSide) addBond(&model, 1, id(r, c), id(r + 1, c));
      if (r + 1 < kClothSide && c + 1 < kClothSide) {
        addBond(&model, 2, id(r, c), id(r + 1, c + 1));
        addBond(&model, 3, id(r, c + 1), id(r + 1, c));
      }
      if (c + 2 < kClothSide) addBond(&model, 4, id(r, c), id(r, c + 2));
      if (r + 2 < kClothSide) addBond(&model, 5, id(r, c), id(r + 2, c));
    }
  for (int i = 0; i < kClothSide * kClothSide; ++i)
    if (!model.particles[i].fixed) addBond(&model, air_type, i);
  scene.default_frames = 300;
  scene.reference_data = settleToEquilibrium(model);
  return scene;
}

// ------------------------------------------------------------------------------------------
// fluid_jet: a 2-D jet penetrating a gas (section 4.3, Table II), after Luciani's turbulent
// fluids: no installed bonds, only conditional interactions found on the fly.
//   gas_visc [gas,gas]            viscous: damping 2.5, damping_nl 1.25, within 1.5
//   jet_visc [jet,gas], [jet,jet]  viscous: damping 4, damping_nl 2, within 2
//   elast [gas,gas],[gas,jet],[jet,jet]  elastic: stiffness 2, rest 1.1 (fixed), within 1.1
//                                  (active only below its rest length: a repulsion)
// The 8 parameters of Table II are free. Units are arbitrary (called metres), masses 1.
// Sizes: an 18 x 16 gas at spacing 1.7 (+-10 % jitter, so only some neighbours start within the
// viscous range 1.5; a slight agitation) and a 3 x 20 jet at spacing 2.0 moving at 10 m/s; over
// the 200 default frames ~81 000 interaction bonds are active in all (the paper: "about 80000"),
// growing as the jet compresses the gas. One integration step per frame (50 Hz; damping rates
// stay below the explicit limit), so that the paper's one-frame prediction from frame
// differences reproduces the true model exactly (with substeps, the velocity at the end of a
// frame differs from the frame difference and the true values no longer have zero cost).
constexpr int kGasColumns = 18, kGasRows = 16;
constexpr double kGasSpacing = 1.7;
constexpr int kJetLength = 20, kJetWidth = 3;
constexpr double kJetSpacing = 2.0;
constexpr double kJetSpeed = 10.0;
constexpr double kFluidFrameRateHz = 50.0;
constexpr int kFluidSubsteps = 1;
constexpr double kGasAgitationMps = 0.1;

Scene makeFluidJet() {
  Random random(0xf1e1d7e7ULL);
  Scene scene;
  Model& model = scene.model;
  model.frame_rate_hz = kFluidFrameRateHz;
  model.substeps = kFluidSubsteps;
  setGravity(&model, Eigen::Vector3d::Zero());
  char name[32];
  // Gas: a jittered grid (+-10 % of the spacing) with a slight agitation (+-kGasAgitationMps).
  for (int r = 0; r < kGasRows; ++r)
    for (int c = 0; c < kGasColumns; ++c) {
      const Eigen::Vector3d x((c + 0.2 * (random.uniform() - 0.5)) * kGasSpacing,
                              (r + 0.2 * (random.uniform() - 0.5)) * kGasSpacing, 0.0);
      const Eigen::Vector3d v(2.0 * kGasAgitationMps * (random.uniform() - 0.5),
                              2.0 * kGasAgitationMps * (random.uniform() - 0.5), 0.0);
      std::snprintf(name, sizeof(name), "gas_%03d", r * kGasColumns + c);
      addParticle(&model, x, {name, 1.0, v, false, "gas"});
    }
  // Jet: a stream kJetWidth wide, left of the gas, centred on it, moving right.
  const double y_centre = 0.5 * (kGasRows - 1) * kGasSpacing;
  const double x_front = -1.5 * kGasSpacing;
  for (int c = 0; c < kJetLength; ++c)
    for (int w = 0; w < kJetWidth; ++w) {
      const Eigen::Vector3d x(x_front - (c + 0.1 * (random.uniform() - 0.5)) * kJetSpacing,
                              y_centre + (w - 0.5 * (kJetWidth - 1) + 0.1 * (random.uniform() - 0.5)) * kJetSpacing,
                              0.0);
      std::snprintf(name, sizeof(name), "jet_%03d", c * kJetWidth + w);
      addParticle(&model, x, {name, 1.0, Eigen::Vector3d(kJetSpeed, 0.0, 0.0), false, "jet"});
    }
  BondType gas_visc;
  gas_visc.name = "gas_visc";
  gas_visc.param(kDamping) = freeMagnitude(2.5);
  gas_visc.param(kDampingNl) = freeMagnitude(1.25);
  gas_visc.param(kMaxDistance) = freeLength(1.5);
  const int gv = addBondType(&model, gas_visc);
  BondType jet_visc;
  jet_visc.name = "jet_visc";
  jet_visc.param(kDamping) = freeMagnitude(4.0);
  jet_visc.param(kDampingNl) = freeMagnitude(2.0);
  jet_visc.param(kMaxDistance) = freeLength(2.0);
  const int jv = addBondType(&model, jet_visc);
  BondType elast;
  elast.name = "elast";
  elast.param(kStiffness) = freeMagnitude(2.0);
  elast.param(kRestLength) = valueParam(1.1);
  elast.param(kMaxDistance) = freeLength(1.1);
  const int el = addBondType(&model, elast);
  model.interactions = {{gv, "gas", "gas"}, {jv, "jet", "gas"}, {jv, "jet", "jet"},
                        {el, "gas", "gas"}, {el, "gas", "jet"}, {el, "jet", "jet"}};
  scene.default_frames = 200;
  return scene;
}

}  // namespace

std::vector<std::string> sceneNames() { return {"paper_object", "provot_cloth", "fluid_jet", "walker"}; }

Scene makeScene(const std::string& name) {
  if (name == "paper_object") return makePaperObject();
  if (name == "provot_cloth") return makeProvotCloth();
  if (name == "fluid_jet") return makeFluidJet();
  if (name == "walker") return scene_parts::makeWalker();
  std::string known;
  for (const std::string& n : sceneNames()) known += (known.empty() ? "" : ", ") + n;
  throw InputError("unknown scene '" + name + "' (known: " + known + ")");
}

}  // namespace mme

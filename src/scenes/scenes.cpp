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

namespace mme {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// Positive magnitude (stiffness, damping, ...): bounds [truth/10, truth*10].
Param freeMagnitude(double value) { return boundedParam(value, value / 10.0, value * 10.0); }
/// Length (rest length, distance): bounds [truth/2, truth*2].
Param freeLength(double value) { return boundedParam(value, value / 2.0, value * 2.0); }

void setGravity(Model* model, const Eigen::Vector3d& g) {
  for (int k = 0; k < 3; ++k) model->gravity_mps2[k] = valueParam(g[k]);
}

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

// ------------------------------------------------------------------------------------------
// walker: the horse of section 4.4 with its 35 markers at 50 Hz (5 per leg: leg_<fl|fr|hl|hr>_0
// shoulder/hip .. _4 hoof; 15 body/head markers body_00..body_14). It trots on a floor, driven
// by known muscle controllers (docs/scenes.md "The walker": the laws, figures and limits).
//  - trunk, neck and head: one triangular prism truss along x, 6 cross-sections (x = -0.6 ..
//    1.4 m, step 0.4 m), equilateral of edge 0.4 m: two bottom "rails" (y = +-0.2 m) and a top
//    ridge; every rectangular face braced by one diagonal. Sections 0..3 are the trunk (the legs
//    hang from the rails of sections 0 and 3), 4 and 5 the neck and head; the tail (body_08) sits
//    on three soft springs behind section 0.
//  - legs: 4 segments of 0.4 m inclined +20, 0, -20, 0 degrees (forwards) from the vertical in
//    the leg's plane, which splays outwards by 10 degrees: joints of 160 degrees, _3 on the
//    line from the hip to the hoof. Flexions: "knee" at _1 and _2 (stiff), "fetlock" at _3
//    (soft: the lift muscle holds it), "hip"/"hip_hind" between the upper segment and the rail
//    one bay inwards (the fore-aft swing), and "splay" from the other hip of the pair to every
//    joint of the leg (holds the leg in its plane; it does not resist the swing).
//  - ground: a `floor` bond on every hoof (a conditional bond: it acts only below z = 0).
//  - controllers (all muscles are pure actuators: no stiffness or damping of their own):
//    * rhythm: a muscle along the tail's top spring reads that spring's elongation speed and
//      pushes the way the tail moves (negative damping, saturated by tanh): a limit cycle of the
//      tail bobbing at ~1.6 Hz. Every leg muscle reads the tail's top spring.
//    * swing (one per leg, _2 to the rail one bay inwards): a servo on the length of a soft
//      "reach" spring along it (hidden unit 0), whose target the stride moves (hidden unit 1).
//    * lift (one per leg, _2 to the hoof): a servo on a soft "cannon" spring along it, whose
//      target folds the fetlock while the leg swings and stretches it a little in stance.
//    Types come in pairs for the two diagonals (a: fl + hr, b: fr + hl) whose stride weights are
//    each other's negatives: a diagonal trot. A servo, not a passive joint, carries the load:
//    a passive fetlock stiff enough to stand would need several times the weight to fold.
// The walker starts mid-stride: the model's initial state is where a 2-s warm-up from the
// standing pose (tail pushed up) ends. 80 substeps: the stiff contact and servos (~1000 rad/s)
// need them for an integration that has converged (with 20 the motion was chaotic at round-off
// and a different gait); the gait stays the same with 100 or 160.
constexpr double kWalkerEdgeM = 0.4;                       // trunk bays and cross-sections
constexpr double kWalkerSegmentM = 0.4;                    // leg segments
constexpr double kWalkerLegTiltRad = 20.0 * kPi / 180.0;   // segment inclinations
constexpr double kWalkerSplayRad = 10.0 * kPi / 180.0;     // leg plane from the vertical
constexpr int kWalkerSubsteps = 80;
constexpr int kWalkerWarmupFrames = 100;
constexpr double kWalkerLegMassKg[5] = {8.0, 6.0, 5.0, 4.0, 4.0};  // shoulder/hip .. hoof
constexpr double kWalkerTrunkMassKg = 10.0;
constexpr double kWalkerTailMassKg = 4.0;
constexpr double kWalkerNeckMassKg = 2.0;
constexpr double kWalkerHeadMassKg = 1.0;
constexpr double kWalkerTailKickMps = 0.5;  // the tail's initial upward speed
// Controller weights (docs/scenes.md "The walker"): the tail's drive [s/m]; the stride units
// read the tail's top spring (elongation [1/m], speed [s/m], centred on its mean elongation
// [m]); the servos read their reach or cannon spring; outputs are dimensionless (the gains are
// in N).
constexpr double kTailDriveGainN = 4.43, kTailDriveSpeed = -20.0, kTailMeanM = 0.04;
constexpr double kSwingGainN = 2740.0, kSwingStrideZ = -99.6, kSwingStrideS = 0.9;
constexpr double kReachServoZ = 28.0, kReachServoS = 0.5, kReachOut = 10.0, kSwingOut = 2.73;
constexpr double kLiftGainN = 2290.0, kLiftStrideZ = -100.0, kLiftStrideS = 0.11;
constexpr double kCannonServoZ = 40.0, kCannonServoS = 0.5, kCannonOut = 10.0;
constexpr double kLiftOut = 4.74, kLiftBias = 4.47;

/// A muscle type that is a pure actuator (stiffness, rest length and damping present and 0),
/// every parameter fixed.
BondType walkerMuscleType(const std::string& name, double gain_n, int inputs, int hidden,
                          const std::vector<double>& network) {
  BondType type;
  type.name = name;
  type.kind = BondKind::kMuscle;
  type.param(kStiffness) = valueParam(0.0);
  type.param(kRestLength) = valueParam(0.0);
  type.param(kDamping) = valueParam(0.0);
  type.param(kGain) = valueParam(gain_n);
  type.network_inputs = inputs;
  type.network_hidden = hidden;
  for (double w : network) type.network.push_back(valueParam(w));
  return type;
}

/// Installs a bond and names it; returns its index.
int addNamedBond(Model* model, int type, int a, int b, const std::string& name) {
  addBond(model, type, a, b);
  model->bonds.back().name = name;
  return static_cast<int>(model->bonds.size()) - 1;
}

/// Where the walker's particles are: legs [fl, fr, hl, hr][hip .. hoof], prism sections [rear ..
/// head][left rail, right rail, ridge], the tail, and each hip's rail one bay inwards (the hip
/// flexion's third point and the swing muscle's).
struct WalkerLayout {
  static constexpr int kSections = 6;
  int leg[4][5];
  int section[kSections][3];
  int tail = -1;
  int inner_rail[4];
};

constexpr const char* kWalkerLegNames[4] = {"fl", "fr", "hl", "hr"};
constexpr double kWalkerLegX[4] = {0.6, 0.6, -0.6, -0.6};
constexpr double kWalkerLegY[4] = {0.2, -0.2, 0.2, -0.2};

/// The legs' 20 markers, then the body's (its rails and ridge, the tail, the neck and the head).
WalkerLayout placeWalkerParticles(Model* model) {
  WalkerLayout w;
  const double e = kWalkerEdgeM, seg = kWalkerSegmentM, splay = kWalkerSplayRad;
  const double leg_angles[4] = {kWalkerLegTiltRad, 0.0, -kWalkerLegTiltRad, 0.0};
  double rail_z = 0.0;
  for (double a : leg_angles) rail_z += seg * std::cos(a) * std::cos(splay);
  const double ridge_z = rail_z + e * std::sqrt(0.75);
  char name[32];
  for (int l = 0; l < 4; ++l) {
    const double side = kWalkerLegY[l] > 0 ? 1.0 : -1.0;
    Eigen::Vector3d x(kWalkerLegX[l], kWalkerLegY[l], rail_z);
    for (int k = 0; k < 5; ++k) {
      std::snprintf(name, sizeof(name), "leg_%s_%d", kWalkerLegNames[l], k);
      if (k == 4) x.z() = 0.0;  // on the floor despite rounding
      w.leg[l][k] = addParticle(model, x, {name, kWalkerLegMassKg[k]});
      if (k == 4) break;
      const double down = seg * std::cos(leg_angles[k]);
      x += Eigen::Vector3d(seg * std::sin(leg_angles[k]), side * down * std::sin(splay), -down * std::cos(splay));
    }
  }
  w.section[0][0] = w.leg[2][0];
  w.section[0][1] = w.leg[3][0];
  w.section[3][0] = w.leg[0][0];
  w.section[3][1] = w.leg[1][0];
  auto sectionPoint = [&](int s, int corner) {
    const double x = -0.6 + e * s;
    if (corner == 2) return Eigen::Vector3d(x, 0.0, ridge_z);
    return Eigen::Vector3d(x, corner == 0 ? 0.2 : -0.2, rail_z);
  };
  int next_body = 0;
  auto addBody = [&](const Eigen::Vector3d& x, double mass_kg) {
    std::snprintf(name, sizeof(name), "body_%02d", next_body++);
    return addParticle(model, x, {name, mass_kg});
  };
  for (int s = 0; s < 4; ++s) w.section[s][2] = addBody(sectionPoint(s, 2), kWalkerTrunkMassKg);  // 00-03
  for (int corner = 0; corner < 2; ++corner)  // 04-07: rails between the legs
    for (int s = 1; s <= 2; ++s) w.section[s][corner] = addBody(sectionPoint(s, corner), kWalkerTrunkMassKg);
  // Tail (body_08): apex of a regular tetrahedron on the rear face.
  const Eigen::Vector3d rear = (sectionPoint(0, 0) + sectionPoint(0, 1) + sectionPoint(0, 2)) / 3.0;
  w.tail = addBody(rear - Eigen::Vector3d(e * std::sqrt(2.0 / 3.0), 0.0, 0.0), kWalkerTailMassKg);
  for (int s = 4; s < WalkerLayout::kSections; ++s)  // 09-11 neck, 12-14 head
    for (int corner = 0; corner < 3; ++corner)
      w.section[s][corner] = addBody(sectionPoint(s, corner), s == 4 ? kWalkerNeckMassKg : kWalkerHeadMassKg);
  const int inner_rail[4] = {w.section[2][0], w.section[2][1], w.section[1][0], w.section[1][1]};
  std::copy(inner_rail, inner_rail + 4, w.inner_rail);
  return w;
}

enum WalkerSpring { kLeg, kBody, kBodyBrace, kNeck, kNeckBrace, kTail, kCannon, kReachFore, kReachHind, kSpringTypes };
enum WalkerFlexion { kKnee, kFetlock, kHipFore, kHipHind, kSplay, kFlexionTypes };

/// The walker's bond types: springs (stiffness, damping, rest length free: that of the unloaded
/// geometry), flexions (stiffness, rest angle free; damping fixed) and the ground.
struct WalkerTypes {
  int spring[kSpringTypes];
  int flexion[kFlexionTypes];
  int ground = -1;
};

WalkerTypes addWalkerTypes(Model* model, const WalkerLayout& w) {
  std::vector<Eigen::Vector3d> x0;
  for (const Particle& p : model->particles) x0.push_back(p.position_m);
  auto dist = [&](int a, int b) { return (x0[a] - x0[b]).norm(); };
  auto angle = [&](int a, int b, int c) {
    return std::acos((x0[a] - x0[b]).normalized().dot((x0[c] - x0[b]).normalized()));
  };
  const double e = kWalkerEdgeM, seg = kWalkerSegmentM;
  struct SpringSpec {
    const char* name;
    double rest_length, stiffness, damping;
  };
  const double k_leg = 3.0e5, k_body = 3.0e5;
  const SpringSpec springs[kSpringTypes] = {
      {"leg_spring", seg, k_leg, 0.0003 * k_leg},
      {"body_spring", e, k_body, 0.0003 * k_body},
      {"body_brace", e * std::sqrt(2.0), 0.5 * k_body, 0.00015 * k_body},
      {"neck_spring", e, 0.4 * k_body, 0.0001 * k_body},
      {"neck_brace", e * std::sqrt(2.0), 0.25 * k_body, 0.00005 * k_body},
      {"tail_spring", e, 1200.0, 2.0},
      // The servos' sensors: soft springs along the lift and swing muscles.
      {"cannon", dist(w.leg[0][2], w.leg[0][4]), 2000.0, 5.0},
      {"reach_fore", dist(w.leg[0][2], w.inner_rail[0]), 2000.0, 5.0},
      {"reach_hind", dist(w.leg[2][2], w.inner_rail[2]), 2000.0, 5.0}};
  WalkerTypes types;
  for (int t = 0; t < kSpringTypes; ++t) {
    BondType type;
    type.name = springs[t].name;
    type.param(kStiffness) = freeMagnitude(springs[t].stiffness);
    type.param(kDamping) = freeMagnitude(springs[t].damping);
    type.param(kRestLength) = freeLength(springs[t].rest_length);
    types.spring[t] = addBondType(model, type);
  }
  struct FlexionSpec {
    const char* name;
    double rest_angle, stiffness, damping;
  };
  const FlexionSpec flexions[kFlexionTypes] = {
      {"knee", angle(w.leg[0][0], w.leg[0][1], w.leg[0][2]), 1.0e5, 100.0},
      {"fetlock", angle(w.leg[0][2], w.leg[0][3], w.leg[0][4]), 200.0, 10.0},
      {"hip", angle(w.leg[0][1], w.leg[0][0], w.inner_rail[0]), 7460.0, 100.0},
      {"hip_hind", angle(w.leg[2][1], w.leg[2][0], w.inner_rail[2]), 7460.0, 100.0},
      {"splay", angle(w.leg[1][0], w.leg[0][0], w.leg[0][4]), 3.0e4, 100.0}};
  for (int t = 0; t < kFlexionTypes; ++t) {
    BondType type;
    type.name = flexions[t].name;
    type.kind = BondKind::kFlexion;
    type.param(kStiffness) = freeMagnitude(flexions[t].stiffness);
    type.param(kRestAngle) = boundedParam(flexions[t].rest_angle, 0.5 * flexions[t].rest_angle,
                                          std::min(kPi, 2.0 * flexions[t].rest_angle));
    type.param(kDamping) = valueParam(flexions[t].damping);
    types.flexion[t] = addBondType(model, type);
  }
  // Ground contact, free: stiffness, damping, friction; the floor's height (0) and contact
  // depth fixed. The damping and friction grow over the first 0.3 mm of the 4.5-6 mm a stance
  // hoof sinks: without that the force jumps at touch-down and gradient fits stall on the jumps
  // it makes in the motion (docs/scenes.md "Identifying the walker").
  BondType ground;
  ground.name = "ground";
  ground.kind = BondKind::kFloor;
  ground.param(kStiffness) = freeMagnitude(5.0e5);
  ground.param(kDamping) = freeMagnitude(2000.0);
  ground.param(kFriction) = freeMagnitude(4000.0);
  ground.param(kHeight) = valueParam(0.0);
  ground.param(kContactDepth) = valueParam(3.0e-4);
  types.ground = addBondType(model, ground);
  return types;
}

/// Legs: segments, joints, hips, splay (from the other hip of the pair), ground contact.
void addWalkerLegBonds(Model* model, const WalkerLayout& w, const WalkerTypes& types) {
  for (int l = 0; l < 4; ++l) {
    const int other_hip = w.leg[l ^ 1][0];
    for (int k = 0; k < 4; ++k) addBond(model, types.spring[kLeg], w.leg[l][k], w.leg[l][k + 1]);
    for (int k = 1; k <= 3; ++k)
      addBond(model, types.flexion[k == 3 ? kFetlock : kKnee], w.leg[l][k - 1], w.leg[l][k], w.leg[l][k + 1]);
    addBond(model, types.flexion[kWalkerLegX[l] > 0 ? kHipFore : kHipHind], w.leg[l][1], w.leg[l][0],
            w.inner_rail[l]);
    for (int k = 1; k <= 4; ++k) addBond(model, types.flexion[kSplay], other_hip, w.leg[l][0], w.leg[l][k]);
    addBond(model, types.ground, w.leg[l][4]);
  }
}

/// Prism: cross-section triangles, then per bay 3 longitudinal edges and 3 face diagonals.
void addWalkerPrismBonds(Model* model, const WalkerLayout& w, const WalkerTypes& types) {
  for (int s = 0; s < WalkerLayout::kSections; ++s) {
    const int edge = s < 4 ? types.spring[kBody] : types.spring[kNeck];
    addBond(model, edge, w.section[s][0], w.section[s][1]);
    addBond(model, edge, w.section[s][0], w.section[s][2]);
    addBond(model, edge, w.section[s][1], w.section[s][2]);
  }
  for (int s = 0; s + 1 < WalkerLayout::kSections; ++s) {
    const int edge = s < 3 ? types.spring[kBody] : types.spring[kNeck];
    const int brace = s < 3 ? types.spring[kBodyBrace] : types.spring[kNeckBrace];
    for (int corner = 0; corner < 3; ++corner) addBond(model, edge, w.section[s][corner], w.section[s + 1][corner]);
    addBond(model, brace, w.section[s][0], w.section[s + 1][2]);
    addBond(model, brace, w.section[s][1], w.section[s + 1][2]);
    addBond(model, brace, w.section[s][0], w.section[s + 1][1]);
  }
}

/// The muscles: the tail's drive (y = w s_top), then per diagonal a swing and a lift muscle
/// reading (tail top, sensor); hidden 0 = the servo on the sensor's length, hidden 1 = the
/// stride (sign +-1 per diagonal); y = servo_out h0 + stride_out h1 + b2.
void addWalkerMuscles(Model* model, const WalkerLayout& w, int tail_top, const int cannon[4],
                      const int reach[4]) {
  const int tail_drive = addBondType(model, walkerMuscleType("tail_drive", kTailDriveGainN, 1, 0,
                                                             {0.0, kTailDriveSpeed, 0.0}));
  addBond(model, tail_drive, w.tail, w.section[0][2]);
  model->bonds.back().inputs = {tail_top};
  int swing[2], lift[2];
  for (int d = 0; d < 2; ++d) {
    const double sign = d == 0 ? 1.0 : -1.0;
    const std::string diagonal = d == 0 ? "_a" : "_b";
    swing[d] = addBondType(model, walkerMuscleType("swing" + diagonal, kSwingGainN, 2, 2,
                                                   {0.0, kReachServoZ, 0.0, kReachServoS,                   // w1_0_*
                                                    sign * kSwingStrideZ, 0.0, sign * kSwingStrideS, 0.0,   // w1_1_*
                                                    0.0, -sign * kSwingStrideZ * kTailMeanM,                // b1
                                                    kReachOut, kSwingOut, 0.0}));                           // w2, b2
    lift[d] = addBondType(model, walkerMuscleType("lift" + diagonal, kLiftGainN, 2, 2,
                                                  {0.0, kCannonServoZ, 0.0, kCannonServoS,                  // w1_0_*
                                                   sign * kLiftStrideZ, 0.0, sign * kLiftStrideS, 0.0,      // w1_1_*
                                                   0.0, -sign * kLiftStrideZ * kTailMeanM,                  // b1
                                                   kCannonOut, kLiftOut, kLiftBias}));                      // w2, b2
  }
  // A swing muscle's tension pulls the knee backwards on a fore leg, forwards on a hind one: the
  // left legs (fl, hl) take swing_a, the right ones swing_b, so that fl and hr push back while
  // fr and hl swing forward. The lifts go by diagonal.
  const int lift_diagonal[4] = {0, 1, 1, 0};
  for (int l = 0; l < 4; ++l) {
    addBond(model, swing[kWalkerLegY[l] > 0 ? 0 : 1], w.leg[l][2], w.inner_rail[l]);
    model->bonds.back().inputs = {tail_top, reach[l]};
    addBond(model, lift[lift_diagonal[l]], w.leg[l][2], w.leg[l][4]);
    model->bonds.back().inputs = {tail_top, cannon[l]};
  }
}

/// Warm-up from the standing pose with the tail pushed up; the scene starts where it ends.
void warmUpWalker(Model* model, int tail) {
  model->particles[tail].velocity_mps = Eigen::Vector3d(0.0, 0.0, kWalkerTailKickMps);
  Simulator simulator(*model);
  State state = simulator.initialState();
  for (int f = 0; f < kWalkerWarmupFrames; ++f) simulator.stepFrame(&state, 1.0 / model->frame_rate_hz);
  for (size_t i = 0; i < model->particles.size(); ++i) {
    model->particles[i].position_m = state.x_m[i];
    model->particles[i].velocity_mps = state.v_mps[i];
  }
}

Scene makeWalker() {
  Scene scene;
  Model& model = scene.model;
  model.frame_rate_hz = 50.0;
  model.substeps = kWalkerSubsteps;
  setGravity(&model, Eigen::Vector3d(0.0, 0.0, -9.81));
  const WalkerLayout w = placeWalkerParticles(&model);
  const WalkerTypes types = addWalkerTypes(&model, w);
  addWalkerLegBonds(&model, w, types);
  // The servos' sensor springs: cannons (_2 to the hoof), reaches (_2 to the inner rail).
  int cannon[4], reach[4];
  for (int l = 0; l < 4; ++l)
    cannon[l] = addNamedBond(&model, types.spring[kCannon], w.leg[l][2], w.leg[l][4],
                             std::string("cannon_") + kWalkerLegNames[l]);
  for (int l = 0; l < 4; ++l)
    reach[l] = addNamedBond(&model, types.spring[kWalkerLegX[l] > 0 ? kReachFore : kReachHind], w.leg[l][2],
                            w.inner_rail[l], std::string("reach_") + kWalkerLegNames[l]);
  addWalkerPrismBonds(&model, w, types);
  // Tail: three soft springs to the rear section, named (the top one is every muscle's input).
  const char* tail_names[3] = {"tail_left", "tail_right", "tail_top"};
  int tail_top = -1;
  for (int corner = 0; corner < 3; ++corner)
    tail_top = addNamedBond(&model, types.spring[kTail], w.tail, w.section[0][corner], tail_names[corner]);
  addWalkerMuscles(&model, w, tail_top, cannon, reach);
  warmUpWalker(&model, w.tail);
  scene.default_frames = 250;
  return scene;
}

}  // namespace

std::vector<std::string> sceneNames() { return {"paper_object", "provot_cloth", "fluid_jet", "walker"}; }

Scene makeScene(const std::string& name) {
  if (name == "paper_object") return makePaperObject();
  if (name == "provot_cloth") return makeProvotCloth();
  if (name == "fluid_jet") return makeFluidJet();
  if (name == "walker") return makeWalker();
  std::string known;
  for (const std::string& n : sceneNames()) known += (known.empty() ? "" : ", ") + n;
  throw InputError("unknown scene '" + name + "' (known: " + known + ")");
}

}  // namespace mme

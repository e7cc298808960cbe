// Private to the core: the compiled motion law shared by Simulator and ShortTermCost.
//
// Both the simulator and the cost integrate with this one Engine so that, for the same inputs,
// they do bit-identical arithmetic (the true model then has zero cost on its own simulated
// data up to the rounding of the observed velocity). Positions, velocities and forces are flat
// double arrays of 3N (x, y, z per particle): the layout of std::vector<Eigen::Vector3d>, so the
// simulator uses its State directly, and plain doubles so there is no aliasing question.
#pragma once

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>


#include "motion_model_estimation/core/forces.h"
#include "motion_model_estimation/core/model.h"

namespace mme {
namespace detail {

/// Sentinel meaning "no upper distance condition" (matches SpringLaw's default).
constexpr double kNoMaxDistance_m = 1e300;
/// Flexion is skipped below these (angle gradient undefined) [m], [1].
constexpr double kFlexionMinLength_m = 1e-12;
constexpr double kFlexionMinSin = 1e-9;

struct PairIdx {
  int32_t a, b;
};
/// Contiguous range [begin, end) of a pair array sharing one law (`law` indexes a law array).
struct SpringRun {
  int32_t law;
  uint32_t begin, end;
};
struct FlexionBond {
  int32_t a, b, c, type;
};
struct UnaryBond {
  int32_t p, type;
};  // viscosity and floor bonds
struct ClampBond {
  int32_t a, b, type;
};
/// A muscle bond: its ends, its type, and its input bonds muscle_inputs_[input_begin, input_end).
struct MuscleBond {
  int32_t a, b, type;
  uint32_t input_begin, input_end;
};
/// A bond of a kind without a fast path: the particles it joins (its kind's arity of them), its
/// type and its kind's law (bondLaw).
struct GenericBond {
  int32_t p[3];
  int32_t type;
  const BondLaw* law;
};
/// A bond a muscle reads: its ends and its type (whose rest length gives the elongation).
struct InputBond {
  int32_t a, b, type;
};
/// A muscle type's activation parameters: gain, layout, and where its network starts in
/// LawTable::network.
struct MuscleTypeLaw {
  double gain_n = 0.0;
  double activation_time_s = 0.0;  // > 0: the activation is a state (Simulator, State)
  int32_t hidden = 0;  // the input count is the bond's (validateModel: the type's)
  uint32_t network_offset = 0;
};

/// Current parameter values per bond type (indexed by bond type), in the inner loop's form.
/// Types are few, so the whole table stays in L1.
struct LawTable {
  std::vector<SpringLaw> spring;
  std::vector<FlexionLaw> flexion;
  std::vector<double> viscosity_nspm;    ///< unary viscosity c
  std::vector<double> max_elongation;    ///< Provot tau (only used by clamp bonds)
  std::vector<FloorLaw> floor;           ///< ground contact
  std::vector<MuscleTypeLaw> muscle;     ///< activation of muscle types (passive part: spring)
  std::vector<double> network;           ///< every muscle type's network parameters, concatenated
  /// Every type's value of every ParamId, kParamCount per type (absent: ParamInfo::absent_value):
  /// the generic path's parameters, and the source the law forms above are derived from.
  std::vector<double> values;
  double gravity_mps2[3] = {0, 0, 0};

  void load(const Model& model);
  /// Writes one parameter (as addressed by freeParameters / presentParameters).
  void set(const ParamRef& ref, double value);
  /// Type t's parameters (kParamCount values, indexed by ParamId).
  const double* valuesOf(size_t t) const { return values.data() + t * kParamCount; }

 private:
  /// Derives type t's law forms from its values.
  void derive(size_t t);
};

// ------------------------------------------------------------------ per-bond kernels
// Templated on which terms are non-zero so the common linear undamped spring is a short,
// branch-free sequence; the general form (all true) is what forces.cpp exposes.

/// Tension of a spring from its geometry (shared by the scalar and the blocked kernels).
template <bool kDamp, bool kNl, bool kCond>
inline double springTension(const SpringLaw& law, double l, double ux, double uy, double uz,
                            const double* va, const double* vb) {
  const double e = l - law.rest_length;
  double t = law.stiffness * e;
  if (kNl) t += law.stiffness_nl * (e * e * e);
  if (kDamp) {
    const double s = (vb[0] - va[0]) * ux + (vb[1] - va[1]) * uy + (vb[2] - va[2]) * uz;
    t += law.damping * s + law.damping_nl * (s * std::fabs(s));
  }
  if (kCond) t = (l >= law.min_distance && l <= law.max_distance) ? t : 0.0;
  return t;
}

template <bool kDamp, bool kNl, bool kCond>
inline void springPair(const SpringLaw& law, const double* xa, const double* xb,
                       const double* va, const double* vb, double* fa, double* fb) {
  const double dx = xb[0] - xa[0], dy = xb[1] - xa[1], dz = xb[2] - xa[2];
  const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
  // l == 0 gives d == 0, hence u == 0 and no force, without a branch.
  const double inv_l = 1.0 / std::max(l, DBL_MIN);
  const double ux = dx * inv_l, uy = dy * inv_l, uz = dz * inv_l;
  const double t = springTension<kDamp, kNl, kCond>(law, l, ux, uy, uz, va, vb);
  const double fx = t * ux, fy = t * uy, fz = t * uz;
  fa[0] += fx; fa[1] += fy; fa[2] += fz;
  fb[0] -= fx; fb[1] -= fy; fb[2] -= fz;
}

/// Springs [begin, end) of `pairs` with one law (loop-invariant, kept in registers).
/// A blocked variant doing the square roots and divisions as packed SSE2 was measured no
/// faster on the target machine, so the plain loop stays.
template <bool kDamp, bool kNl, bool kCond>
inline void springRunT(const SpringLaw& law, const PairIdx* pairs, uint32_t begin, uint32_t end,
                       const double* __restrict x, const double* __restrict v,
                       double* __restrict f) {
  // A local copy: the force stores could otherwise alias the law, forcing a reload of every
  // parameter on every spring.
  const SpringLaw local_law = law;
  for (uint32_t k = begin; k < end; ++k) {
    const int32_t a = 3 * pairs[k].a, b = 3 * pairs[k].b;
    springPair<kDamp, kNl, kCond>(local_law, x + a, x + b, v + a, v + b, f + a, f + b);
  }
}

/// Which template a law needs: skipping zero terms gives the same forces (adding exact zeros).
inline void springRun(const SpringLaw& law, const PairIdx* pairs, uint32_t begin, uint32_t end,
                      const double* x, const double* v, double* f) {
  const bool damp = law.damping != 0.0 || law.damping_nl != 0.0;
  const bool nl = law.stiffness_nl != 0.0;
  const bool cond = law.min_distance > 0.0 || law.max_distance < kNoMaxDistance_m;
  const int sel = (damp ? 4 : 0) | (nl ? 2 : 0) | (cond ? 1 : 0);
  switch (sel) {
    case 0: springRunT<false, false, false>(law, pairs, begin, end, x, v, f); break;
    case 1: springRunT<false, false, true>(law, pairs, begin, end, x, v, f); break;
    case 2: springRunT<false, true, false>(law, pairs, begin, end, x, v, f); break;
    case 3: springRunT<false, true, true>(law, pairs, begin, end, x, v, f); break;
    case 4: springRunT<true, false, false>(law, pairs, begin, end, x, v, f); break;
    case 5: springRunT<true, false, true>(law, pairs, begin, end, x, v, f); break;
    case 6: springRunT<true, true, false>(law, pairs, begin, end, x, v, f); break;
    default: springRunT<true, true, true>(law, pairs, begin, end, x, v, f); break;
  }
}

/// A muscle: the visco-elastic tension of its spring law plus the activation a [N].
inline void musclePair(const SpringLaw& law, double activation_n, const double* xa,
                       const double* xb, const double* va, const double* vb, double* fa,
                       double* fb) {
  const double dx = xb[0] - xa[0], dy = xb[1] - xa[1], dz = xb[2] - xa[2];
  const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
  const double inv_l = 1.0 / std::max(l, DBL_MIN);
  const double ux = dx * inv_l, uy = dy * inv_l, uz = dz * inv_l;
  const double t = springTension<true, false, false>(law, l, ux, uy, uz, va, vb) + activation_n;
  const double fx = t * ux, fy = t * uy, fz = t * uz;
  fa[0] += fx; fa[1] += fy; fa[2] += fz;
  fb[0] -= fx; fb[1] -= fy; fb[2] -= fz;
}

/// Ground contact (FloorLaw): normal penalty force while below the plane, viscous friction;
/// damping and friction ramped in over law.contact_depth.
inline void floorForceRaw(const FloorLaw& law, const double* x, const double* v, double* f) {
  const double penetration_m = law.height - x[2];
  if (!(penetration_m > 0.0)) return;
  // r ramps damping and friction in over the contact depth: no jump at touch-down.
  const double r = penetration_m < law.contact_depth ? penetration_m / law.contact_depth : 1.0;
  f[0] -= r * law.friction * v[0];
  f[1] -= r * law.friction * v[1];
  f[2] += std::max(0.0, law.stiffness * penetration_m - r * law.damping * v[2]);
}

/// Elongation l - rest_length [m] and elongation speed (v_b - v_a).u [m/s] of a pair bond.
inline void elongationRaw(double rest_length_m, const double* xa, const double* xb,
                          const double* va, const double* vb, double* e_m, double* s_mps) {
  const double dx = xb[0] - xa[0], dy = xb[1] - xa[1], dz = xb[2] - xa[2];
  const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
  const double inv_l = 1.0 / std::max(l, DBL_MIN);
  *e_m = l - rest_length_m;
  *s_mps = ((vb[0] - va[0]) * dx + (vb[1] - va[1]) * dy + (vb[2] - va[2]) * dz) * inv_l;
}

inline double springEnergyRaw(const SpringLaw& law, const double* xa, const double* xb) {
  const double dx = xb[0] - xa[0], dy = xb[1] - xa[1], dz = xb[2] - xa[2];
  const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (!(l >= law.min_distance && l <= law.max_distance)) return 0.0;
  const double e = l - law.rest_length;
  const double e2 = e * e;
  return 0.5 * law.stiffness * e2 + 0.25 * law.stiffness_nl * e2 * e2;
}

inline double flexionAngleRaw(const double* xa, const double* xb, const double* xc) {
  const double u[3] = {xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2]};
  const double w[3] = {xc[0] - xb[0], xc[1] - xb[1], xc[2] - xb[2]};
  const double cx = u[1] * w[2] - u[2] * w[1];
  const double cy = u[2] * w[0] - u[0] * w[2];
  const double cz = u[0] * w[1] - u[1] * w[0];
  // atan2 of (|u x w|, u.w) is accurate over the whole [0, pi], unlike acos near 0 and pi.
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), u[0] * w[0] + u[1] * w[1] + u[2] * w[2]);
}

/// Flexion at vertex b: torque T = -k (theta - theta0) - c dtheta/dt, F_i = T dtheta/dx_i with
/// dtheta/du = -(w^ - cos(theta) u^) / (|u| sin(theta)), u = xa - xb, w = xc - xb.
inline void flexionForceRaw(const FlexionLaw& law, const double* xa, const double* xb,
                            const double* xc, const double* va, const double* vb,
                            const double* vc, double* fa, double* fb, double* fc) {
  const double u[3] = {xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2]};
  const double w[3] = {xc[0] - xb[0], xc[1] - xb[1], xc[2] - xb[2]};
  const double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  const double lw = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  if (!(lu > kFlexionMinLength_m && lw > kFlexionMinLength_m)) return;
  const double cx = u[1] * w[2] - u[2] * w[1];
  const double cy = u[2] * w[0] - u[0] * w[2];
  const double cz = u[0] * w[1] - u[1] * w[0];
  const double cross = std::sqrt(cx * cx + cy * cy + cz * cz);
  const double dot = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
  const double theta = std::atan2(cross, dot);
  const double luw = lu * lw;
  const double sin_t = cross / luw, cos_t = dot / luw;
  // Straight or folded-back: the gradient direction is undefined, so no force.
  if (!(sin_t > kFlexionMinSin)) return;
  const double inv_lu = 1.0 / lu, inv_lw = 1.0 / lw;
  const double ga_s = -1.0 / (lu * sin_t), gc_s = -1.0 / (lw * sin_t);
  double ga[3], gc[3], gb[3];
  for (int k = 0; k < 3; ++k) {
    const double uh = u[k] * inv_lu, wh = w[k] * inv_lw;
    ga[k] = ga_s * (wh - cos_t * uh);
    gc[k] = gc_s * (uh - cos_t * wh);
    gb[k] = -(ga[k] + gc[k]);
  }
  double torque = -law.stiffness * (theta - law.rest_angle);
  if (law.damping != 0.0) {
    const double theta_dot = ga[0] * va[0] + ga[1] * va[1] + ga[2] * va[2] + gb[0] * vb[0] +
                             gb[1] * vb[1] + gb[2] * vb[2] + gc[0] * vc[0] + gc[1] * vc[1] +
                             gc[2] * vc[2];
    torque -= law.damping * theta_dot;
  }
  for (int k = 0; k < 3; ++k) {
    fa[k] += torque * ga[k];
    fb[k] += torque * gb[k];
    fc[k] += torque * gc[k];
  }
}

inline double flexionEnergyRaw(const FlexionLaw& law, const double* xa, const double* xb,
                               const double* xc) {
  const double d = flexionAngleRaw(xa, xb, xc) - law.rest_angle;
  return 0.5 * law.stiffness * d * d;
}

// The law forms from a type's value of every ParamId (LawTable::values' layout).
inline SpringLaw springLawOf(const double* p) {
  SpringLaw law;
  law.stiffness = p[kStiffness];
  law.rest_length = p[kRestLength];
  law.damping = p[kDamping];
  law.stiffness_nl = p[kStiffnessNl];
  law.damping_nl = p[kDampingNl];
  law.min_distance = p[kMinDistance];
  law.max_distance = p[kMaxDistance];
  return law;
}
inline FlexionLaw flexionLawOf(const double* p) {
  FlexionLaw law;
  law.stiffness = p[kStiffness];
  law.rest_angle = p[kRestAngle];
  law.damping = p[kDamping];
  return law;
}
inline FloorLaw floorLawOf(const double* p) {
  return {p[kStiffness], p[kDamping], p[kFriction], p[kHeight], p[kContactDepth]};
}

// ------------------------------------------------------------------ compiled model

/// The model's structure (what does not change with parameter values), laid out for the
/// inner loops: springs grouped into per-type runs, int32 indices, per-component mass arrays.
class Engine {
 public:
  Engine() = default;
  /// `fast_paths` false sends every bond whose kind has a generic law (bondLaw) through the
  /// generic per-bond path, so a test can check that path against the fast ones.
  explicit Engine(const Model& model, bool fast_paths = true);

  int numParticles() const { return n_; }
  size_t numSprings() const { return spring_pairs_.size(); }
  size_t numFlexions() const { return flexions_.size(); }
  size_t numMuscles() const { return muscles_.size(); }
  size_t numGenericBonds() const { return generic_.size(); }
  /// The muscles in bond order (the order of State::activation_n).
  const std::vector<MuscleBond>& muscles() const { return muscles_; }
  const std::vector<uint8_t>& fixed() const { return fixed_; }

  /// f = gravity + unary viscosity + installed springs + flexion + muscles + floor contacts +
  /// bonds on the generic path + the given interaction runs
  /// (pairs[run.begin..run.end) with law inter_laws[run.law]).
  /// A muscle's activation is its network's output (its excitation) unless `activation_n` is
  /// given and its type has an activation time constant: then activation_n[k] (k: the muscle's
  /// index in bond order). `excitation_n`, when given, receives every muscle's excitation.
  void forces(const LawTable& laws, const double* x, const double* v, double* f,
              const SpringLaw* inter_laws, const PairIdx* inter_pairs,
              const SpringRun* inter_runs, size_t num_inter_runs,
              const double* activation_n = nullptr, double* excitation_n = nullptr) const;
  /// Semi-implicit Euler on free particles: v += dt F/m; x += dt v. Fixed ones keep x and v.
  void integrate(double dt_s, const double* f, double* x, double* v) const;
  /// Provot: one pass in bond order over springs whose type has max_elongation.
  void clamp(const LawTable& laws, double* x) const;
  /// Elastic energy of installed springs, flexion bonds, muscles' passive parts and generic bonds
  /// whose law has an energy (interactions excluded) [J].
  double bondEnergy(const LawTable& laws, const double* x) const;

 private:
  int n_ = 0;
  std::vector<double> inv_mass3_;  // 1/m per component, 0 for fixed particles
  std::vector<double> mobile3_;    // 1 per component, 0 for fixed particles
  std::vector<double> mass_;
  std::vector<uint8_t> fixed_;
  std::vector<PairIdx> spring_pairs_;  // grouped by type (stable within a type)
  std::vector<SpringRun> spring_runs_;
  std::vector<FlexionBond> flexions_;
  std::vector<UnaryBond> unary_;
  std::vector<UnaryBond> floors_;  // in bond order
  std::vector<ClampBond> clamps_;  // in bond order
  std::vector<MuscleBond> muscles_;      // in bond order
  std::vector<InputBond> muscle_inputs_;
  std::vector<GenericBond> generic_;  // in bond order

  void muscleForces(const LawTable& laws, const double* x, const double* v, double* f,
                    const double* activation_n, double* excitation_n) const;
  void genericForces(const LawTable& laws, const double* x, const double* v, double* f) const;
};

}  // namespace detail
}  // namespace mme

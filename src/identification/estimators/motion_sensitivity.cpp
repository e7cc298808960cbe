// Forward sensitivities of the semi-implicit Euler step. With F(x, v, p) the total force,
//   v' = v + dt F / m,  x' = x + dt v'
// gives, for S_x = dx/dq and S_v = dv/dq,
//   S_v' = S_v + dt/m (F_x S_x + F_v S_v + F_p),  S_x' = S_x + dt S_v'.
// F_x, F_v and F_p are summed bond by bond: each bond's local Jacobian (its own particles and its
// type's parameters) comes from Ceres' Jets on a templated copy of its force law (the same
// formulas as the engine's kernels, core/engine.h), so the sparsity of a step is kept: a bond
// touches only its particles' rows, its parameters only their own column.
#include "motion_model_estimation/identification/estimators/motion_sensitivity.h"

#include <ceres/jet.h>

#include <algorithm>
#include <cmath>

#include "motion_model_estimation/core/bond_kind.h"
#include "motion_model_estimation/core/error.h"

namespace mme {

namespace {

// Below these the flexion angle's gradient is undefined and the engine applies no force [m], [1].
constexpr double kFlexionMinLength_m = 1e-12;
constexpr double kFlexionMinSin = 1e-9;

/// A spring's force on its first particle (the second gets the opposite) from d = x_b - x_a,
/// w = v_b - v_a and its parameters p = (k, L, c, k_nl, c_nl); false when it acts not at all.
template <typename T>
bool springForceOnA(const T* d, const T* w, const T* p, double min_distance_m, double max_distance_m,
                    T* fa) {
  using std::abs;
  using std::sqrt;
  const T l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(l > 0.0) || !(l >= min_distance_m && l <= max_distance_m)) return false;
  const T u[3] = {d[0] / l, d[1] / l, d[2] / l};
  const T e = l - p[1];
  const T s = w[0] * u[0] + w[1] * u[1] + w[2] * u[2];
  const T tension = p[0] * e + p[3] * (e * e * e) + p[2] * s + p[4] * (s * abs(s));
  for (int k = 0; k < 3; ++k) fa[k] = tension * u[k];
  return true;
}

/// Flexion forces on a, b (vertex) and c from positions x (9), velocities v (9) and p = (k,
/// theta0, c); false when the angle's gradient is undefined.
template <typename T>
bool flexionForces(const T* x, const T* v, const T* p, T* f) {
  using std::atan2;
  using std::sqrt;
  const T u[3] = {x[0] - x[3], x[1] - x[4], x[2] - x[5]};
  const T w[3] = {x[6] - x[3], x[7] - x[4], x[8] - x[5]};
  const T lu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  const T lw = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  if (!(lu > kFlexionMinLength_m && lw > kFlexionMinLength_m)) return false;
  const T cx = u[1] * w[2] - u[2] * w[1], cy = u[2] * w[0] - u[0] * w[2], cz = u[0] * w[1] - u[1] * w[0];
  const T cross = sqrt(cx * cx + cy * cy + cz * cz);
  const T dot = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
  const T theta = atan2(cross, dot);
  const T sin_t = cross / (lu * lw), cos_t = dot / (lu * lw);
  if (!(sin_t > kFlexionMinSin)) return false;
  T ga[3], gb[3], gc[3];
  for (int k = 0; k < 3; ++k) {
    const T uh = u[k] / lu, wh = w[k] / lw;
    ga[k] = -(wh - cos_t * uh) / (lu * sin_t);
    gc[k] = -(uh - cos_t * wh) / (lw * sin_t);
    gb[k] = -(ga[k] + gc[k]);
  }
  T theta_dot = T(0.0);
  for (int k = 0; k < 3; ++k) theta_dot += ga[k] * v[k] + gb[k] * v[3 + k] + gc[k] * v[6 + k];
  const T torque = -p[0] * (theta - p[1]) - p[2] * theta_dot;
  for (int k = 0; k < 3; ++k) {
    f[k] = torque * ga[k];
    f[3 + k] = torque * gb[k];
    f[6 + k] = torque * gc[k];
  }
  return true;
}

/// The floor's force on a particle at x with velocity v, p = (k, c, mu, height, contact depth);
/// false out of contact.
template <typename T>
bool floorForce(const T* x, const T* v, const T* p, T* f) {
  const T penetration = p[3] - x[2];
  if (!(penetration > 0.0)) return false;
  const T r = penetration < p[4] ? penetration / p[4] : T(1.0);
  f[0] = -r * p[2] * v[0];
  f[1] = -r * p[2] * v[1];
  const T normal = p[0] * penetration - r * p[1] * v[2];
  f[2] = normal > 0.0 ? normal : T(0.0);
  return true;
}

constexpr ParamId kSpringParams[5] = {kStiffness, kRestLength, kDamping, kStiffnessNl, kDampingNl};
constexpr ParamId kFlexionParams[3] = {kStiffness, kRestAngle, kDamping};
constexpr ParamId kFloorParams[5] = {kStiffness, kDamping, kFriction, kHeight, kContactDepth};

struct Bond3 {
  int p[3];
  int type;
};

}  // namespace

std::string sensitivityUnsupportedReason(const Model& model) {
  if (!model.interactions.empty())
    return "interactions (bonds that appear and vanish with distance) are differentiated by finite differences";
  for (const BondType& type : model.bond_types) {
    // No default: a new kind must say here whether its law is differentiated (-Werror=switch).
    switch (type.kind) {
      case BondKind::kMuscle:
        return "muscles (a force driven by a network over other bonds) are differentiated by "
               "finite differences";
      case BondKind::kSpring:
        if (type.param(kMaxElongation).present)
          return "Provot's clamp (max_elongation, a projection after the step) is differentiated "
                 "by finite differences";
        break;
      case BondKind::kFlexion:
      case BondKind::kViscosity:
      case BondKind::kFloor:
        break;
    }
  }
  return "";
}

struct MotionSensitivity::Impl {
  int n = 0;
  int substeps = 1;
  std::vector<double> mass;
  std::vector<int> free_particles;
  std::vector<ParamRef> params;
  std::vector<int> column_of;  // type * kParamCount + id -> parameter column, or -1
  int gravity_column[3] = {-1, -1, -1};
  bool parameter_columns = true;
  std::vector<double> values;  // type * kParamCount + id -> value (absent: its absent value)
  double gravity[3] = {0, 0, 0};
  std::vector<Bond3> springs, flexions, drags, floors;
  State s;
  Matrix sx, sv, df, diff_x, diff_v, block;
  std::vector<double> f;

  int columnCount() const {
    return (parameter_columns ? static_cast<int>(params.size()) : 0) + 6 * static_cast<int>(free_particles.size());
  }
  int paramColumn(int type, ParamId id) const {
    return parameter_columns ? column_of[static_cast<size_t>(type) * kParamCount + id] : -1;
  }
  const double* typeValues(int type) const { return values.data() + static_cast<size_t>(type) * kParamCount; }

  void addSprings();
  void addFlexions();
  void addDragsAndFloors();
  void step(double dt_s);
};

void MotionSensitivity::Impl::addSprings() {
  using J = ceres::Jet<double, 11>;  // d (3), w (3), the 5 parameters
  const double* x = s.x_m[0].data();
  const double* v = s.v_mps[0].data();
  for (const Bond3& b : springs) {
    const double* p = typeValues(b.type);
    const int a3 = 3 * b.p[0], b3 = 3 * b.p[1];
    J d[3], w[3], pj[5], fa[3];
    for (int k = 0; k < 3; ++k) {
      d[k] = J(x[b3 + k] - x[a3 + k], k);
      w[k] = J(v[b3 + k] - v[a3 + k], 3 + k);
    }
    for (int j = 0; j < 5; ++j) pj[j] = J(p[kSpringParams[j]], 6 + j);
    if (!springForceOnA(d, w, pj, p[kMinDistance], p[kMaxDistance], fa)) continue;
    Eigen::Matrix3d kd, kw;
    for (int r = 0; r < 3; ++r) {
      f[a3 + r] += fa[r].a;
      f[b3 + r] -= fa[r].a;
      for (int k = 0; k < 3; ++k) {
        kd(r, k) = fa[r].v[k];
        kw(r, k) = fa[r].v[3 + k];
      }
    }
    // The force depends on the differences only: one product per derivative, +/- per end.
    diff_x = sx.middleRows<3>(b3) - sx.middleRows<3>(a3);
    diff_v = sv.middleRows<3>(b3) - sv.middleRows<3>(a3);
    block.noalias() = kd * diff_x;
    block.noalias() += kw * diff_v;
    df.middleRows<3>(a3) += block;
    df.middleRows<3>(b3) -= block;
    for (int j = 0; j < 5; ++j) {
      const int c = paramColumn(b.type, kSpringParams[j]);
      if (c < 0) continue;
      for (int r = 0; r < 3; ++r) {
        df(a3 + r, c) += fa[r].v[6 + j];
        df(b3 + r, c) -= fa[r].v[6 + j];
      }
    }
  }
}

void MotionSensitivity::Impl::addFlexions() {
  using J = ceres::Jet<double, 21>;  // x (9), v (9), the 3 parameters
  const double* x = s.x_m[0].data();
  const double* v = s.v_mps[0].data();
  for (const Bond3& b : flexions) {
    const double* p = typeValues(b.type);
    J xj[9], vj[9], pj[3], fj[9];
    for (int q = 0; q < 3; ++q)
      for (int k = 0; k < 3; ++k) {
        xj[3 * q + k] = J(x[3 * b.p[q] + k], 3 * q + k);
        vj[3 * q + k] = J(v[3 * b.p[q] + k], 9 + 3 * q + k);
      }
    for (int j = 0; j < 3; ++j) pj[j] = J(p[kFlexionParams[j]], 18 + j);
    if (!flexionForces(xj, vj, pj, fj)) continue;
    for (int o = 0; o < 3; ++o) {
      const int o3 = 3 * b.p[o];
      for (int r = 0; r < 3; ++r) f[o3 + r] += fj[3 * o + r].a;
      for (int q = 0; q < 3; ++q) {
        Eigen::Matrix3d kx, kv;
        for (int r = 0; r < 3; ++r)
          for (int k = 0; k < 3; ++k) {
            kx(r, k) = fj[3 * o + r].v[3 * q + k];
            kv(r, k) = fj[3 * o + r].v[9 + 3 * q + k];
          }
        const int q3 = 3 * b.p[q];
        df.middleRows<3>(o3).noalias() += kx * sx.middleRows<3>(q3);
        df.middleRows<3>(o3).noalias() += kv * sv.middleRows<3>(q3);
      }
      for (int j = 0; j < 3; ++j) {
        const int c = paramColumn(b.type, kFlexionParams[j]);
        if (c >= 0)
          for (int r = 0; r < 3; ++r) df(o3 + r, c) += fj[3 * o + r].v[18 + j];
      }
    }
  }
}

void MotionSensitivity::Impl::addDragsAndFloors() {
  const double* x = s.x_m[0].data();
  const double* v = s.v_mps[0].data();
  for (const Bond3& b : drags) {  // F = -c v
    const int i3 = 3 * b.p[0];
    const double c = typeValues(b.type)[kViscosity];
    for (int r = 0; r < 3; ++r) f[i3 + r] -= c * v[i3 + r];
    df.middleRows<3>(i3) -= c * sv.middleRows<3>(i3);
    const int col = paramColumn(b.type, kViscosity);
    if (col >= 0)
      for (int r = 0; r < 3; ++r) df(i3 + r, col) -= v[i3 + r];
  }
  using J = ceres::Jet<double, 11>;  // x (3), v (3), the 5 parameters
  for (const Bond3& b : floors) {
    const double* p = typeValues(b.type);
    const int i3 = 3 * b.p[0];
    J xj[3], vj[3], pj[5], fj[3];
    for (int k = 0; k < 3; ++k) {
      xj[k] = J(x[i3 + k], k);
      vj[k] = J(v[i3 + k], 3 + k);
    }
    for (int j = 0; j < 5; ++j) pj[j] = J(p[kFloorParams[j]], 6 + j);
    if (!floorForce(xj, vj, pj, fj)) continue;
    Eigen::Matrix3d kx, kv;
    for (int r = 0; r < 3; ++r) {
      f[i3 + r] += fj[r].a;
      for (int k = 0; k < 3; ++k) {
        kx(r, k) = fj[r].v[k];
        kv(r, k) = fj[r].v[3 + k];
      }
    }
    block.noalias() = kx * sx.middleRows<3>(i3);
    block.noalias() += kv * sv.middleRows<3>(i3);
    df.middleRows<3>(i3) += block;
    for (int j = 0; j < 5; ++j) {
      const int c = paramColumn(b.type, kFloorParams[j]);
      if (c >= 0)
        for (int r = 0; r < 3; ++r) df(i3 + r, c) += fj[r].v[6 + j];
    }
  }
}

void MotionSensitivity::Impl::step(double dt_s) {
  f.assign(3 * static_cast<size_t>(n), 0.0);
  df.setZero();
  for (int i = 0; i < n; ++i)
    for (int r = 0; r < 3; ++r) {
      f[3 * i + r] = mass[i] * gravity[r];
      if (parameter_columns && gravity_column[r] >= 0) df(3 * i + r, gravity_column[r]) = mass[i];
    }
  addDragsAndFloors();
  addSprings();
  addFlexions();
  double* x = s.x_m[0].data();
  double* v = s.v_mps[0].data();
  for (int i : free_particles) {
    const int i3 = 3 * i;
    const double inv_m = 1.0 / mass[i];
    // The engine's arithmetic, in its order (Engine::integrate).
    for (int r = 0; r < 3; ++r) {
      v[i3 + r] += dt_s * (f[i3 + r] * inv_m);
      x[i3 + r] += dt_s * v[i3 + r];
    }
    sv.middleRows<3>(i3) += (dt_s * inv_m) * df.middleRows<3>(i3);
    sx.middleRows<3>(i3) += dt_s * sv.middleRows<3>(i3);
  }
}

MotionSensitivity::MotionSensitivity(const Model& model, std::vector<ParamRef> params) : impl_(new Impl) {
  const std::string unsupported = sensitivityUnsupportedReason(model);
  if (!unsupported.empty()) throw InputError("motion sensitivity: " + unsupported);
  Impl& m = *impl_;
  m.n = static_cast<int>(model.particles.size());
  m.substeps = std::max(1, model.substeps);
  for (int i = 0; i < m.n; ++i) {
    m.mass.push_back(model.particles[i].mass_kg);
    if (!model.particles[i].fixed) m.free_particles.push_back(i);
  }
  m.params = std::move(params);
  m.column_of.assign(model.bond_types.size() * kParamCount, -1);
  for (size_t c = 0; c < m.params.size(); ++c) {
    const ParamRef& ref = m.params[c];
    if (ref.bond_type < 0) m.gravity_column[ref.param] = static_cast<int>(c);
    else if (!ref.isNetwork()) m.column_of[static_cast<size_t>(ref.bond_type) * kParamCount + ref.param] = static_cast<int>(c);
  }
  for (const Bond& b : model.bonds) {
    Bond3 bond{{b.particles[0], b.particles[0], b.particles[0]}, b.type};
    for (size_t k = 1; k < b.particles.size() && k < 3; ++k) bond.p[k] = b.particles[k];
    switch (model.bond_types[b.type].kind) {
      case BondKind::kSpring: m.springs.push_back(bond); break;
      case BondKind::kFlexion: m.flexions.push_back(bond); break;
      case BondKind::kViscosity: m.drags.push_back(bond); break;
      case BondKind::kFloor: m.floors.push_back(bond); break;
      case BondKind::kMuscle: break;  // refused above
    }
  }
  setParameters(model);
}

MotionSensitivity::~MotionSensitivity() = default;
MotionSensitivity::MotionSensitivity(MotionSensitivity&&) noexcept = default;
MotionSensitivity& MotionSensitivity::operator=(MotionSensitivity&&) noexcept = default;

void MotionSensitivity::setParameters(const Model& model) {
  Impl& m = *impl_;
  m.values.assign(model.bond_types.size() * kParamCount, 0.0);
  for (size_t t = 0; t < model.bond_types.size(); ++t)
    for (int id = 0; id < kParamCount; ++id) {
      const Param& p = model.bond_types[t].param(static_cast<ParamId>(id));
      m.values[t * kParamCount + id] = p.present ? p.value : paramInfo(static_cast<ParamId>(id)).absent_value;
    }
  const Eigen::Vector3d g = model.gravity();
  for (int r = 0; r < 3; ++r) m.gravity[r] = g[r];
}

void MotionSensitivity::setParameterColumns(bool on) { impl_->parameter_columns = on; }

void MotionSensitivity::start(const State& s) {
  Impl& m = *impl_;
  if (static_cast<int>(s.x_m.size()) != m.n || static_cast<int>(s.v_mps.size()) != m.n)
    throw InputError("motion sensitivity: state size differs from the particle count");
  m.s = s;
  const int cols = m.columnCount(), c0 = stateColumn0();
  m.sx.setZero(3 * m.n, cols);
  m.sv.setZero(3 * m.n, cols);
  m.df.resize(3 * m.n, cols);
  for (size_t f = 0; f < m.free_particles.size(); ++f)
    for (int r = 0; r < 3; ++r) {
      m.sx(3 * m.free_particles[f] + r, c0 + 6 * static_cast<int>(f) + r) = 1.0;
      m.sv(3 * m.free_particles[f] + r, c0 + 6 * static_cast<int>(f) + 3 + r) = 1.0;
    }
}

void MotionSensitivity::stepFrame(double frame_period_s) {
  const double dt_s = frame_period_s / impl_->substeps;
  for (int k = 0; k < impl_->substeps; ++k) impl_->step(dt_s);
}

const State& MotionSensitivity::state() const { return impl_->s; }
const MotionSensitivity::Matrix& MotionSensitivity::dx() const { return impl_->sx; }
const MotionSensitivity::Matrix& MotionSensitivity::dv() const { return impl_->sv; }
int MotionSensitivity::columns() const { return impl_->columnCount(); }
int MotionSensitivity::stateColumn0() const {
  return impl_->parameter_columns ? static_cast<int>(impl_->params.size()) : 0;
}

}  // namespace mme

// Single-bond force laws: thin Eigen wrappers over the kernels the simulator and cost run, so the
// functions tested here are the arithmetic actually used in the inner loops; and every kind's
// law in the generic per-bond form (bondLaw), the one place a new kind's force law goes.
#include "motion_model_estimation/core/forces.h"

#include "engine.h"

namespace mme {

void addSpringForce(const SpringLaw& law, const Eigen::Vector3d& xa, const Eigen::Vector3d& xb,
                    const Eigen::Vector3d& va, const Eigen::Vector3d& vb, Eigen::Vector3d* fa,
                    Eigen::Vector3d* fb) {
  detail::springPair<true, true, true>(law, xa.data(), xb.data(), va.data(), vb.data(),
                                       fa->data(), fb->data());
}

void addFloorForce(const FloorLaw& law, const Eigen::Vector3d& x, const Eigen::Vector3d& v,
                   Eigen::Vector3d* f) {
  detail::floorForceRaw(law, x.data(), v.data(), f->data());
}

double springEnergy(const SpringLaw& law, const Eigen::Vector3d& xa, const Eigen::Vector3d& xb) {
  return detail::springEnergyRaw(law, xa.data(), xb.data());
}

double flexionAngle(const Eigen::Vector3d& xa, const Eigen::Vector3d& xb,
                    const Eigen::Vector3d& xc) {
  return detail::flexionAngleRaw(xa.data(), xb.data(), xc.data());
}

void addFlexionForce(const FlexionLaw& law, const Eigen::Vector3d& xa, const Eigen::Vector3d& xb,
                     const Eigen::Vector3d& xc, const Eigen::Vector3d& va,
                     const Eigen::Vector3d& vb, const Eigen::Vector3d& vc, Eigen::Vector3d* fa,
                     Eigen::Vector3d* fb, Eigen::Vector3d* fc) {
  detail::flexionForceRaw(law, xa.data(), xb.data(), xc.data(), va.data(), vb.data(), vc.data(),
                          fa->data(), fb->data(), fc->data());
}

double flexionEnergy(const FlexionLaw& law, const Eigen::Vector3d& xa, const Eigen::Vector3d& xb,
                     const Eigen::Vector3d& xc) {
  return detail::flexionEnergyRaw(law, xa.data(), xb.data(), xc.data());
}

namespace {

// The generic forms (BondLaw) of the built-in kinds: the same kernels as their fast paths.

void springLawForce(const double* p, const double* const* x, const double* const* v,
                    double* const* f) {
  detail::springPair<true, true, true>(detail::springLawOf(p), x[0], x[1], v[0], v[1], f[0], f[1]);
}
double springLawEnergy(const double* p, const double* const* x) {
  return detail::springEnergyRaw(detail::springLawOf(p), x[0], x[1]);
}

void flexionLawForce(const double* p, const double* const* x, const double* const* v,
                     double* const* f) {
  detail::flexionForceRaw(detail::flexionLawOf(p), x[0], x[1], x[2], v[0], v[1], v[2], f[0], f[1],
                          f[2]);
}
double flexionLawEnergy(const double* p, const double* const* x) {
  return detail::flexionEnergyRaw(detail::flexionLawOf(p), x[0], x[1], x[2]);
}

void viscosityLawForce(const double* p, const double* const* /*x*/, const double* const* v,
                       double* const* f) {
  const double c = p[kViscosity];
  for (int k = 0; k < 3; ++k) f[0][k] -= c * v[0][k];
}

void floorLawForce(const double* p, const double* const* x, const double* const* v,
                   double* const* f) {
  detail::floorForceRaw(detail::floorLawOf(p), x[0], v[0], f[0]);
}

}  // namespace

const BondLaw& bondLaw(BondKind kind) {
  static const BondLaw kSpringLaw{&springLawForce, &springLawEnergy};
  static const BondLaw kFlexionLaw{&flexionLawForce, &flexionLawEnergy};
  static const BondLaw kViscosityLaw{&viscosityLawForce, nullptr};
  static const BondLaw kFloorLaw{&floorLawForce, nullptr};  // the energy counts no contact
  static const BondLaw kNoLaw{nullptr, nullptr};
  // No default: a new kind without a line here does not compile (-Werror=switch).
  switch (kind) {
    case BondKind::kSpring: return kSpringLaw;
    case BondKind::kFlexion: return kFlexionLaw;
    case BondKind::kViscosity: return kViscosityLaw;
    case BondKind::kMuscle: return kNoLaw;  // its network reads other bonds: the muscle path
    case BondKind::kFloor: return kFloorLaw;
  }
  return kNoLaw;  // not reached: every enumerator is listed
}

}  // namespace mme

// Single-bond force laws: thin Eigen wrappers over the kernels the simulator and cost run, so the
// functions tested here are the arithmetic actually used in the inner loops.
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

}  // namespace mme

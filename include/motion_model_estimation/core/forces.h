// Force laws of the bond catalogue (SPEC section 3) and their energies, for one bond at a time.
#pragma once

#include <Eigen/Core>

#include "motion_model_estimation/core/bond_kind.h"

namespace mme {

/// Parameters of one spring type in the form the inner loop wants.
struct SpringLaw {
  double stiffness = 0;      ///< k [N/m]
  double rest_length = 0;    ///< L [m]
  double damping = 0;        ///< c [N s/m]
  double stiffness_nl = 0;   ///< k_nl [N/m^3]
  double damping_nl = 0;     ///< c_nl [N s^2/m^2]
  double min_distance = 0;   ///< [m] (0 = no lower condition)
  double max_distance = 1e300;  ///< [m] (huge = no upper condition)
};

struct FlexionLaw {
  double stiffness = 0;   ///< [N m/rad]
  double rest_angle = 0;  ///< [rad]
  double damping = 0;     ///< [N m s/rad]
};

/// Ground contact of one particle with the floor plane z = height (world z up).
struct FloorLaw {
  double stiffness = 0;  ///< k [N/m] on the penetration
  double damping = 0;    ///< c [N s/m] on the normal speed
  double friction = 0;   ///< mu [N s/m]: viscous, along the floor
  double height = 0;     ///< [m]
  /// d [m]: damping and friction grow as min(1, p / d) over the first d of penetration, so the
  /// force is continuous at touch-down; 0: full from the first contact
  double contact_depth = 0;
};

/// Adds the floor's force on a particle at x with velocity v: with penetration p = height - z > 0
/// and r = min(1, p / d) (r = 1 when d = 0), F_z += max(0, k p - r c v_z) (it pushes, never
/// pulls), F_x += -r mu v_x, F_y += -r mu v_y; nothing when p <= 0.
void addFloorForce(const FloorLaw& law, const Eigen::Vector3d& x, const Eigen::Vector3d& v,
                   Eigen::Vector3d* f);

/// Adds the spring force between a and b: f = k e + k_nl e^3 + c s + c_nl s|s| along u = (xb-xa)/l;
/// F_a += f u, F_b -= f u; nothing outside [min_distance, max_distance] or when l == 0.
void addSpringForce(const SpringLaw& law, const Eigen::Vector3d& xa, const Eigen::Vector3d& xb,
                    const Eigen::Vector3d& va, const Eigen::Vector3d& vb, Eigen::Vector3d* fa,
                    Eigen::Vector3d* fb);
/// Elastic energy 1/2 k e^2 + 1/4 k_nl e^4 (0 when inactive) [J].
double springEnergy(const SpringLaw& law, const Eigen::Vector3d& xa, const Eigen::Vector3d& xb);

/// Angle at vertex b between (a-b) and (c-b) [rad], in [0, pi].
double flexionAngle(const Eigen::Vector3d& xa, const Eigen::Vector3d& xb, const Eigen::Vector3d& xc);
/// Adds flexion forces: -grad of 1/2 k (theta - theta0)^2 plus damping -c dtheta/dt grad(theta).
/// Skipped when the three points are (nearly) collinear-degenerate.
void addFlexionForce(const FlexionLaw& law, const Eigen::Vector3d& xa, const Eigen::Vector3d& xb,
                     const Eigen::Vector3d& xc, const Eigen::Vector3d& va, const Eigen::Vector3d& vb,
                     const Eigen::Vector3d& vc, Eigen::Vector3d* fa, Eigen::Vector3d* fb,
                     Eigen::Vector3d* fc);
double flexionEnergy(const FlexionLaw& law, const Eigen::Vector3d& xa, const Eigen::Vector3d& xb,
                     const Eigen::Vector3d& xc);

/// One bond's law in the form the simulator's generic per-bond path calls, so that a kind needs
/// no code in the simulator. `params` holds the bond type's value of every ParamId, indexed by
/// it (an absent parameter reads ParamInfo::absent_value); x[p], v[p] and f[p] are the
/// position [m], velocity [m/s] and force accumulator [N] (3 doubles each) of the p-th particle
/// the bond joins, p < bondKindInfo(kind).arity.
struct BondLaw {
  /// Adds the bond's forces to f.
  void (*force)(const double* params, const double* const* x, const double* const* v,
                double* const* f);
  /// Its potential energy [J]; nullptr when it stores none the total energy counts (a drag, a
  /// contact).
  double (*energy)(const double* params, const double* const* x);
};

/// The law of a kind. Both nullptr for a kind whose force needs more than its own particles and
/// parameters (a muscle: its network reads other bonds; the simulator has its own path for it).
const BondLaw& bondLaw(BondKind kind);

}  // namespace mme

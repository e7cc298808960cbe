// The stiffest mode of a model: how fast its fastest vibration is, which decides how many
// integration steps a frame needs (semi-implicit Euler drifts as (omega h)^2 and is unstable
// beyond omega h = 2).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"

namespace mme {

/// Largest angular frequency [rad/s] of the linearised springs at positions `x_m` (one per
/// particle): the square root of the largest eigenvalue of M^-1/2 K M^-1/2, K the stiffness of
/// every installed spring (k + 3 k_nl e^2 along the bond, plus the tension's transverse part);
/// fixed particles do not move. Flexion and interaction bonds are not counted. Power iteration.
double stiffestModeRadPerS(const Model& model, const std::vector<Eigen::Vector3d>& x_m);

}  // namespace mme

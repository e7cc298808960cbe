// The model a sensor-muscle fit gives: the passive model with the sensor bonds and a muscle type
// and bond per fitted muscle, every parameter fixed.
#pragma once

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"
#include "group_selection.h"
#include "muscle_equations.h"

namespace mme::sensor_muscles {

/// The passive model with sensors and muscles carrying theta (scaled columns), every gain
/// `margin` x its muscle's largest linear activation over frames [0, t_end), every muscle with
/// the activation time constant `activation_time_s` [s] (0: none); the muscles and sensors
/// `selection` drops (may be null) are left out. Throws InputError when the model does not
/// validate.
Model buildMuscleModel(const MuscleEquations& equations, const Eigen::VectorXd& theta, double margin, int t_end,
                       double activation_time_s = 0.0, const GroupSelection* selection = nullptr);

}  // namespace mme::sensor_muscles

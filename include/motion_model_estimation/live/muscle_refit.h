// The live node's cheap refit of sensor muscles: with the sensors, the muscles' own stiffness and
// damping and the passive model's forces known, Newton's law on the window's frames is linear in
// every muscle's activation (gain x network, its linearised tanh), so a refit on a new window is
// one sparse ridge-regularised least-squares solve (each particle's rows touch only its own
// muscles' columns). No ROS here; the muscle job runs it on the node's sliding window.
#pragma once

#include <string>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

struct MuscleRefitResult {
  bool ok = false;       ///< false: nothing to refit or no equation (`why` says)
  std::string why;
  Model model;           ///< the input model with its muscles' networks and gains refitted
  int muscle_types = 0;  ///< muscle types refitted (linear network, every network value fixed)
  int unknowns = 0;      ///< their linear unknowns (2 inputs x sensors + 1 per type)
  int rows = 0;          ///< equations (3 per free particle and usable frame)
  double residual_rms_m = 0.0;  ///< the fit's one-step residual a h^2 per coordinate [m]
};

/// Refits the activation of every muscle type with a linear network (hidden 0) and no free
/// network value on `window` (the model's particles as markers; fixed particles without a
/// marker stay where the model holds them). A frame gives equations when every free particle
/// is seen in it and in the frames before and after. `relative_ridge`: the ridge relative to
/// the mean diagonal of the normal matrix in columns scaled to unit RMS (as the sensor muscles'
/// own fit); solved by a sparse factorisation up to `direct_max_unknowns`, above by at most 200
/// conjugate-gradient iterations started at the model's current values (an update, not a new
/// fit: a large body's factor fills in). `gain_margin`: each gain becomes this many times its muscle's largest linear
/// activation over the window (tanh then stays near linear where the data went). Never throws
/// on data it cannot use: ok false and why.
MuscleRefitResult refitMuscleActivations(const Model& model, const Trajectory& window,
                                         double relative_ridge, double gain_margin = 10.0,
                                         int direct_max_unknowns = 1500);

/// Muscle types refitMuscleActivations would refit in `model`.
int refittableMuscleTypes(const Model& model);

}  // namespace mme

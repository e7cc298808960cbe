// The sensor muscles' anchors: three fixed particles far along x, y and z (docs/muscles.md,
// *Anchors*), and whether their muscles get a stiffness of their own.
#pragma once

#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"

namespace mme::sensor_muscles {

/// Adds the anchors to a copy of the model and of the data: three fixed particles at the free
/// particles' mean position over the data plus `extents` x their bounding-box diagonal along x,
/// y and z, seen in every frame. Returns the flags per particle (1: an anchor).
std::vector<char> addAnchors(Model* model, Trajectory* data, double extents);

/// `o` with AnchorStiffness::kAuto decided: held at 0 (kNone) when the passive model has no
/// fixed particle and `body_travel` (bodyTravel) is at least o.travel_body_sizes, fitted otherwise. Says which.
SensorMuscleOptions resolveAnchorStiffness(const Model& passive, double body_travel,
                                           const SensorMuscleOptions& o);

}  // namespace mme::sensor_muscles

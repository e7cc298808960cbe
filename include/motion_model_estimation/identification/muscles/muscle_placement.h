// Muscles on a passive model: the paper's section 4.4 experiment, "the same bonds,
// driven by a neural controller", for a model whose passive structure is known (written by hand
// or chosen by structure selection).
//
// Every spring type becomes a muscle type. It keeps its spring part (stiffness, rest length,
// damping: values, freedom and bounds) and gains a free output gain and a free network whose
// parameters all start at 0, so the activation starts at 0 and the model starts as the passive
// one: a warm start from the passive fit can only lower the cost. Each of its bonds reads the
// `inputs` bonds nearest to it: the bonds sharing one of its ends first, then the others by the
// distance between the bonds' midpoints (each particle where the data first see it, or at the
// model's position), ties by bond index. Bonds a muscle reads get a name ("bond_<index>") when
// they have none.
// Types that cannot be muscles stay as they are: conditional or non-linear springs (a muscle has
// no threshold or cubic term), interaction types, and every other kind.
#pragma once

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

struct MusclePlacement {
  int inputs = 2;        ///< input bonds each muscle reads (fewer when the model has fewer)
  int hidden = 0;        ///< hidden units (0: the network is linear in its inputs)
  /// Initial output gain [N]; 0 = the mean weight (m |g|, |g| at least 9.81 m/s^2) of the
  /// type's bonds' end particles.
  double gain_n = 0.0;
};

/// The model with muscles; `data` (may be null) places the particles for ranking the inputs.
/// Throws InputError when the placement's numbers are out of range.
Model addMuscles(const Model& passive, const Trajectory* data, const MusclePlacement& placement = {});

/// The passive model under `model`: every muscle type a spring with the muscle's spring part
/// (stiffness, rest length, damping), its gain, network and inputs dropped.
Model removeMuscles(const Model& model);

/// Types of `model` that are muscles.
int muscleTypeCount(const Model& model);

}  // namespace mme

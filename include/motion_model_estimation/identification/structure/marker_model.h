// A starting model for a capture that comes without one: its markers as particles (and, for
// benchmarks, springs between its most rigid marker pairs). What structure selection starts from
// on real recordings (identify --select-structure without --model, bench_paper).
#pragma once

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// One particle per marker of `data` (its name, 1 kg, not fixed, in marker order), a free
/// gravity (its direction is the capture's, unknown), the data's frame rate, and
/// `rigid_pair_bonds` damped springs, one type each (stiffness, rest length and damping free,
/// no values), between the marker pairs whose distance's std / mean over the frames is smallest
/// (pairs seen together in fewer than 80 % of the frames are not considered). Unit masses: the
/// motion fixes only force per mass, so identified stiffnesses [N/m] and dampings [N s/m] are
/// per kilogram of marker. Throws InputError when `data` has no marker or no frame.
Model markerModel(const Trajectory& data, int rigid_pair_bonds = 0);

}  // namespace mme

// Random 3-D mass-spring objects for tests and benchmarks of identification beyond the paper's
// fixed scenes (e.g. generations to converge against the number of bond types).
#pragma once

#include <cstdint>

#include "motion_model_estimation/core/model.h"

namespace mme {

struct RandomObjectSpec {
  int particles = 18;
  int bond_types = 12;         ///< linear spring types (stiffness + rest_length free each)
  int bonds = 40;              ///< >= particles - 1 (a spanning tree keeps it connected)
  double frame_rate_hz = 120.0;
  double size_m = 0.3;         ///< edge of the cube the particles start in [m]
  uint64_t seed = 1;
};

/// A connected floating object (no gravity, no fixed particle) whose bonds use every type at
/// least once, with rest lengths that differ from the initial distances so it vibrates, and
/// stiffnesses low enough for the explicit integration at the frame rate (omega h < 0.5).
/// Free parameters carry their true values; bounds bracket them by 10x (stiffness) and 2x
/// (rest length). Throws InputError on an impossible spec.
Model makeRandomObject(const RandomObjectSpec& spec);

}  // namespace mme

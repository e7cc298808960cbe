// The thresholds of conditional bonds (min_distance, max_distance) have no useful slope: with one
// step per frame the cost is flat between the observed lengths where a condition switches
// (Gene::breakpoints) and jumps at them. Gradient refinements leave them alone; this search moves
// them one at a time over those flat intervals, the other genes held, and ends each at the middle
// of the best interval it found (any point of it fits the data equally well).
#pragma once

#include "motion_model_estimation/core/cost.h"
#include "motion_model_estimation/identification/parameter_space.h"
#include "motion_model_estimation/identification/refiner.h"

namespace mme {

/// Moves every threshold gene (not smooth, with breakpoints; settings.movable, when given,
/// narrows the set further) by a discrete pattern search over the index of its flat intervals:
/// steps doubling while the cost falls, then halving down to the neighbouring interval. Stops at
/// settings.max_evaluations or the deadline. Status kConverged when no threshold moved the cost
/// down, kStalled otherwise (more rounds may pay).
RefineResult searchThresholds(const Cost& cost, const ParameterSpace& space,
                              const RefineStart& start, const RefineSettings& settings);

}  // namespace mme

// The thresholds of conditional bonds (min_distance, max_distance) have no useful slope: with one
// step per frame the cost is flat between the observed lengths where a condition switches
// (Gene::breakpoints) and jumps at them. Gradient refinements leave them alone; this search moves
// them one at a time over those flat intervals, the other genes held, and ends each at the middle
// of the best interval it found (any point of it fits the data equally well).
#pragma once

#include "motion_model_estimation/core/cost.h"
#include "motion_model_estimation/identification/search/parameter_space.h"
#include "motion_model_estimation/identification/search/refiner.h"

namespace mme {

/// Moves every threshold gene (not smooth, with breakpoints; settings.movable, when given,
/// narrows the set further) by a discrete pattern search over the index of its flat intervals:
/// steps doubling while the cost falls, then halving down to the neighbouring interval. Stops at
/// settings.max_evaluations or the deadline. Status kConverged when no threshold moved the cost
/// down, kStalled otherwise (more rounds may pay).
RefineResult searchThresholds(const Cost& cost, const ParameterSpace& space,
                              const RefineStart& start, const RefineSettings& settings);

/// Whether some gene of the space is a threshold with breakpoints (searchThresholds applies).
bool hasThresholds(const ParameterSpace& space);

/// One refinement as the engine runs it: `refiner` on settings.movable (the smooth genes), then,
/// when the space has thresholds, the threshold search and `refiner` again in turn while the cost
/// falls, at most `rounds` times, all inside settings' evaluation budget and deadline. The status
/// is the first smooth refinement's.
RefineResult refineAlternating(const Refiner& refiner, const Cost& cost, const ParameterSpace& space,
                               const RefineStart& start, const RefineSettings& settings,
                               ThreadPool* pool, int rounds = 3);

}  // namespace mme

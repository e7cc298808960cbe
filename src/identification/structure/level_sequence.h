// The order of levels in structure selection. The cumulative levels (springs; + dampers;
// + flexion; + viscosity) are planned up front; the non-linear and conditional levels depend on
// which earlier level judged best, so they are planned as the sequence runs. This unit runs
// the levels in order, recognises a level that kept nothing new as an earlier one's structure,
// and stops the sequence when the time limit is spent.
#pragma once

#include <array>
#include <set>
#include <utility>
#include <vector>

#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "level_fit.h"
#include "selection_context.h"

namespace mme {
namespace structure {

/// The cumulative levels, in rising complexity, each holding every candidate component of the
/// ones before: springs; + dampers; + flexion (when `with_flexion`: some near-collinear triple);
/// + viscosity, as the options allow.
std::vector<Level> cumulativeLevels(const StructureOptions& options, bool with_flexion);

/// Fits, refits and judges `levels` in order, adding the non-linear level after the cumulative
/// ones and conditional levels where the residual asks for them; `all_candidates` are the
/// candidate pairs (screening adds to them). Returns every candidate tried, in order (at least
/// the first level's: the time limit never stops it).
std::vector<StructureCandidate> runLevels(const SelectionContext& ctx, std::vector<Level> levels,
                                          const std::vector<std::array<int, 3>>& triples,
                                          std::set<std::pair<int, int>> all_candidates);

}  // namespace structure
}  // namespace mme

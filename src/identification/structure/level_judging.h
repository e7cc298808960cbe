// Judging levels by held-out prediction. The equation error that chooses each level's bonds
// is fitted on the same frames it is scored on, so it cannot say which level generalises; the
// levels are instead refitted by the full identification and compared on frames never fitted
// (the end of the window), with the model-free guesses as the bar to clear.
#pragma once

#include <vector>

#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "selection_context.h"

namespace mme {
namespace structure {

/// The model-free guesses (constant velocity, constant acceleration, gravity only) on the
/// held-out frames into `result->guess_rms_m` (NaN when no start there has every particle
/// placed: then a note says why).
void judgeModelFreeGuesses(const Model& model, const HeldOutSplit& split, StructureResult* result);

/// A level's typed model refitted by the full identification on the fitted frames (rest
/// lengths of the non-linear level free again: the seeds are Gauss-Newton steps of the
/// linearised equation error from the values; the conditional level's thresholds free for the
/// threshold search) and judged on the held-out frames. Not refitted when the options say so,
/// when nothing is free, or when the time limit is spent.
void refitAndJudge(const SelectionContext& ctx, StructureCandidate* cand, bool nonlinear, bool conditional);

/// The held-out 10-frame error decides; within 2 % of the best, the criterion (then fewer
/// parameters) does. -1 when `candidates` is empty.
int bestCandidate(const std::vector<StructureCandidate>& candidates);

}  // namespace structure
}  // namespace mme

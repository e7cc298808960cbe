// Screening by the one-step residual: what a fitted model still gets wrong, read per pair of
// particles. Geometry alone misses long bonds and cannot see a bond that switches off (a
// cable, a contact); the residual of a fit can, so after a level is solved this unit names the
// pairs a spring would explain and the springs a threshold would improve, and the levels
// (level_fit.h, level_sequence.h) add them as candidates.
#pragma once

#include <set>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {
namespace structure {

/// Per frame, the weighted one-step residual (m a - F) h^2 / m of every free particle seen at
/// t-1, t and t+1 under `model` (every value set; raw differences); NaN elsewhere, and frames
/// 0 and T-1 empty.
std::vector<std::vector<Eigen::Vector3d>> oneStepResiduals(const Model& model, const Trajectory& data);

/// Pairs outside `have` that the residual of `model` (every value set) asks for: for each pair,
/// the part of the one-step residual a spring between them (tension k l - k L along the pair)
/// would explain, c^T G^-1 c over the frames where both are seen. Returns the pairs explaining
/// more than 20 ln(N) times the residual's mean square (a pair of parameters' BIC price with a
/// wide margin, so that noise adds nothing), the most first, at most `most`; none when the
/// residual's RMS is below `floor_rms_m` (nothing is missing).
std::vector<std::pair<int, int>> missingPairs(const Model& model, const Trajectory& data,
                                              const std::set<std::pair<int, int>>& have,
                                              double floor_rms_m, int most);

/// A kept spring made conditional: active only when its length is at least (`lower`) or at
/// most the threshold.
struct ConditionalChoice {
  int type = -1;
  bool lower = true;
  double threshold_m = 0.0;
  double gain_m2 = 0.0;  ///< the residual's fall when the bond is off beyond the threshold
};

/// For each candidate spring of `model` (types from `first_candidate_type`, one bond each, every
/// value set), the threshold whose switching the one-step residual asks for most: the bond's
/// force removed on the frames where it is shorter (or longer) than the threshold, the residual's
/// fall is a prefix (suffix) sum over the frames sorted by length. Returns those falling by more
/// than `min_gain_m2`, the most first.
std::vector<ConditionalChoice> conditionalCandidates(const Model& model, const Trajectory& data,
                                                     int first_candidate_type, double min_gain_m2);

}  // namespace structure
}  // namespace mme

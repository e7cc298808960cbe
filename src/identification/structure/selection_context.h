// What every step of one structure selection reads: its inputs, settings, time limit and where
// it reports. The selection is a sequence of steps spread over several units (candidates,
// elimination, typing, levels, judging); passing them one context instead of a dozen
// arguments keeps each step's signature about what it computes.
#pragma once

#include <string>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "deadline.h"

namespace mme {
namespace structure {

/// Solves per level (non-physical drops, screening rounds), and rounds of the typed fit.
constexpr int kMaxPasses = 12;

struct SelectionContext {
  SelectionContext(const Model& model_in, const StructureOptions& options_in,
                   const HeldOutSplit& split_in, const Deadline& deadline_in, StructureResult* result_in)
      : model(model_in), options(options_in), split(split_in), fit(split_in.fit),
        deadline(deadline_in), result(result_in) {}

  const Model& model;               ///< the particles and given bonds, the frame rate set
  const StructureOptions& options;
  const HeldOutSplit& split;        ///< fitted and held-out frames
  const Trajectory& fit;            ///< split.fit: every fit uses these frames only
  const Deadline& deadline;
  StructureResult* result;          ///< notes, candidate count, stopped_by_time
  EquationErrorOptions ee;          ///< the equation error's kinematics (raw or smoothed)
  int first_candidate_type = 0;     ///< the given model's types come first

  /// A progress line (when the caller asked for them).
  void say(const std::string& line) const {
    if (options.progress) options.progress(line);
  }
};

}  // namespace structure
}  // namespace mme

// The `identification:` block a written model carries (method, cost, frames, the 1-sigma and
// the flag of every parameter, notes), built in one place for the offline pipeline and the live
// node, so that a file says the same things whichever wrote it.
#pragma once

#include <string>
#include <vector>

#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/online/online_estimator.h"
#include "motion_model_estimation/io/model_yaml.h"

namespace mme {

/// The method's name in the file: "es" or "es+output_error" offline, "es-online" or
/// "es-online+output_error" live.
std::string methodName(Estimator estimator, bool online);

/// The offline identification's block, with `notes`.
IdentificationInfo identificationInfo(const IdentifyResult& result,
                                      const std::vector<std::string>& notes);
/// The live estimate's block (no notes, no wall time).
IdentificationInfo identificationInfo(const Estimate& estimate);

}  // namespace mme

#include "motion_model_estimation/identification/estimators/estimator_kind.h"

namespace mme {

const char* estimatorName(Estimator estimator) {
  switch (estimator) {
    case Estimator::kShortTerm: return "short_term";
    case Estimator::kOutputError: return "output_error";
  }
  return "?";
}

const char* parameterFlagName(ParameterFlag flag) {
  switch (flag) {
    case ParameterFlag::kNone: return "";
    case ParameterFlag::kAtLowerBound: return "at_lower_bound";
    case ParameterFlag::kAtUpperBound: return "at_upper_bound";
    case ParameterFlag::kUnidentifiable: return "unidentifiable";
  }
  return "?";
}

}  // namespace mme

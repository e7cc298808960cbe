// What an identification's answer is and how far to trust each parameter, as enums the core
// passes around: which estimator's cost gave the final values, and what the data left undecided
// about a parameter. The names are the words the command line, the model file and the ROS
// messages use; only those edges turn the enums into text.
#pragma once

namespace mme {

/// The cost whose minimum is the answer.
enum class Estimator {
  kShortTerm,    ///< the paper's one-step prediction (exact on noiseless data, biased by noise)
  kOutputError,  ///< multiple shooting over segments (output_error.h)
};
/// "short_term" | "output_error".
const char* estimatorName(Estimator estimator);

/// What the data left undecided about a parameter.
enum class ParameterFlag {
  kNone,
  kAtLowerBound,    ///< within 1 % of its lower search bound (the answer may lie beyond)
  kAtUpperBound,    ///< within 1 % of its upper search bound
  kUnidentifiable,  ///< the data do not determine it (output error: null space, or std > value)
};
/// "" | "at_lower_bound" | "at_upper_bound" | "unidentifiable".
const char* parameterFlagName(ParameterFlag flag);

}  // namespace mme

#include "motion_model_estimation/pipeline/result_metadata.h"

#include <cmath>

namespace mme {

namespace {

/// Each parameter's 1-sigma (where finite) and flag (where set), in the parameters' order.
void addParameters(const std::vector<std::string>& names, const std::vector<double>& std_devs,
                   const std::vector<ParameterFlag>& flags, IdentificationInfo* info) {
  for (size_t k = 0; k < names.size(); ++k) {
    if (k < std_devs.size() && std::isfinite(std_devs[k])) {
      info->std_names.push_back(names[k]);
      info->std_values.push_back(std_devs[k]);
    }
    if (k < flags.size() && flags[k] != ParameterFlag::kNone)
      info->flags.emplace_back(names[k], parameterFlagName(flags[k]));
  }
}

}  // namespace

std::string methodName(Estimator estimator, bool online) {
  std::string name = online ? "es-online" : "es";
  if (estimator == Estimator::kOutputError) name += "+output_error";
  return name;
}

IdentificationInfo identificationInfo(const IdentifyResult& result,
                                      const std::vector<std::string>& notes) {
  IdentificationInfo info;
  info.method = methodName(result.estimator, false);
  info.global_cost = result.global_cost;
  info.frames = result.frames;
  info.generations = result.generations;
  info.wall_time_s = result.wall_time_s;
  std::vector<std::string> names;
  for (const ParamRef& ref : result.parameters) names.push_back(ref.name);
  addParameters(names, result.std_devs, result.flags, &info);
  info.notes = notes;
  return info;
}

IdentificationInfo identificationInfo(const Estimate& estimate) {
  IdentificationInfo info;
  info.method = methodName(estimate.estimator, true);
  info.global_cost = estimate.global_cost;
  info.frames = static_cast<int>(estimate.window_frames);
  info.generations = static_cast<int>(estimate.generation);
  addParameters(estimate.parameter_names, estimate.std_devs, estimate.parameter_flags, &info);
  return info;
}

}  // namespace mme

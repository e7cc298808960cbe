#include "motion_model_estimation/identification/online/migrants.h"

#include <algorithm>
#include <cmath>

namespace mme {

std::string parameterMismatch(const std::vector<std::string>& ours,
                              const std::vector<std::string>& theirs) {
  const size_t common = std::min(ours.size(), theirs.size());
  for (size_t k = 0; k < common; ++k) {
    if (ours[k] != theirs[k])
      return "parameter " + std::to_string(k) + " is '" + theirs[k] + "' in the migrants but '" +
             ours[k] + "' here";
  }
  if (theirs.size() < ours.size())
    return "the migrants have " + std::to_string(theirs.size()) + " parameters, this island " +
           std::to_string(ours.size()) + ": '" + ours[common] + "' is missing";
  if (theirs.size() > ours.size())
    return "the migrants have " + std::to_string(theirs.size()) + " parameters, this island " +
           std::to_string(ours.size()) + ": '" + theirs[common] + "' is not searched here";
  return "";
}

std::string malformedBatch(const MigrantBatch& batch) {
  const size_t n = batch.parameter_names.size();
  for (size_t i = 0; i < batch.individuals.size(); ++i) {
    const Individual& ind = batch.individuals[i];
    if (ind.genes.size() != n || ind.mutability.size() != n)
      return "migrant " + std::to_string(i) + " has " + std::to_string(ind.genes.size()) +
             " genes and " + std::to_string(ind.mutability.size()) + " mutabilities for " +
             std::to_string(n) + " parameters";
    for (double g : ind.genes)
      if (!std::isfinite(g)) return "migrant " + std::to_string(i) + " has a non-finite gene";
  }
  return "";
}

}  // namespace mme

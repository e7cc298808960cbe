#include "motion_model_estimation/identification/online/migrants.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

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

std::string unflattenMigrants(uint64_t count, const std::vector<double>& genes,
                              const std::vector<double>& mutabilities, const std::vector<double>& costs,
                              MigrantBatch* batch) {
  batch->individuals.clear();
  const uint64_t n = batch->parameter_names.size();
  // count * n compared by division: a wild count must not wrap around.
  const bool rows_match = n == 0 ? genes.empty() && mutabilities.empty()
                                 : genes.size() % n == 0 && genes.size() / n == count &&
                                       mutabilities.size() == genes.size();
  if (costs.size() != count || !rows_match)
    return "migrant_count " + std::to_string(count) + " and " + std::to_string(n) +
           " parameter names need " + (n == 0 || count <= UINT64_MAX / n ? std::to_string(count * n) : "too many") +
           " genes and mutabilities and " + std::to_string(count) + " costs; the message has " +
           std::to_string(genes.size()) + ", " + std::to_string(mutabilities.size()) + " and " +
           std::to_string(costs.size());
  batch->individuals.resize(count);
  for (size_t i = 0; i < count; ++i) {
    Individual& ind = batch->individuals[i];
    ind.genes.assign(genes.begin() + i * n, genes.begin() + (i + 1) * n);
    ind.mutability.assign(mutabilities.begin() + i * n, mutabilities.begin() + (i + 1) * n);
    ind.cost = costs[i];
  }
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

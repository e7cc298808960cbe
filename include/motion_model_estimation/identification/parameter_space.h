// The search space of identification: one gene per free parameter, log scale for positive
// physical parameters, bounds in one place, and the paper's initialisation rules.
#pragma once

#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/random.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// One free parameter as the search sees it.
struct Gene {
  ParamRef ref;               ///< where it lives in the model
  bool log_scale = true;      ///< gene = ln(value) (positive physical parameters)
  double lower = 0.0;         ///< bound in search space
  double upper = 0.0;         ///< bound in search space
  double init_center = 0.0;   ///< centre of the initial distribution (search space)
  double init_spread = 1.0;   ///< std of the initial distribution (search space)
  bool has_initial = false;   ///< the model file gave a value (initial guess)
};

/// Maps genes <-> physical parameter values. Built from a model (free flags, bounds, initial
/// guesses) and the observed data (average bond lengths for rest-length-like parameters).
class ParameterSpace {
 public:
  /// `trajectory` has the model's particles as markers (see remapMarkers).
  ParameterSpace(const Model& model, const Trajectory& trajectory);

  size_t size() const { return genes_.size(); }
  const Gene& gene(size_t k) const { return genes_[k]; }
  const std::vector<Gene>& genes() const { return genes_; }
  /// The free parameters in CostFunction order.
  std::vector<ParamRef> refs() const;

  double toPhysical(size_t k, double gene_value) const;
  double toSearch(size_t k, double physical_value) const;
  std::vector<double> toPhysical(const std::vector<double>& genes) const;
  /// Clamps a gene into its bounds by reflection (keeps the search distribution symmetric).
  double reflect(size_t k, double gene_value) const;
  /// Draws gene k from the paper's initialisation (rest lengths around the average observed
  /// distance of the bonds of that type, others log-Gaussian), inside the bounds.
  double sampleInitial(size_t k, Random& random) const;

  /// Genes of each bond type (index = bond type; empty for types without free parameters).
  const std::vector<std::vector<int>>& genesOfType() const { return genes_of_type_; }
  /// Particles at an extremity of a bond of each type (for interactions: all particles of the
  /// interacting groups): the "sites" whose local costs judge that type's parameters.
  const std::vector<std::vector<int>>& sitesOfType() const { return sites_of_type_; }
  /// Bond types that own at least one gene, ascending.
  const std::vector<int>& typesWithGenes() const { return types_with_genes_; }

 private:
  std::vector<Gene> genes_;
  std::vector<std::vector<int>> genes_of_type_;
  std::vector<std::vector<int>> sites_of_type_;
  std::vector<int> types_with_genes_;
};

}  // namespace mme

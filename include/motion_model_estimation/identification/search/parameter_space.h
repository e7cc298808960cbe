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
  /// The bound came from the model file (a user's constraint: reported when reached, never
  /// widened); otherwise it is a default that identification may widen.
  bool user_lower = false;
  bool user_upper = false;
  /// The cost has a useful slope along it. Not so for the thresholds of conditional bonds
  /// (min_distance, max_distance): the cost is flat between the switching events, so gradient
  /// refinements leave them to the evolution strategy.
  bool smooth = true;
  /// Thresholds only: the observed lengths where the condition switches (the bond lengths of
  /// its type, or the pair distances of its interaction's groups, in the data), in search space,
  /// ascending, within the bounds, at most kMaxBreakpoints (quantiles when there are more). The
  /// cost is flat between two of them when a frame is one step.
  std::vector<double> breakpoints;
  /// max_elongation (Provot's tau) is searched as the clamp length ln((1 + tau) L), with L the
  /// same type's rest length: the clamp acts where that length meets the longest observed bond,
  /// a point that does not move when L does. Physical tau = exp(gene) / L - 1.
  bool clamp_length = false;
  int rest_gene = -1;               ///< gene of the type's rest length (-1: L is fixed)
  double fixed_rest_length_m = 0.0; ///< L when the rest length is not free
  double tau_lower = 0.0;           ///< physical bounds of tau (clamp_length genes only)
  double tau_upper = 0.0;
};

/// Maps genes <-> physical parameter values. Built from a model (free flags, bounds, initial
/// guesses) and the observed data (average bond lengths for rest-length-like parameters).
class ParameterSpace {
 public:
  /// Most breakpoints kept per threshold gene.
  static constexpr size_t kMaxBreakpoints = 4096;

  /// `trajectory` has the model's particles as markers (see remapMarkers).
  ParameterSpace(const Model& model, const Trajectory& trajectory);

  size_t size() const { return genes_.size(); }
  const Gene& gene(size_t k) const { return genes_[k]; }
  const std::vector<Gene>& genes() const { return genes_; }
  /// The free parameters in Cost order.
  std::vector<ParamRef> refs() const;

  /// Genes -> physical values in Cost order (a clamp-length gene needs its type's rest
  /// length, so the conversion works on whole vectors).
  std::vector<double> toPhysical(const std::vector<double>& genes) const;
  /// Physical values -> genes (inverse of toPhysical inside the bounds; not reflected).
  std::vector<double> toSearch(const std::vector<double>& physical) const;
  /// d(physical value k) / d(gene k) at `genes`, other genes held: turns a gene's standard
  /// deviation into the parameter's.
  double physicalSlope(size_t k, const std::vector<double>& genes) const;
  /// Replaces gene k's search-space bounds (e.g. a default bound widened after the answer
  /// reached it). Breakpoints outside them are dropped. Throws InputError when empty.
  void setBounds(size_t k, double lower, double upper);
  /// -1 when gene k's value `gene` lies within 1 % of its lower bound (1 % of the value for log
  /// genes, of the range for linear ones), +1 within 1 % of its upper bound, 0 inside.
  int boundSide(size_t k, double gene) const;
  /// Clamps a gene into its bounds by reflection (keeps the search distribution symmetric).
  double reflect(size_t k, double gene_value) const;
  /// Draws gene k from the paper's initialisation (rest lengths around the average observed
  /// distance of the bonds of that type, others log-Gaussian), inside the bounds.
  template <class R>
  double sampleInitial(size_t k, R& random) const {
    return reflect(k, genes_[k].init_center + genes_[k].init_spread * random.normal());
  }

  /// Genes of each bond type (index = bond type; empty for types without free parameters).
  const std::vector<std::vector<int>>& genesOfType() const { return genes_of_type_; }
  /// Particles at an extremity of a bond of each type (for interactions: all particles of the
  /// interacting groups): the "sites" whose local costs judge that type's parameters.
  const std::vector<std::vector<int>>& sitesOfType() const { return sites_of_type_; }
  /// Bond types that own at least one gene, ascending.
  const std::vector<int>& typesWithGenes() const { return types_with_genes_; }

 private:
  double restLength(const Gene& g, const std::vector<double>& physical) const;

  std::vector<Gene> genes_;
  std::vector<std::vector<int>> genes_of_type_;
  std::vector<std::vector<int>> sites_of_type_;
  std::vector<int> types_with_genes_;
};

}  // namespace mme

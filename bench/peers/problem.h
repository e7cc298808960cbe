// Identification problems for the peer benchmark: a true model, the data it produced
// (optionally perturbed: noise, occlusion, another frame rate), the paper's cost and search space
// that every method shares, the random starts, parameter errors and the long-rollout check.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/random.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/search/parameter_space.h"

namespace bench {

struct Errors {
  double median = 0.0, max = 0.0;  ///< relative parameter errors [%]
};
Errors relativeErrors(const std::vector<double>& values, const std::vector<double>& truth);

/// The model as identification sees it: free values forgotten (bounds kept), like bench_paper.
mme::Model forgetFreeValues(mme::Model model);

struct Problem {
  std::string name;
  mme::Model truth;    ///< true values (free flags set); substeps = the data generator's
  mme::Model model;    ///< what identification sees: free values forgotten, identification substeps
  mme::Trajectory data;
  std::shared_ptr<const mme::ShortTermCost> cost;
  std::shared_ptr<const mme::ParameterSpace> space;
  std::vector<double> truth_values;  ///< physical, in free-parameter order
  /// Starts: < 0 = the paper's initial distribution (ParameterSpace::sampleInitial, the same
  /// stream the engine draws its initial population from); >= 0 = the true genes plus a normal
  /// draw of this std as a share of each gene's range (the initial-guess-spread axis).
  double start_spread = -1.0;
  /// Long-rollout check: the exact state at the first data frame and the number of frames.
  mme::State rollout_state;
  int rollout_frames = 0;
  double rollout_limit_m = 0.0;  ///< bounded = every displacement stays below it
  /// Marker noise added to the data [m] (0: none) and the data before it was added (the same
  /// occlusion pattern): what the Cramer-Rao bound is computed on.
  double noise_std_m = 0.0;
  mme::Trajectory noiseless_data;
  /// Equation-error least squares applies (linear springs/dampers, one step per frame).
  bool lls_applicable = false;
  std::string lls_reason;  ///< why not, when it does not apply
};

/// Builds cost, space, frame costs, truth values, the rollout reference and the LLS verdict.
/// `data_state` is the exact state at the data's first frame (for the rollout check).
Problem makeProblem(const std::string& name, const mme::Model& truth, int identification_substeps,
                    const mme::Trajectory& data, const mme::State& data_state);

/// The Cramer-Rao bound (mme::cramerRaoBound: output-error model, initial state unknown, white
/// marker noise of problem.noise_std_m) of every free parameter as a share of its true value
/// [%], computed on the truth at the identification substeps and the noiseless data; NaN for
/// thresholds and undetermined parameters; empty when the data are noise-free.
std::vector<double> cramerRaoPct(const Problem& problem);

/// Per-parameter |value - truth| / bound (bound in % of the truth, as cramerRaoPct): the median
/// over the parameters with a finite bound; NaN when there is none or the values are not finite.
double medianEfficiency(const std::vector<double>& values, const std::vector<double>& truth,
                        const std::vector<double>& bound_pct);

/// Thresholds of conditional bonds are determined by the data only up to the flat interval
/// between the observed switching lengths around them (Gene::breakpoints). The largest error [%]
/// over the thresholds of the middle of the truth's interval (what a method returning interval
/// middles, like the threshold search, scores at best); NaN when the problem has no threshold.
double thresholdMiddleErrorPct(const Problem& problem);

/// Simulates `frames` frames of `model` (its substeps) at `rate_hz`, keeping the exact state at
/// frame `first` (returned in *state_at_first) and returning frames [first, frames).
mme::Trajectory simulateWindow(const mme::Model& model, int frames, double rate_hz, int first,
                               mme::State* state_at_first);

/// Marks a random share of the samples occluded (position zeroed), reproducibly from `seed`.
void occludeRandomly(mme::Trajectory* data, double share, uint64_t seed);

/// Highest angular frequency [rad/s] of the linearised spring network at the model's initial
/// positions (axial stiffness only): sqrt of the largest eigenvalue of M^-1/2 K M^-1/2.
double stiffestOmega(const mme::Model& model);

/// The random starts of one run: draw i is the i-th individual of the engine's initial
/// population for the same seed (default rule).
class Starts {
 public:
  Starts(const Problem& problem, uint64_t seed);
  std::vector<double> next();

 private:
  const Problem& problem_;
  mme::Random random_;
};

/// Global cost of genes (reflected into the bounds first, as the engine does with its moves).
double costOfGenes(const Problem& problem, std::vector<double>* genes);

/// Simulates the identified model (truth with `values` installed, `substeps` steps per frame:
/// the ones it was identified with; 0 = the problem's identification substeps) from the exact
/// state at the first data frame for rollout_frames frames: true when every position stays
/// finite and within rollout_limit_m of its start.
bool rolloutBounded(const Problem& problem, const std::vector<double>& values, int substeps = 0);

/// Linear spring-network test scene for the scaling experiment: a rows x cols sheet with
/// structural, shear and bending springs (3 types, 6 unknowns), floating and vibrating.
mme::Model makeSheet(int rows, int cols, double rate_hz, uint64_t seed);

/// A random object whose first `cable_types` spring types are cables: active only when
/// stretched (min_distance = rest length, free), i.e. conditional bonds.
mme::Model makeCableObject(int bond_types, int cable_types, int particles, int bonds,
                           double rate_hz, uint64_t seed);

}  // namespace bench

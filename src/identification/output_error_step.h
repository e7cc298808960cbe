// The output-error step of identifyModel, after the search on the one-step cost: its starts, the
// stiff-scene substep trial, the final fit, and the judgement that decides whether its answer
// replaces the one-step answer at all (answer_judge.h). A fit that diverged is reported and
// never adopted; when the model cannot explain the motion and the first stage gains nothing on
// the judge, the expensive later stages are not run.
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/search/parameter_space.h"

namespace mme {

/// What the step leaves for the identification's result.
struct OutputErrorOutcome {
  bool adopted = false;      ///< the output error's answer replaces the one-step answer
  OutputErrorResult fit;     ///< the adopted fit (meaningful when adopted)
  int substeps = 1;          ///< the adopted answer's integrator (the input model's when not adopted)
  bool time_cut = false;     ///< a time limit ended one of its fits
  std::string std_missing_reason;  ///< set when the adopted fit carries no std
  double one_step_judged_rms_m = 0.0;  ///< the judge's figure of the one-step answer
  double judged_rms_m = 0.0;           ///< ... of the answer that stands after the step
};

class OutputErrorStep {
 public:
  /// `elapsed` gives the identification's wall time so far [s] (its time limit is shared);
  /// `note` records a line for the result (and the user). Every reference must outlive the step.
  OutputErrorStep(const Model& model, const Trajectory& trajectory, const ParameterSpace& space,
                  const IdentifyOptions& options, const std::vector<Eigen::Vector3d>& reference_m,
                  std::function<double()> elapsed, std::function<void(const std::string&)> note);

  /// From the search's answer `one_step_genes` on data whose estimated marker noise is
  /// `noise_estimate_m` [m].
  OutputErrorOutcome run(const std::vector<double>& one_step_genes, double noise_estimate_m);

 private:
  std::vector<std::vector<double>> starts(const std::vector<double>& one_step_genes) const;
  OutputErrorResult fit(const Model& m, const std::vector<double>& from, int max_iterations,
                        bool estimate_std) const;
  std::string unusableBecause(const OutputErrorResult& oe) const;
  OutputErrorResult scoutStarts(const std::vector<double>& one_step_genes, std::string* failed);
  bool misfit(const OutputErrorResult& oe) const;
  double judge(const Model& m, const std::vector<double>& genes) const;
  void trySubsteps(OutputErrorResult* best, double* best_rms_m);
  void finalFit(OutputErrorResult* best, double* best_rms_m);
  void noteFit(const OutputErrorResult& oe, bool first_stage_only) const;
  double omegaH(const std::vector<double>& values) const;

  const Trajectory& trajectory_;
  const ParameterSpace& space_;
  const IdentifyOptions& options_;
  const std::vector<Eigen::Vector3d>& reference_m_;
  std::function<double()> elapsed_;
  std::function<void(const std::string&)> note_;
  Model model_;  ///< the integrator the output error fits with (the trial may refine it)
  double noise_estimate_m_ = 0.0;
  /// The one-step answer's output-error cost (the first scout's start) [m^2].
  double one_step_oe_cost_m2_ = std::numeric_limits<double>::infinity();
  OutputErrorOutcome out_;
};

}  // namespace mme

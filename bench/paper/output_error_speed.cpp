// The output error's Jacobians, exact (forward sensitivities) against forward differences, from
// the same start in the same run: the `oe_speed` experiment of bench_paper.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common.h"
#include "experiments.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "motion_model_estimation/identification/search/parameter_space.h"
#include "motion_model_estimation/identification/structure/marker_model.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/scenes/random_object.h"

namespace paper {

namespace {

double medianOf(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t m = v.size();
  return m % 2 ? v[m / 2] : 0.5 * (v[m / 2 - 1] + v[m / 2]);
}

const char* jacobianName(mme::OutputErrorJacobian j) {
  return j == mme::OutputErrorJacobian::kExact ? "exact" : "finite_differences";
}

}  // namespace

/// Two cases, each fitted with both Jacobians from one start:
/// - random43: the big soak model (43 markers, 91 damped spring types, 273 unknowns), 240
///   frames at 120 Hz, 0.1 mm of noise, started 2 % off the truth (alternating signs in search
///   space): wall time, iterations, the median relative error and its ratio to the Cramer-Rao
///   bound's median.
/// - walk39: motion_capture_walk's first 240 frames with markerModel's 39 damped springs and a
///   free gravity (120 unknowns, the size its structure selection leaves), from the search
///   space's initial centres, a few iterations: the time per iteration (no truth to compare).
void outputErrorSpeed(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/oe_speed.csv",
                         "case,jacobian,unknowns,frames,wall_s,iterations,s_per_iteration,"
                         "converged,median_error_percent,bound_median_percent,error_over_bound");
  const std::vector<mme::OutputErrorJacobian> kinds = {mme::OutputErrorJacobian::kFiniteDifferences,
                                                       mme::OutputErrorJacobian::kExact};
  {
    mme::RandomObjectSpec spec;  // as bench_paper's online experiment and the soak's big model
    spec.particles = 43;
    spec.bond_types = 91;
    spec.bonds = 91;
    spec.damping_max_nspm = 0.05;
    const Model truth = mme::makeRandomObject(spec);
    const int frames = s.quick ? 120 : 240;
    const double noise_m = 1e-4;
    const mme::Trajectory clean = mme::simulateTrajectory(truth, frames, truth.frame_rate_hz);
    mme::Trajectory data = clean;
    mme::addGaussianNoise(&data, noise_m, 41);
    const std::vector<double> true_values = mme::getValues(truth, mme::freeParameters(truth));
    const Model search = forgetFreeValues(truth);
    const mme::ParameterSpace space(search, data);
    std::vector<double> start = space.toSearch(true_values);
    for (size_t k = 0; k < start.size(); ++k) start[k] = space.reflect(k, start[k] + (k % 2 ? 0.02 : -0.02));
    const mme::ParameterSpace truth_space(truth, clean);
    const auto bound_began = std::chrono::steady_clock::now();
    const std::vector<double> bound = mme::cramerRaoBound(truth, clean, truth_space, noise_m);
    const double bound_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - bound_began).count();
    std::vector<double> bound_rel;
    for (size_t k = 0; k < bound.size(); ++k) bound_rel.push_back(100.0 * bound[k] / std::abs(true_values[k]));
    const double bound_median = medianOf(bound_rel);
    std::printf("oe_speed: random43: %zu unknowns, %d frames, Cramer-Rao bound median %.4g %% (%.1f s)\n",
                true_values.size(), frames, bound_median, bound_s);
    double fd_s = 0.0;
    for (mme::OutputErrorJacobian j : kinds) {
      mme::OutputErrorOptions o;
      o.threads = s.threads;
      o.jacobian = j;
      const mme::OutputErrorResult r = mme::estimateOutputError(search, data, space, start, o);
      std::vector<double> errors;
      for (size_t k = 0; k < r.values.size(); ++k)
        errors.push_back(100.0 * std::abs(r.values[k] / true_values[k] - 1.0));
      const double median = medianOf(errors);
      if (j == mme::OutputErrorJacobian::kFiniteDifferences) fd_s = r.wall_time_s;
      std::fprintf(f, "random43,%s,%zu,%d,%.3f,%d,%.4f,%d,%.6g,%.6g,%.4g\n", jacobianName(j),
                   true_values.size(), frames, r.wall_time_s, r.iterations,
                   r.wall_time_s / std::max(1, r.iterations), r.converged ? 1 : 0, median,
                   bound_median, median / bound_median);
      std::fflush(f);
      std::printf("oe_speed: random43 %-18s %8.2f s (Jacobians %.2f s, linear solver %.2f s), %3d "
                  "iterations (%.3f s each), %s, median error %.4g %% = %.2f x the bound; jacobian: %s\n",
                  jacobianName(j), r.wall_time_s, r.jacobian_time_s, r.linear_solver_time_s,
                  r.iterations, r.wall_time_s / std::max(1, r.iterations),
                  r.converged ? "converged" : r.termination.c_str(), median, median / bound_median,
                  r.jacobian.c_str());
      if (j == mme::OutputErrorJacobian::kExact && fd_s > 0.0)
        std::printf("oe_speed: random43: finite differences / exact wall time = %.2f\n", fd_s / r.wall_time_s);
    }
    // The linear solvers on the same problem, exact Jacobians, a fixed number of iterations.
    const std::vector<std::pair<const char*, mme::OutputErrorLinearSolver>> solvers = {
        {"sparse_normal_cholesky", mme::OutputErrorLinearSolver::kSparseNormalCholesky},
        {"sparse_schur", mme::OutputErrorLinearSolver::kSparseSchur},
        {"iterative_schur", mme::OutputErrorLinearSolver::kIterativeSchur}};
    for (const auto& solver : solvers) {
      mme::OutputErrorOptions o;
      o.threads = s.threads;
      o.linear_solver = solver.second;
      o.max_iterations = s.quick ? 3 : 8;
      o.estimate_std = false;
      const mme::OutputErrorResult r = mme::estimateOutputError(search, data, space, start, o);
      std::fprintf(f, "random43_%s,exact,%zu,%d,%.3f,%d,%.4f,%d,,,\n", solver.first, true_values.size(),
                   frames, r.wall_time_s, r.iterations, r.wall_time_s / std::max(1, r.iterations),
                   r.converged ? 1 : 0);
      std::fflush(f);
      std::printf("oe_speed: random43 solver %-22s %7.2f s (Jacobians %.2f s, linear solver %.2f s), "
                  "%d iterations, cost %.6g m^2\n", solver.first, r.wall_time_s, r.jacobian_time_s,
                  r.linear_solver_time_s, r.iterations, r.observation_cost_m2);
    }
  }
  {
    const std::string path = std::string(MME_TEST_DATA_DIR) + "/real/motion_capture_walk.trc";
    const mme::Trajectory data = mme::sliceFrames(mme::readTrajectoryFile(path), 0, 240);
    const Model model = mme::markerModel(data, 39);
    const mme::ParameterSpace space(model, data);
    std::vector<double> start;
    for (size_t k = 0; k < space.size(); ++k) start.push_back(space.gene(k).init_center);
    double fd_per_iteration = 0.0;
    for (mme::OutputErrorJacobian j : kinds) {
      mme::OutputErrorOptions o;
      o.threads = s.threads;
      o.jacobian = j;
      o.max_iterations = s.quick ? 3 : 10;
      o.estimate_std = false;
      const mme::OutputErrorResult r = mme::estimateOutputError(model, data, space, start, o);
      const double per_iteration = r.wall_time_s / std::max(1, r.iterations);
      std::fprintf(f, "walk39,%s,%zu,%d,%.3f,%d,%.4f,%d,,,\n", jacobianName(j), space.size(),
                   data.numFrames(), r.wall_time_s, r.iterations, per_iteration, r.converged ? 1 : 0);
      std::fflush(f);
      std::printf("oe_speed: walk39 %-18s %8.2f s (Jacobians %.2f s, linear solver %.2f s), %3d "
                  "iterations (%.3f s each), cost %.4g -> %.4g m^2; jacobian: %s\n", jacobianName(j),
                  r.wall_time_s, r.jacobian_time_s, r.linear_solver_time_s, r.iterations, per_iteration,
                  r.start_cost_m2, r.observation_cost_m2, r.jacobian.c_str());
      if (j == mme::OutputErrorJacobian::kFiniteDifferences) fd_per_iteration = per_iteration;
      else if (per_iteration > 0.0)
        std::printf("oe_speed: walk39: finite differences / exact time per iteration = %.2f\n",
                    fd_per_iteration / per_iteration);
    }
  }
  std::fclose(f);
}

}  // namespace paper

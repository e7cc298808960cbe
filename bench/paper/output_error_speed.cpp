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
#include "motion_model_estimation/identification/estimators/motion_sensitivity.h"
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

/// Runs one output-error fit on the case and writes its CSV line.
struct Case {
  std::string name;
  Model search;
  mme::Trajectory data;
  const mme::ParameterSpace* space;
  std::vector<double> start;
  std::vector<double> truth;  // empty: no truth to compare
  double bound_median_percent = NAN;
};

mme::OutputErrorResult fitCase(const Settings& s, std::FILE* f, const Case& c, const char* solver_name,
                               mme::OutputErrorOptions o) {
  o.threads = s.threads;
  const mme::OutputErrorResult r = mme::estimateOutputError(c.search, c.data, *c.space, c.start, o);
  std::vector<double> errors;
  for (size_t k = 0; k < c.truth.size(); ++k) errors.push_back(100.0 * std::abs(r.values[k] / c.truth[k] - 1.0));
  const double median = medianOf(errors);
  const int iterations = std::max(1, r.iterations);
  std::fprintf(f, "%s,%s,%s,%zu,%d,%d,%.3f,%.3f,%.3f,%d,%.4f,%d,%.6g,%.6g,%.4g,%.0e\n", c.name.c_str(),
               jacobianName(o.jacobian), solver_name, c.space->size(), c.data.numFrames(), o.max_iterations,
               r.wall_time_s, r.jacobian_time_s, r.linear_solver_time_s, r.iterations,
               r.wall_time_s / iterations, r.converged ? 1 : 0, median, c.bound_median_percent,
               median / c.bound_median_percent, o.first_stage_function_tolerance);
  std::fflush(f);
  std::printf("oe_speed: %s %-18s %-22s %8.2f s (Jacobians %.2f s, linear solver %.2f s), %3d "
              "iterations (%.3f s each; soft stage to %.0e), %s, cost %.6g m^2", c.name.c_str(),
              jacobianName(o.jacobian), solver_name, r.wall_time_s, r.jacobian_time_s, r.linear_solver_time_s,
              r.iterations, r.wall_time_s / iterations, o.first_stage_function_tolerance,
              r.converged ? "converged" : "not converged", r.observation_cost_m2);
  if (!c.truth.empty())
    std::printf(", median error %.4g %% = %.2f x the bound", median, median / c.bound_median_percent);
  std::printf("; jacobian: %s%s%s\n", mme::outputErrorJacobianName(r.jacobian),
              r.exact_jacobian_unsupported.empty() ? "" : ": ", r.exact_jacobian_unsupported.c_str());
  std::fflush(stdout);
  return r;
}

const std::vector<std::pair<const char*, mme::OutputErrorLinearSolver>>& solvers() {
  static const std::vector<std::pair<const char*, mme::OutputErrorLinearSolver>> kSolvers = {
      {"sparse_normal_cholesky", mme::OutputErrorLinearSolver::kSparseNormalCholesky},
      {"sparse_schur", mme::OutputErrorLinearSolver::kSparseSchur},
      {"iterative_schur", mme::OutputErrorLinearSolver::kIterativeSchur}};
  return kSolvers;
}

/// How sparse a shooting segment's Jacobian could be made: the fraction of (particle, column
/// block) pairs, the blocks being each bond type's parameters and each particle's start state,
/// where the particle's rows over the segment's frames reach `tolerance` x the block's largest
/// entry in the segment (0: structurally non-zero). The sensitivities from the truth's state at
/// frame 20 of `clean`, over `frames` frames. Ceres' products scale with the square of it.
void printSegmentFill(const char* name, const Model& truth, const mme::Trajectory& clean, int frames) {
  const std::vector<mme::ParamRef> refs = mme::freeParameters(truth);
  const int n = static_cast<int>(truth.particles.size()), types = static_cast<int>(truth.bond_types.size());
  mme::MotionSensitivity sens(truth, refs);
  mme::State state;
  const int t0 = std::min(20, clean.numFrames() - 2);
  for (int i = 0; i < n; ++i) {
    state.x_m.push_back(clean.position(t0, i));
    state.v_mps.push_back((clean.position(t0 + 1, i) - clean.position(t0 - 1, i)) * (0.5 * truth.frame_rate_hz));
  }
  sens.start(state);
  const int np = static_cast<int>(refs.size()), blocks = types + 1 + n;  // types, gravity, particles
  std::vector<int> block_of(sens.columns());
  for (int c = 0; c < sens.columns(); ++c) {
    if (c >= np) block_of[c] = types + 1 + (c - np) / 6;  // a free particle's x and v h
    else block_of[c] = refs[c].bond_type < 0 ? types : refs[c].bond_type;
  }
  std::vector<double> largest(static_cast<size_t>(n) * blocks, 0.0), block_largest(blocks, 0.0);
  std::vector<uint8_t> used(blocks, 0);
  for (int t = 0; t < frames; ++t) {
    sens.stepFrame(1.0 / truth.frame_rate_hz);
    for (int i = 0; i < n; ++i)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < sens.columns(); ++c) {
          const double v = std::abs(sens.dx()(3 * i + r, c));
          double& cell = largest[static_cast<size_t>(i) * blocks + block_of[c]];
          cell = std::max(cell, v);
          block_largest[block_of[c]] = std::max(block_largest[block_of[c]], v);
          used[block_of[c]] = 1;
        }
  }
  std::printf("oe_speed: %s: fill of a %d-frame segment's Jacobian per (particle, bond type or particle "
              "state):", name, frames);
  for (double tolerance : {0.0, 1e-12, 1e-9, 1e-6, 1e-3}) {
    long kept = 0, all = 0;
    for (int i = 0; i < n; ++i)
      for (int b = 0; b < blocks; ++b) {
        if (!used[b]) continue;
        ++all;
        kept += largest[static_cast<size_t>(i) * blocks + b] > tolerance * block_largest[b] ? 1 : 0;
      }
    std::printf(" %.0e: %.2f", tolerance, static_cast<double>(kept) / std::max(1L, all));
  }
  std::printf("\n");
  std::fflush(stdout);
}

/// One random object's fits (see outputErrorSpeed); `probes`: first the time of an iteration of
/// every pair, the whole fit with exact Jacobians then taking the fastest solver.
void randomObjectFits(const Settings& s, std::FILE* f, const char* name, const mme::RandomObjectSpec& spec,
                      int probe_iterations, bool probes) {
  const Model truth = mme::makeRandomObject(spec);
  const int frames = s.quick ? 120 : 240;
  const double noise_m = 1e-4;
  const mme::Trajectory clean = mme::simulateTrajectory(truth, frames, truth.frame_rate_hz);
  Case c;
  c.name = name;
  c.data = clean;
  mme::addGaussianNoise(&c.data, noise_m, 41);
  c.truth = mme::getValues(truth, mme::freeParameters(truth));
  c.search = forgetFreeValues(truth);
  const mme::ParameterSpace space(c.search, c.data);
  c.space = &space;
  c.start = space.toSearch(c.truth);
  for (size_t k = 0; k < c.start.size(); ++k) c.start[k] = space.reflect(k, c.start[k] + (k % 2 ? 0.02 : -0.02));
  // The time of an iteration: every pair, a few iterations per continuity stage.
  std::pair<const char*, mme::OutputErrorLinearSolver> fastest = solvers().front();
  double fastest_s = INFINITY;
  for (const auto& solver : solvers()) {
    if (!probes) break;
    mme::OutputErrorOptions o;
    o.linear_solver = solver.second;
    o.max_iterations = probe_iterations;
    o.estimate_std = false;
    const mme::OutputErrorResult r = fitCase(s, f, c, solver.first, o);
    const double per_iteration = r.wall_time_s / std::max(1, r.iterations);
    if (per_iteration < fastest_s) {
      fastest_s = per_iteration;
      fastest = solver;
    }
  }
  if (probes) {
    mme::OutputErrorOptions o;
    o.jacobian = mme::OutputErrorJacobian::kFiniteDifferences;
    o.max_iterations = probe_iterations;
    o.estimate_std = false;
    fitCase(s, f, c, solvers().front().first, o);
  }
  const mme::ParameterSpace truth_space(truth, clean);
  const auto bound_began = std::chrono::steady_clock::now();
  const std::vector<double> bound = mme::cramerRaoBound(truth, clean, truth_space, noise_m);
  const double bound_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - bound_began).count();
  std::vector<double> bound_rel;
  for (size_t k = 0; k < bound.size(); ++k) bound_rel.push_back(100.0 * bound[k] / std::abs(c.truth[k]));
  c.bound_median_percent = medianOf(bound_rel);
  std::printf("oe_speed: %s: %zu unknowns, %d frames, Cramer-Rao bound median %.4g %% (%.1f s)\n",
              name, c.truth.size(), frames, c.bound_median_percent, bound_s);
  printSegmentFill(name, truth, clean, mme::OutputErrorOptions().segment_frames);
  mme::OutputErrorOptions exact;
  exact.linear_solver = fastest.second;
  exact.first_stage_function_tolerance = 1e-3;  // the soft stage as a waypoint
  const double exact_s = fitCase(s, f, c, fastest.first, exact).wall_time_s;
  // The fit before the soft stage became a waypoint: run to the hard stage's precision.
  mme::OutputErrorOptions exact_waypoint = exact;
  exact_waypoint.first_stage_function_tolerance = 1e-14;
  const double exact_waypoint_s = fitCase(s, f, c, fastest.first, exact_waypoint).wall_time_s;
  mme::OutputErrorOptions today;  // the fit before exact Jacobians
  today.jacobian = mme::OutputErrorJacobian::kFiniteDifferences;
  today.linear_solver = mme::OutputErrorLinearSolver::kSparseNormalCholesky;
  today.first_stage_function_tolerance = 1e-14;
  const double today_s = fitCase(s, f, c, solvers().front().first, today).wall_time_s;
  std::printf("oe_speed: %s: soft stage to 1e-14 / to %.0e = %.2f; forward differences, soft stage to 1e-14 "
              "/ exact with %s = %.2f\n", name, exact.first_stage_function_tolerance,
              exact_waypoint_s / exact_s, fastest.first, today_s / exact_s);
}

}  // namespace

/// Two cases:
/// - random43: the big soak model (43 markers, 91 damped spring types, 273 unknowns), 240
///   frames at 120 Hz, 0.1 mm of noise, started 2 % off the truth (alternating signs in search
///   space). First a few iterations of every (Jacobian, linear solver) pair from the same start
///   (the time of an iteration), then the whole fit with exact Jacobians and the fastest
///   solver, then today's (forward differences, sparse normal Cholesky) whole fit: wall times,
///   their ratio, the median relative error and its ratio to the Cramer-Rao bound's median.
/// - walk39: motion_capture_walk (238 frames) with markerModel's 39 damped springs and a
///   free gravity (120 unknowns, the size its structure selection leaves), from the search
///   space's initial centres, a few iterations each way: the time per iteration.
/// `--only oe_speed_small` instead: random18's object with damped types (18 markers, 12 types,
/// 36 unknowns), the whole fits both ways and its bound (minutes, where random43's take hours on
/// a loaded machine), and random43's segment fill.
/// Each random object's whole fits: exact Jacobians with the soft stage as a waypoint (1e-3), the
/// same with the soft stage run to 1e-14 (the default), and forward differences
/// with the soft stage to 1e-14 (the fit before exact Jacobians), in one run; before them the
/// fill of a segment's Jacobian (printSegmentFill).
void outputErrorSpeed(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/oe_speed.csv",
                         "case,jacobian,linear_solver,unknowns,frames,max_iterations,wall_s,jacobian_s,"
                         "linear_solver_s,iterations,s_per_iteration,converged,median_error_percent,"
                         "bound_median_percent,error_over_bound,first_stage_function_tolerance");
  const int probe_iterations = s.quick ? 2 : 4;
  if (!s.wants("oe_speed_small")) {
    const std::string path = std::string(MME_TEST_DATA_DIR) + "/real/motion_capture_walk.trc";
    Case c;
    c.name = "walk39";
    c.data = mme::readTrajectoryFile(path);  // 238 frames
    c.search = mme::markerModel(c.data, 39);
    const mme::ParameterSpace space(c.search, c.data);
    c.space = &space;
    for (size_t k = 0; k < space.size(); ++k) c.start.push_back(space.gene(k).init_center);
    for (const auto& solver : solvers()) {
      mme::OutputErrorOptions o;
      o.linear_solver = solver.second;
      o.max_iterations = probe_iterations;
      o.estimate_std = false;
      fitCase(s, f, c, solver.first, o);
    }
    mme::OutputErrorOptions o;
    o.jacobian = mme::OutputErrorJacobian::kFiniteDifferences;
    o.max_iterations = probe_iterations;
    o.estimate_std = false;
    fitCase(s, f, c, solvers().front().first, o);
  }
  mme::RandomObjectSpec big;  // as bench_paper's online experiment and the soak's big model
  big.particles = 43;
  big.bond_types = 91;
  big.bonds = 91;
  big.damping_max_nspm = 0.05;
  if (!s.wants("oe_speed_small")) randomObjectFits(s, f, "random43", big, probe_iterations, true);
  if (s.wants("oe_speed_small")) {
    // The big object's fill too (one short simulation): its fits take hours on a loaded machine.
    const Model truth = mme::makeRandomObject(big);
    printSegmentFill("random43", truth, mme::simulateTrajectory(truth, 40, truth.frame_rate_hz),
                     mme::OutputErrorOptions().segment_frames);
    mme::RandomObjectSpec spec;  // random18's object with damped types
    spec.damping_max_nspm = 0.05;
    randomObjectFits(s, f, "random18", spec, probe_iterations, false);
  }
  std::fclose(f);
}

}  // namespace paper

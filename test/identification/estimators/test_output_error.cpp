// The output-error estimator: the noise level from the data, accuracy at the Cramer-Rao bound on
// a noisy scene, std that means something, occluded samples that simply do not count, and the
// identifier's choices (which estimator, how many substeps) made from the data.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/core/stiffness.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "motion_model_estimation/scenes/scenes.h"
#include "test_helpers.h"

namespace {

using mme::test::maxRelativeError;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

std::vector<double> relativeErrors(const std::vector<double>& values, const std::vector<double>& truth) {
  std::vector<double> e;
  for (size_t k = 0; k < values.size(); ++k) e.push_back(std::abs(values[k] / truth[k] - 1.0));
  return e;
}

struct Noisy {
  mme::Model truth = mme::makeScene("paper_object").model;
  mme::Model search = mme::test::withoutValues(truth);
  mme::Trajectory clean = mme::simulateTrajectory(truth, 100, truth.frame_rate_hz);
  std::vector<double> true_values = mme::getValues(truth, mme::freeParameters(truth));
  mme::Trajectory noisy(double sigma, uint64_t seed) const {
    mme::Trajectory d = clean;
    mme::addGaussianNoise(&d, sigma, seed);
    return d;
  }
  /// The true values moved by +-offset in the search space (alternate signs), reflected in bounds.
  std::vector<double> offStart(const mme::ParameterSpace& space, double offset) const {
    std::vector<double> start = space.toSearch(true_values);
    for (size_t k = 0; k < start.size(); ++k)
      start[k] = space.reflect(k, start[k] + (k % 2 ? offset : -offset));
    return start;
  }
};

TEST(OutputError, MarkerNoiseIsEstimatedFromTheDataAlone) {
  Noisy n;
  for (double sigma : {1e-5, 1e-4, 1e-3}) {
    const double estimate = mme::estimateMarkerNoise(n.noisy(sigma, 3));
    EXPECT_NEAR(estimate, sigma, 0.1 * sigma) << sigma;
  }
  EXPECT_LT(mme::estimateMarkerNoise(n.clean), 1e-7);  // smooth motion: h^4 x'''' only
}

// From the truth 2 % off, at 0.1 mm of noise on paper_object (100 frames): the median error is
// within 2x the Cramer-Rao bound's median (0.035 %), every parameter within 1 %, and the
// reported std are close to the bound and cover the errors.
TEST(OutputError, ReachesTheCramerRaoBoundOnANoisyScene) {
  Noisy n;
  const mme::Trajectory data = n.noisy(1e-4, 7);
  const mme::ParameterSpace space(n.search, data);
  const std::vector<double> start = n.offStart(space, 0.02);
  const mme::OutputErrorResult r = mme::estimateOutputError(n.search, data, space, start);
  ASSERT_TRUE(r.ran) << r.reason;
  EXPECT_TRUE(r.converged) << r.termination;
  const mme::ParameterSpace truth_space(n.truth, n.clean);
  const std::vector<double> bound = mme::cramerRaoBound(n.truth, n.clean, truth_space, 1e-4);
  const std::vector<double> errors = relativeErrors(r.values, n.true_values);
  std::vector<double> bound_rel;
  for (size_t k = 0; k < bound.size(); ++k) bound_rel.push_back(bound[k] / n.true_values[k]);
  EXPECT_LT(median(errors), 2.0 * median(bound_rel));
  EXPECT_LT(*std::max_element(errors.begin(), errors.end()), 0.01);
  EXPECT_NEAR(r.noise_std_m, 1e-4, 1e-5);
  int covered = 0;
  for (size_t k = 0; k < errors.size(); ++k) {
    ASSERT_TRUE(std::isfinite(r.std_devs[k]));
    EXPECT_LT(r.std_devs[k], 1.5 * bound[k]) << k;
    EXPECT_GT(r.std_devs[k], 0.67 * bound[k]) << k;
    covered += std::abs(r.values[k] - n.true_values[k]) <= 3.0 * r.std_devs[k];
    EXPECT_FALSE(r.unidentifiable[k]);
  }
  EXPECT_GE(covered, 19);
}

// An occluded sample has no residual: garbage written at occluded positions changes nothing.
TEST(OutputError, OccludedSamplesDoNotCount) {
  Noisy n;
  mme::Trajectory data = n.noisy(1e-4, 9);
  for (size_t k = 0; k < data.occluded.size(); ++k)
    if ((k * 2654435761u) % 7 == 0) data.occluded[k] = 1;
  mme::Trajectory garbage = data;
  for (size_t k = 0; k < garbage.occluded.size(); ++k)
    if (garbage.occluded[k]) garbage.positions_m[k] = Eigen::Vector3d(3.0, -2.0, 1.0);
  const mme::ParameterSpace space(n.search, data);
  const std::vector<double> start = space.toSearch(n.true_values);
  mme::OutputErrorOptions o;
  o.estimate_std = false;
  const mme::OutputErrorResult a = mme::estimateOutputError(n.search, data, space, start, o);
  const mme::OutputErrorResult b = mme::estimateOutputError(n.search, garbage, space, start, o);
  ASSERT_TRUE(a.ran && b.ran);
  EXPECT_EQ(a.observations, b.observations);
  EXPECT_LT(maxRelativeError(b.values, a.values), 1e-9);
  EXPECT_LT(maxRelativeError(a.values, n.true_values), 0.01);
}

// The progress hook hears every iteration of every stage, in order within a stage, with the
// stage's iteration budget and a wall time that never goes back; the answer is the same as
// without it (a tool's progress line cannot change the fit).
TEST(OutputError, TheProgressHookHearsEveryIterationWithoutChangingTheAnswer) {
  Noisy n;
  const mme::Trajectory data = n.noisy(1e-4, 11);
  const mme::ParameterSpace space(n.search, data);
  const std::vector<double> start = n.offStart(space, 0.05);
  mme::OutputErrorOptions o;
  o.estimate_std = false;
  const mme::OutputErrorResult plain = mme::estimateOutputError(n.search, data, space, start, o);
  std::vector<int> iterations;
  double last_elapsed_s = 0.0;
  bool time_went_back = false, wrong_budget = false;
  o.progress = [&](int iteration, int max_iterations, double elapsed_s) {
    iterations.push_back(iteration);
    time_went_back = time_went_back || elapsed_s < last_elapsed_s;
    wrong_budget = wrong_budget || max_iterations != o.max_iterations;
    last_elapsed_s = elapsed_s;
  };
  const mme::OutputErrorResult heard = mme::estimateOutputError(n.search, data, space, start, o);
  ASSERT_TRUE(plain.ran && heard.ran);
  EXPECT_EQ(heard.values, plain.values);
  ASSERT_FALSE(iterations.empty());
  EXPECT_EQ(static_cast<int>(iterations.size()), heard.iterations);
  EXPECT_EQ(iterations.front(), 1);
  for (size_t k = 1; k < iterations.size(); ++k)  // 1, 2, ... within a stage; a new stage from 1
    EXPECT_TRUE(iterations[k] == iterations[k - 1] + 1 || iterations[k] == 1) << k;
  EXPECT_FALSE(time_went_back);
  EXPECT_FALSE(wrong_budget);
}

// A segment's two residual blocks read one shared simulation (and its Jacobian), which Ceres'
// threads may ask for at once: the answer is the same bit for bit with 1 and 2 threads, and the
// same as a second run's.
TEST(OutputError, ThreadsShareEachSegmentsSimulationWithoutChangingTheAnswer) {
  Noisy n;
  const mme::Trajectory data = n.noisy(1e-4, 11);
  const mme::ParameterSpace space(n.search, data);
  const std::vector<double> start = n.offStart(space, 0.05);
  mme::OutputErrorOptions o;
  o.max_iterations = 6;
  o.segment_frames = 5;  // many segments: the threads' blocks interleave
  o.estimate_std = false;
  o.threads = 1;
  const mme::OutputErrorResult one = mme::estimateOutputError(n.search, data, space, start, o);
  o.threads = 2;
  const mme::OutputErrorResult two = mme::estimateOutputError(n.search, data, space, start, o);
  const mme::OutputErrorResult again = mme::estimateOutputError(n.search, data, space, start, o);
  ASSERT_TRUE(one.ran && two.ran && again.ran);
  EXPECT_LT(one.observation_cost_m2, 0.5 * one.start_cost_m2);  // it did move
  EXPECT_EQ(one.genes, two.genes);
  EXPECT_EQ(two.genes, again.genes);
  EXPECT_EQ(one.observation_cost_m2, two.observation_cost_m2);
  EXPECT_EQ(one.iterations, two.iterations);
}

// Growing the data (grow_segments): the fit runs on the first segment's frames, then on 2, 4 and
// 8 segments' and then on all 100 (5 stages), each from the last answer; it reaches the plain
// fit's optimum, judged on every frame (its last stage starts from the fit on 81 frames, as
// close to the data as the truth), a stop by time still reports the cost on every frame, and a
// negative count is refused by name.
TEST(OutputError, GrowingTheDataEndsAtThePlainFitsOptimumJudgedOnEveryFrame) {
  Noisy n;
  const mme::Trajectory data = n.noisy(1e-4, 13);
  const mme::ParameterSpace space(n.search, data);
  const std::vector<double> start = n.offStart(space, 0.1);
  mme::OutputErrorOptions o;
  o.estimate_std = false;
  const mme::OutputErrorResult plain = mme::estimateOutputError(n.search, data, space, start, o);
  o.grow_segments = 1;
  const mme::OutputErrorResult grown = mme::estimateOutputError(n.search, data, space, start, o);
  ASSERT_TRUE(plain.ran && grown.ran) << plain.reason << grown.reason;
  EXPECT_EQ(plain.stages, 1);
  EXPECT_EQ(grown.stages, 5);
  EXPECT_EQ(grown.observations, plain.observations);
  EXPECT_EQ(grown.segments, plain.segments);
  // The last stage starts as close to the data as the truth does (segment states fitted to
  // their first 2 frames, no iteration: 4.6e-4 m^2), the plain fit 5.8x farther.
  mme::OutputErrorOptions none = o;
  none.grow_segments = 0;
  none.max_iterations = 0;
  const mme::OutputErrorResult at_truth =
      mme::estimateOutputError(n.search, data, space, space.toSearch(n.true_values), none);
  ASSERT_TRUE(at_truth.ran) << at_truth.reason;
  EXPECT_LT(grown.start_cost_m2, 1.05 * at_truth.observation_cost_m2);
  EXPECT_GT(plain.start_cost_m2, 3.0 * at_truth.observation_cost_m2);
  EXPECT_NEAR(grown.observation_cost_m2, plain.observation_cost_m2,
              1e-6 * plain.observation_cost_m2);
  EXPECT_LT(maxRelativeError(grown.values, plain.values), 1e-4);
  EXPECT_LT(maxRelativeError(grown.values, n.true_values), 0.01);

  o.max_time_s = 1e-3;  // stops in the first stage: the answer so far, judged on every frame
  const mme::OutputErrorResult stopped = mme::estimateOutputError(n.search, data, space, start, o);
  ASSERT_TRUE(stopped.ran) << stopped.reason;
  EXPECT_EQ(stopped.stages, 1);
  EXPECT_EQ(stopped.observations, plain.observations);
  EXPECT_TRUE(std::isfinite(stopped.observation_cost_m2));

  o.max_time_s = 0.0;
  o.grow_segments = -1;
  const mme::OutputErrorResult refused = mme::estimateOutputError(n.search, data, space, start, o);
  EXPECT_FALSE(refused.ran);
  EXPECT_NE(refused.reason.find("grow_segments"), std::string::npos) << refused.reason;
}

// The walker's stiff contact and servos act within a frame: the frame difference is not the
// velocity, and segments started from it miss the true motion (noiseless data, true parameters)
// by far more than segments started from the state the model itself fits to the first frames.
TEST(OutputError, StartStatesFromTheModelFollowStiffMotionThatFrameDifferencesMiss) {
  const mme::Model walker = mme::makeScene("walker").model;
  const mme::Trajectory data = mme::simulateTrajectory(walker, 21, walker.frame_rate_hz);
  const mme::ParameterSpace space(walker, data);
  const std::vector<double> truth = space.toSearch(mme::getValues(walker, mme::freeParameters(walker)));
  mme::OutputErrorOptions o;
  o.max_iterations = 0;  // the start only
  o.estimate_std = false;
  o.noise_std_m = 1e-4;
  o.start_state_frames = 0;
  const mme::OutputErrorResult from_data = mme::estimateOutputError(walker, data, space, truth, o);
  o.start_state_frames = 2;
  const mme::OutputErrorResult from_model = mme::estimateOutputError(walker, data, space, truth, o);
  ASSERT_TRUE(from_data.ran && from_model.ran);
  ASSERT_EQ(from_data.segments, 2);
  EXPECT_GT(from_data.start_cost_m2, 1e-4);
  EXPECT_LT(from_model.start_cost_m2, 1e-3 * from_data.start_cost_m2);
  // With the walker's continuous contact (its floor's contact depth) the fitted states follow
  // the data to round-off: measured 1.5e-20 m^2, against 9.1e-7 with a force that jumps at
  // touch-down (docs/model_file.md "Ground contact").
  EXPECT_LT(from_model.start_cost_m2, 1e-15);
  EXPECT_EQ(from_model.genes, truth);  // no iteration: the parameters did not move
}

// From a start 1 % off, hard continuity makes every segment carry one wrong motion and the fit
// stalls far from the truth; solving first with soft continuity (each segment follows its own
// data) and then hard lands near it (noiseless walker, 2 segments, 10 iterations per stage).
TEST(OutputError, SoftContinuityFirstFindsWhatHardContinuityAloneMisses) {
  const mme::Model walker = mme::makeScene("walker").model;
  const mme::Trajectory data = mme::simulateTrajectory(walker, 11, walker.frame_rate_hz);
  const mme::ParameterSpace space(walker, data);
  const std::vector<double> truth = mme::getValues(walker, mme::freeParameters(walker));
  std::vector<double> off = truth;
  for (size_t k = 0; k < off.size(); ++k) off[k] *= k % 2 ? 1.01 : 0.99;
  mme::OutputErrorOptions o;
  o.segment_frames = 5;
  o.max_iterations = 10;
  o.estimate_std = false;
  o.noise_std_m = 1e-4;
  o.first_continuity_weight = 0.0;
  const mme::OutputErrorResult hard = mme::estimateOutputError(walker, data, space, space.toSearch(off), o);
  o.first_continuity_weight = 1.0;
  const mme::OutputErrorResult soft_first = mme::estimateOutputError(walker, data, space, space.toSearch(off), o);
  ASSERT_TRUE(hard.ran && soft_first.ran);
  ASSERT_EQ(hard.segments, 2);
  EXPECT_LE(hard.iterations, 10);
  EXPECT_GT(soft_first.iterations, 10);  // two stages
  EXPECT_LT(soft_first.observation_cost_m2, 0.05 * hard.observation_cost_m2);
  const auto median = [&](const std::vector<double>& values) {
    std::vector<double> e;
    for (size_t k = 0; k < values.size(); ++k) e.push_back(std::abs(values[k] / truth[k] - 1.0));
    std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
    return e[e.size() / 2];
  };
  EXPECT_LT(median(soft_first.values), 0.5 * median(hard.values));
}

// A parameter the data cannot see (the only bond of its type joins a fixed particle to another
// fixed one) is flagged, not given a confident number.
TEST(OutputError, FlagsWhatTheDataCannotDetermine) {
  Noisy n;
  mme::Model model = n.truth;
  mme::test::addParticle(&model, Eigen::Vector3d(1, 1, 1), 1.0, true);
  mme::test::addParticle(&model, Eigen::Vector3d(1.2, 1, 1), 1.0, true);
  const int type = mme::test::addType(&model, "idle", mme::BondKind::kSpring,
                                      {{mme::kStiffness, 5.0}, {mme::kRestLength, 0.15}});
  mme::test::addBond(&model, type, 15, 16);
  const mme::Trajectory clean = mme::simulateTrajectory(model, 60, model.frame_rate_hz);
  mme::Trajectory data = clean;
  mme::addGaussianNoise(&data, 1e-4, 4);
  const mme::Model search = mme::test::withoutValues(model);
  const mme::ParameterSpace space(search, data);
  const mme::OutputErrorResult r = mme::estimateOutputError(
      search, data, space, space.toSearch(mme::getValues(model, mme::freeParameters(model))));
  ASSERT_TRUE(r.ran);
  const size_t n_params = r.values.size();
  EXPECT_TRUE(r.unidentifiable[n_params - 2]);  // idle/stiffness
  EXPECT_TRUE(r.unidentifiable[n_params - 1]);  // idle/rest_length
  EXPECT_TRUE(std::isnan(r.std_devs[n_params - 1]));
  for (size_t k = 0; k + 2 < n_params; ++k) EXPECT_FALSE(r.unidentifiable[k]) << k;
}

// identify's choice of estimator: the output error on noisy markers (and says so); the one-step
// cost on noiseless ones, where it is exact.
TEST(OutputError, TheIdentifierPicksTheEstimatorFromTheData) {
  Noisy n;
  mme::IdentifyOptions options = mme::identifyOptionsFor(mme::Preset::kDefault);
  options.estimate_std = false;
  const mme::IdentifyResult noisy = mme::identifyModel(n.search, n.noisy(1e-4, 5), options);
  EXPECT_EQ(noisy.estimator, mme::Estimator::kOutputError);
  EXPECT_NEAR(noisy.noise_estimate_m, 1e-4, 1e-5);
  EXPECT_LT(maxRelativeError(noisy.values, n.true_values), 0.01);
  const mme::IdentifyResult clean = mme::identifyModel(n.search, n.clean, options);
  EXPECT_EQ(clean.estimator, mme::Estimator::kShortTerm);
  EXPECT_LT(maxRelativeError(clean.values, n.true_values), 1e-8);
  options.cost = mme::CostChoice::kShortTerm;
  EXPECT_EQ(mme::identifyModel(n.search, n.noisy(1e-4, 5), options).estimator, mme::Estimator::kShortTerm);
}

// A stiff scene (omega h = 0.5, the data integrated with 20 substeps per frame, the model file
// with 1): the identifier finds that a finer integrator fits the frames better, uses it, says so,
// and gets every parameter within 1 % (with one step per frame the one-step cost is 2 % off).
TEST(OutputError, StiffScenesGetMoreSubstepsAutomatically) {
  mme::Model truth = mme::makeScene("paper_object").model;
  std::vector<Eigen::Vector3d> x;
  for (const mme::Particle& p : truth.particles) x.push_back(p.position_m);
  truth.frame_rate_hz = mme::stiffestModeRadPerS(truth, x) / 0.5;
  truth.substeps = 20;
  const mme::Trajectory data = mme::simulateTrajectory(truth, 60, truth.frame_rate_hz);
  mme::Model search = mme::test::withoutValues(truth);
  search.substeps = 1;
  mme::IdentifyOptions options = mme::identifyOptionsFor(mme::Preset::kDefault);
  options.estimate_std = false;
  const mme::IdentifyResult r = mme::identifyModel(search, data, options);
  EXPECT_GT(r.substeps, 1);
  EXPECT_EQ(r.model.substeps, r.substeps);
  EXPECT_NEAR(r.stiffest_omega_h, 0.5, 0.05);
  bool said = false;
  for (const std::string& note : r.notes) said = said || note.find("substeps per frame fit the frames better") != std::string::npos;
  EXPECT_TRUE(said);
  EXPECT_LT(maxRelativeError(r.values, mme::getValues(truth, mme::freeParameters(truth))), 0.01);
}

// 60 % of the samples occluded at random: the one-step cost keeps almost no term (or none) and an
// exact fit of a few terms can be wrong; the identifier notices and the output error, which uses
// every observed sample, finds the truth.
TEST(OutputError, HeavyOcclusionGoesToTheOutputError) {
  Noisy n;
  mme::Trajectory data = mme::simulateTrajectory(n.truth, 60, n.truth.frame_rate_hz);
  uint64_t state = 12345;
  for (size_t k = 0; k < data.occluded.size(); ++k) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    if ((state >> 33) % 10 < 6) data.occluded[k] = 1;
  }
  mme::IdentifyOptions options = mme::identifyOptionsFor(mme::Preset::kDefault);
  options.estimate_std = false;
  const mme::IdentifyResult r = mme::identifyModel(n.search, data, options);
  EXPECT_EQ(r.estimator, mme::Estimator::kOutputError);
  EXPECT_LT(maxRelativeError(r.values, n.true_values), 1e-6);
  options.cost = mme::CostChoice::kShortTerm;
  if (mme::ShortTermCost(n.search, data).termCount() == 0) {
    EXPECT_THROW(mme::identifyModel(n.search, data, options), mme::InputError);
  }
}

}  // namespace

namespace {

// Exact Jacobians (forward sensitivities) and forward differences find the same optimum on
// paper_object at 0.1 mm from 2 % off, with the same std; the result says which ran.
TEST(OutputError, ExactJacobiansReachTheFiniteDifferencesAnswer) {
  Noisy n;
  const mme::Trajectory data = n.noisy(1e-4, 7);
  const mme::ParameterSpace space(n.search, data);
  const std::vector<double> start = n.offStart(space, 0.02);
  mme::OutputErrorOptions o;
  o.jacobian = mme::OutputErrorJacobian::kFiniteDifferences;
  const mme::OutputErrorResult fd = mme::estimateOutputError(n.search, data, space, start, o);
  o.jacobian = mme::OutputErrorJacobian::kExact;
  const mme::OutputErrorResult exact = mme::estimateOutputError(n.search, data, space, start, o);
  ASSERT_TRUE(fd.ran && exact.ran);
  EXPECT_EQ(fd.jacobian, mme::OutputErrorJacobian::kFiniteDifferences);
  EXPECT_EQ(exact.jacobian, mme::OutputErrorJacobian::kExact);
  EXPECT_TRUE(fd.exact_jacobian_unsupported.empty());
  EXPECT_TRUE(exact.exact_jacobian_unsupported.empty()) << exact.exact_jacobian_unsupported;
  EXPECT_TRUE(exact.converged) << exact.termination;
  EXPECT_LT(maxRelativeError(exact.values, fd.values), 1e-6);
  EXPECT_NEAR(exact.observation_cost_m2, fd.observation_cost_m2, 1e-9 * fd.observation_cost_m2);
  for (size_t k = 0; k < exact.std_devs.size(); ++k)
    EXPECT_NEAR(exact.std_devs[k], fd.std_devs[k], 1e-4 * fd.std_devs[k]) << k;
}

// The soft-continuity stage as a waypoint: stopped once its cost changes by less than 0.1 % per
// iteration instead of run to 1e-14 (the default), the fit lands on the same optimum in
// far fewer iterations. A damped random object lets its dampers press on their lower bounds while
// the segments follow their own data, where Ceres' projected steps creep for dozens of
// iterations.
TEST(OutputError, AWaypointSoftStageReachesTheSameOptimumInFewerIterations) {
  mme::RandomObjectSpec spec;
  spec.damping_max_nspm = 0.05;
  const mme::Model truth = mme::makeRandomObject(spec);
  mme::Trajectory data = mme::simulateTrajectory(truth, 80, truth.frame_rate_hz);
  mme::addGaussianNoise(&data, 1e-4, 41);
  const mme::ParameterSpace space(truth, data);
  std::vector<double> start = space.toSearch(mme::getValues(truth, mme::freeParameters(truth)));
  for (size_t k = 0; k < start.size(); ++k) start[k] = space.reflect(k, start[k] + (k % 2 ? 0.02 : -0.02));
  mme::OutputErrorOptions o;
  o.estimate_std = false;
  o.first_stage_function_tolerance = 1e-14;
  const mme::OutputErrorResult exact_waypoint = mme::estimateOutputError(truth, data, space, start, o);
  o.first_stage_function_tolerance = 1e-3;
  const mme::OutputErrorResult waypoint = mme::estimateOutputError(truth, data, space, start, o);
  ASSERT_TRUE(exact_waypoint.ran && waypoint.ran);
  EXPECT_TRUE(waypoint.converged) << waypoint.termination;
  EXPECT_LT(maxRelativeError(waypoint.values, exact_waypoint.values), 1e-6);
  EXPECT_NEAR(waypoint.observation_cost_m2, exact_waypoint.observation_cost_m2,
              1e-9 * exact_waypoint.observation_cost_m2);
  EXPECT_LT(2 * waypoint.iterations, exact_waypoint.iterations)
      << waypoint.iterations << " against " << exact_waypoint.iterations;
  o.first_stage_function_tolerance = 0.0;
  EXPECT_FALSE(mme::estimateOutputError(truth, data, space, start, o).ran);  // refused by name
}

// A model the sensitivities do not cover (muscles) is differentiated by finite differences,
// and the result says why.
TEST(OutputError, MusclesFallBackToFiniteDifferencesAndSaySo) {
  mme::Model m = mme::test::muscleObject();
  m.bond_types[0].param(mme::kStiffness).free = true;
  const mme::Trajectory data = mme::simulateTrajectory(m, 21, m.frame_rate_hz);
  const mme::ParameterSpace space(m, data);
  mme::OutputErrorOptions o;
  o.max_iterations = 2;
  const mme::OutputErrorResult r =
      mme::estimateOutputError(m, data, space, space.toSearch(mme::getValues(m, mme::freeParameters(m))), o);
  ASSERT_TRUE(r.ran) << r.reason;
  EXPECT_EQ(r.jacobian, mme::OutputErrorJacobian::kFiniteDifferences);
  EXPECT_EQ(r.exact_jacobian_unsupported.rfind("muscles", 0), 0u) << r.exact_jacobian_unsupported;
}

}  // namespace

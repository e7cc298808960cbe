// The online estimator's engine: an update runs the generations its budget allows, the
// refinement runs beside the generations and is handed over (and is never waited for, not even
// when the model changes), and the estimate on a window gets as good as the offline
// identification of the same window.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <future>
#include <memory>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/core/stiffness.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/online/online_estimator.h"
#include "motion_model_estimation/scenes/scenes.h"
#include "test_helpers.h"

namespace {

using mme::test::maxRelativeError;

/// Feeds frames [first, first + count) of `data` to the estimator.
void feed(mme::OnlineEstimator* estimator, const mme::Trajectory& data, int first, int count) {
  const int n = data.numMarkers();
  for (int t = first; t < first + count; ++t) {
    std::vector<Eigen::Vector3d> x(data.positions_m.begin() + t * n, data.positions_m.begin() + (t + 1) * n);
    ASSERT_EQ(estimator->addFrame(data.times_s[t], x, {}), "");
  }
}

struct Fixture {
  mme::Model truth = mme::test::smallObject();
  mme::Model search = mme::test::withoutValues(truth);
  mme::Trajectory data = mme::simulateTrajectory(truth, 200, 100.0);
  std::vector<double> true_values = mme::getValues(truth, mme::freeParameters(truth));
};

// A budget shorter than one generation: every update runs exactly one generation, whatever
// generations_per_update says (the node's worker is never held longer).
TEST(OnlineEstimator, AnUpdateRunsOnlyTheGenerationsItsBudgetAllows) {
  Fixture f;
  mme::OnlineEstimatorOptions options;
  options.window_frames = 60;
  options.generations_per_update = 5;
  options.update_budget_s = 1e-9;
  options.es.population = 20;
  options.es.offspring = 20;
  mme::OnlineEstimator estimator(f.search, options);
  feed(&estimator, f.data, 0, 60);
  for (int u = 1; u <= 4; ++u) {
    ASSERT_TRUE(estimator.update());
    EXPECT_EQ(estimator.estimate().generation, static_cast<uint32_t>(u));
  }
  options.update_budget_s = 10.0;
  mme::OnlineEstimator roomy(f.search, options);
  feed(&roomy, f.data, 0, 60);
  ASSERT_TRUE(roomy.update());
  EXPECT_EQ(roomy.estimate().generation, 5u);
}

// The refinement starts once the preset's schedule says (generation 5), runs on its own thread,
// and its answer reaches the estimate at a later update; the sliding window then finds the truth.
TEST(OnlineEstimator, TheRefinementRunsBesideTheGenerationsAndIsHandedOver) {
  Fixture f;
  mme::OnlineEstimatorOptions options;
  options.window_frames = 60;
  options.es.population = 30;
  options.es.offspring = 30;
  mme::OnlineEstimator estimator(f.search, options);
  feed(&estimator, f.data, 0, 60);
  ASSERT_TRUE(estimator.update());  // generations 1-5: the refinement starts after them
  EXPECT_EQ(estimator.estimate().refinements, 0u);
  estimator.waitForRefinement();
  for (int t = 60; t < 120; t += 10) {
    feed(&estimator, f.data, t, 10);
    ASSERT_TRUE(estimator.update());
    estimator.waitForRefinement();
  }
  const mme::Estimate e = estimator.estimate();
  EXPECT_GE(e.refinements, 2u);
  // At the answer a further refinement finds nothing to improve ("no_progress").
  EXPECT_TRUE(e.last_refine_status == mme::RefineStatus::kConverged ||
              e.last_refine_status == mme::RefineStatus::kNoProgress)
      << mme::refineStatusName(e.last_refine_status);
  EXPECT_LT(maxRelativeError(e.values, f.true_values), 1e-6) << e.global_cost;
}

/// Lets a background job held on purpose go, once.
struct Release {
  std::promise<void> promise;
  std::shared_future<void> future = promise.get_future().share();
  std::atomic<bool> done{false};
  void now() {
    if (!done.exchange(true)) promise.set_value();
  }
};

// A refinement beside the generations that does not end (held on purpose until the test lets it
// go, as a long fit or a covariance that cannot be cancelled mid-way would be) never holds the
// worker: updates go on, and a new model (replaceModel) or reset() cancels it and leaves it to end
// on its own, its answer never handed over. Each update() runs on a thread of its own so that a
// worker that waited would show as a failure rather than hang the test: the 60-s wait only
// catches that deadlock (a passing run never comes near it).
TEST(OnlineEstimator, TheWorkerNeverWaitsForABackgroundRefinement) {
  Fixture f;
  mme::OnlineEstimatorOptions options;
  options.window_frames = 60;
  options.es.population = 20;
  options.es.offspring = 20;
  auto release = std::make_shared<Release>();
  auto started = std::make_shared<std::atomic<int>>(0);
  options.on_background_thread_start = [release, started] {
    ++*started;
    release->future.wait();
  };
  mme::OnlineEstimator estimator(f.search, options);
  // Destroyed before the estimator, whose destructor joins the held threads.
  const std::unique_ptr<Release, void (*)(Release*)> release_first(release.get(), [](Release* r) { r->now(); });
  auto update = [&]() {
    std::future<bool> result = std::async(std::launch::async, [&] { return estimator.update(); });
    if (result.wait_for(std::chrono::seconds(60)) == std::future_status::ready) return result.get();
    ADD_FAILURE() << "update() waited for the background refinement";
    release->now();
    return result.get();
  };
  feed(&estimator, f.data, 0, 60);
  for (int u = 0; u < 50 && *started == 0; ++u) ASSERT_TRUE(update());
  ASSERT_EQ(*started, 1) << "no refinement started";
  const uint32_t generation = estimator.estimate().generation;
  for (int u = 0; u < 5; ++u) {  // the refinement is held: the generations go on
    feed(&estimator, f.data, 60 + u, 1);
    ASSERT_TRUE(update());
  }
  EXPECT_GT(estimator.estimate().generation, generation);
  estimator.replaceModel(f.search);  // the held refinement belongs to the old model
  ASSERT_TRUE(update());
  for (int u = 0; u < 50 && *started < 2; ++u) ASSERT_TRUE(update());
  ASSERT_EQ(*started, 2) << "no refinement started on the new model";
  estimator.reset(false);  // a second held one, now for a population that is dropped
  ASSERT_TRUE(update());
  ASSERT_TRUE(update());
  EXPECT_EQ(estimator.estimate().refinements, 0u);  // neither answer was handed over
  release->now();
}

// On a window that stops sliding, the online estimate's cost comes within 2x of what identify
// reaches on the same frames (the target for the live node).
TEST(OnlineEstimator, OnAStillWindowTheEstimateMatchesTheOfflineIdentification) {
  Fixture f;
  mme::addGaussianNoise(&f.data, 1e-4, 11);
  mme::OnlineEstimatorOptions options;
  options.window_frames = 100;
  mme::OnlineEstimator estimator(f.search, options);
  feed(&estimator, f.data, 0, 100);
  for (int u = 0; u < 12; ++u) {
    ASSERT_TRUE(estimator.update());
    estimator.waitForRefinement();
  }
  const mme::Trajectory window = estimator.window();
  mme::IdentifyOptions offline = mme::identifyOptionsFor(mme::Preset::kDefault);
  offline.estimate_std = false;
  const mme::IdentifyResult r = mme::identifyModel(f.search, window, offline);
  const double online = estimator.estimate().global_cost;
  EXPECT_LE(online, 2.0 * r.global_cost) << "online " << online << ", identify " << r.global_cost;
  EXPECT_GE(online, 0.5 * r.global_cost);
}

// A stiff scene at one substep per frame (paper_object at omega h = 2.5, data from 20 substeps
// with 0.1 mm noise): the output-error fits beside the generations blow up over their segments.
// None is published: the estimate stays the one-step answer and counts the fits not adopted.
TEST(OnlineEstimator, AnOutputErrorFitThatPredictsWorseIsNotPublished) {
  const mme::test::StiffAtOneSubstep stiff;
  const mme::Trajectory& data = stiff.data;
  const mme::Model& search = stiff.search;
  mme::OnlineEstimatorOptions options;
  options.window_frames = 60;
  options.cost = mme::CostChoice::kOutputError;
  options.es.threads = 1;
  options.update_budget_s = 100.0;  // every update its 5 generations: the refinements on schedule
  mme::OnlineEstimator estimator(search, options);
  feed(&estimator, data, 0, 60);
  for (int u = 0; u < 4; ++u) {
    ASSERT_TRUE(estimator.update());
    estimator.waitForRefinement();
  }
  const mme::Estimate e = estimator.estimate();
  EXPECT_GE(e.refinements, 1u);
  EXPECT_GE(e.output_error_rejections, 1u);
  EXPECT_EQ(e.estimator, mme::Estimator::kShortTerm);
}

}  // namespace

namespace {

// ~select_structure: the particles alone are refused unless the estimator waits for a structure;
// then it collects frames without identifying, and a model with free parameters starts it on
// the same window.
TEST(OnlineEstimator, WaitsForAStructureWithTheParticlesAlone) {
  Fixture f;
  const mme::Model particles = mme::test::particlesOnly(f.truth);
  mme::OnlineEstimatorOptions options;
  options.window_frames = 60;
  EXPECT_THROW(mme::OnlineEstimator refused(particles, options), mme::InputError);
  options.wait_for_structure = true;
  mme::OnlineEstimator estimator(particles, options);
  feed(&estimator, f.data, 0, 60);
  EXPECT_FALSE(estimator.update());
  EXPECT_FALSE(estimator.estimate().valid);
  estimator.replaceModel(f.search);
  EXPECT_EQ(estimator.window().numFrames(), 60);  // same particles: the window stays
  ASSERT_TRUE(estimator.update());
  EXPECT_TRUE(estimator.estimate().valid);
}

}  // namespace

namespace {

/// smallObject() with an anchor: a fixed particle 5 m off, a point of the model without a marker
/// (the sensor muscles' anchors are such points), hidden in every frame of `data`.
struct AnchoredFixture : Fixture {
  AnchoredFixture() {
    anchored = truth;
    mme::Particle anchor;
    anchor.name = "anchor";
    anchor.fixed = true;
    anchor.position_m = Eigen::Vector3d(5.0, 5.0, 5.0);
    anchored.particles.push_back(anchor);
    motion = mme::simulateTrajectory(anchored, 60, 100.0);
    window = motion;
    for (int t = 0; t < window.numFrames(); ++t) hide(&window, t, 5);
  }
  static void hide(mme::Trajectory* w, int t, int i) {
    w->occluded[t * w->numMarkers() + i] = 1;
    w->position(t, i).setZero();
  }
  mme::Model anchored;
  mme::Trajectory motion, window;
};

// The rollout behind rviz's prediction and reconstruction and the node's stability check starts
// where markers are hidden: an anchor where the model holds it, a hidden marker placed by its
// neighbours. (It returned nothing whenever a particle was hidden in the window's first frames:
// with anchors, always.)
TEST(OnlineEstimator, TheRolloutStartsWithAnchorsAndHiddenMarkers) {
  AnchoredFixture f;
  mme::Trajectory r = mme::OnlineEstimator::rollout(f.anchored, f.window, 30);
  ASSERT_EQ(r.numFrames(), 30);
  for (int t = 0; t < 30; ++t) {
    for (int i = 0; i < 5; ++i)
      EXPECT_LT((r.position(t, i) - f.motion.position(t + 1, i)).norm(), 1e-9) << t << " " << i;
    EXPECT_EQ(r.position(t, 5), f.anchored.particles[5].position_m);
  }
  // Particle 4 hidden in the first two frames: placed there by its neighbours' rigid motion (the
  // body is not rigid: near, not exact).
  AnchoredFixture::hide(&f.window, 0, 4);
  AnchoredFixture::hide(&f.window, 1, 4);
  r = mme::OnlineEstimator::rollout(f.anchored, f.window, 30);
  ASSERT_EQ(r.numFrames(), 30);
  EXPECT_LT((r.position(0, 4) - f.motion.position(1, 4)).norm(), 5e-3);
  EXPECT_LT((r.position(0, 0) - f.motion.position(1, 0)).norm(), 1e-12);
  // Nothing to place it from (every free particle hidden at the start): no rollout.
  for (int i = 0; i < 5; ++i) AnchoredFixture::hide(&f.window, 1, i);
  EXPECT_EQ(mme::OnlineEstimator::rollout(f.anchored, f.window, 30).numFrames(), 0);
}

// The node's stability check judges the free particles: an anchor 5 m off a 0.35 m body, far
// outside 10x the body's extent, does not make a bounded model "UNSTABLE".
TEST(OnlineEstimator, AnAnchorFarOffTheBodyIsNotAnInstability) {
  AnchoredFixture f;
  mme::OnlineEstimatorOptions options;
  options.window_frames = 60;
  mme::OnlineEstimator estimator(mme::test::withoutValues(f.anchored), options);
  for (int t = 0; t < 60; ++t) {
    std::vector<Eigen::Vector3d> x(f.window.positions_m.begin() + t * 6,
                                   f.window.positions_m.begin() + (t + 1) * 6);
    ASSERT_EQ(estimator.addFrame(f.window.times_s[t], x, {0, 0, 0, 0, 0, 1}), "");
  }
  for (int u = 0; u < 12; ++u) {
    ASSERT_TRUE(estimator.update());
    estimator.waitForRefinement();
  }
  const mme::Estimate e = estimator.estimate();
  EXPECT_LT(mme::test::maxRelativeError(e.values, f.true_values), 1e-3);  // the true model
  EXPECT_TRUE(e.stable);
}

}  // namespace

namespace {

/// Frame t of `w` as addFrame takes it.
std::vector<Eigen::Vector3d> frameOf(const mme::Trajectory& w, int t) {
  const int n = w.numMarkers();
  return std::vector<Eigen::Vector3d>(w.positions_m.begin() + t * n, w.positions_m.begin() + (t + 1) * n);
}

// An input without a marker for a fixed particle (the anchor: a point of the model only) is not
// an occlusion, so ~stats does not count it as one; a free particle without a marker is a hidden
// marker, and a flagged occlusion of any particle is one.
TEST(OnlineEstimator, AFixedParticleWithoutAMarkerIsNotCountedAsOccluded) {
  AnchoredFixture f;
  mme::OnlineEstimator estimator(mme::test::withoutValues(f.anchored), mme::OnlineEstimatorOptions());
  const uint8_t none = mme::OnlineEstimator::kNoMarker;
  for (int t = 0; t < 10; ++t)
    ASSERT_EQ(estimator.addFrame(f.motion.times_s[t], frameOf(f.motion, t), {0, 0, 0, 0, 0, none}), "");
  mme::InputCounters c = estimator.counters();
  EXPECT_EQ(c.occluded_samples, 0u);
  EXPECT_EQ(c.model_only_samples, 10u);
  EXPECT_TRUE(estimator.window().isOccluded(9, 5));  // masked all the same
  ASSERT_EQ(estimator.addFrame(f.motion.times_s[10], frameOf(f.motion, 10), {none, 0, 0, 0, 0, 1}), "");
  c = estimator.counters();
  EXPECT_EQ(c.occluded_samples, 2u);  // the free particle without a marker, the flagged anchor
  EXPECT_EQ(c.model_only_samples, 10u);
}

// estimate_values false: an identified model is shown as it is. Each update with a new frame
// publishes the model's own values (judged on the window: cost, stability), none is searched;
// without a new frame there is nothing to publish. A model without values is refused.
TEST(OnlineEstimator, WithEstimateValuesOffTheModelsValuesAreShownUnchanged) {
  AnchoredFixture f;
  mme::OnlineEstimatorOptions options;
  options.window_frames = 30;
  options.min_frames = 10;
  options.estimate_values = false;
  mme::OnlineEstimator estimator(f.anchored, options);
  const std::vector<double> values = mme::getValues(f.anchored, mme::freeParameters(f.anchored));
  const std::vector<uint8_t> mask = {0, 0, 0, 0, 0, mme::OnlineEstimator::kNoMarker};
  for (int t = 0; t < 9; ++t) ASSERT_EQ(estimator.addFrame(f.window.times_s[t], frameOf(f.window, t), mask), "");
  EXPECT_FALSE(estimator.update());  // fewer than min_frames
  for (int t = 9; t < 40; ++t) {
    ASSERT_EQ(estimator.addFrame(f.window.times_s[t], frameOf(f.window, t), mask), "");
    ASSERT_TRUE(estimator.update()) << t;
    EXPECT_FALSE(estimator.update()) << t;  // the same frames again
  }
  const mme::Estimate e = estimator.estimate();
  ASSERT_TRUE(e.valid);
  EXPECT_EQ(e.generation, 31u);  // one held estimate per new frame
  EXPECT_EQ(e.values, values);   // exactly the file's values
  EXPECT_EQ(e.window_frames, 30u);
  EXPECT_LT(e.global_cost, 1e-12);  // the true model on its own noise-free motion
  EXPECT_TRUE(e.stable);
  const mme::Model shown = estimator.currentModel();
  EXPECT_EQ(mme::getValues(shown, mme::freeParameters(shown)), values);

  try {
    mme::OnlineEstimator refused(f.search, options);
    FAIL() << "a model without values was accepted";
  } catch (const mme::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("has no value"), std::string::npos) << error.what();
  }
}

}  // namespace
